"""docs/plasticity.md's 1 m rods (the seed's own case, elastic and plastic, and the MVM form of
b2 against full FE plastic) are their stamped records (issue 51 item 4): the page's tables
are remade here from docs/seed_plastic/one_metre.json and one_metre_mvm.json
(benchmarks/seed_plastic.py) and must stand on the page as they are. Reads JSON, TOML and
Markdown only; no run.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGE = DOCS / "plasticity.md"
RECORDS = DOCS / "seed_plastic"


def _load(name: str) -> dict:
    return json.loads((RECORDS / name).read_text())


def _v0(record: dict) -> float:
    """The striker's impact speed [m/s] from the record's scenario (b1's placement)."""
    with open(ROOT / record["scenario"], "rb") as f:
        sc = tomllib.load(f)
    b1 = next(b for b in sc["bodies"] if b["name"] == "b1")
    return float(np.linalg.norm(b1["placement"]["velocity_mps"]))


def _rows(record: dict) -> dict:
    return {r["run"]: r for r in record["rows"]}


def _duration_us(row: dict) -> float:
    iv = row["contact_intervals_s"]
    return 1e6 * (iv[-1][1] - iv[0][0])


def _pct(new: float, ref: float) -> str:
    return f"{100 * (new / ref - 1):+.1f} %"


def _e1(x: float) -> str:
    """x to one significant digit as the page writes it: 2e-4."""
    m, e = f"{x:.0e}".split("e")
    return f"{m}e{int(e)}"


def _work_uJ(row: dict, body: str) -> float:
    return 1e6 * row["plastic"][body]["plastic_work_J"]


def one_metre_table_rows(record: dict, v0: float) -> list[str]:
    """The page's table 'the seed's own case, 1 m rods' (elastic | plastic | change), row by
    row, from one_metre.json; b2's velocity J / m2 = e v0 + v1 and the impact energy
    m1 v0^2 / 2 with m1 = J / (v0 - v1), both from the row's momentum balance."""
    rows = _rows(record)
    e, p = rows["elastic"], rows["plastic"]
    th = record["theory"]
    m1 = e["impulse_Ns"] / (v0 - e["striker_velocity_after_mps"])
    m_star = e["impulse_Ns"] / ((1 + e["restitution"]) * v0)
    e_theory = th["impulse_Ns"] / (m_star * v0) - 1
    energy_mJ = 1e3 * 0.5 * m1 * v0**2
    v2 = {k: r["restitution"] * v0 + r["striker_velocity_after_mps"] for k, r in rows.items()}
    wp = [_work_uJ(p, "b1"), _work_uJ(p, "b2")]
    wp_frac = 1e-3 * sum(wp) / energy_mJ
    closes = abs(p["energy_rel_error"] + wp_frac)
    dur_e, dur_p = _duration_us(e), _duration_us(p)
    pl = p["plastic"]
    return [
        (
            f"| peak contact force | {e['peak_force_N']:.1f} N | {p['peak_force_N']:.1f} N | "
            f"{_pct(p['peak_force_N'], e['peak_force_N'])} |"
        ),
        f"| contact duration | {dur_e:.1f} us | {dur_p:.1f} us | {_pct(dur_p, dur_e)} |",
        (
            f"| impulse | {1e3 * e['impulse_Ns']:.1f} mN s | {1e3 * p['impulse_Ns']:.1f} mN s | "
            f"{_pct(p['impulse_Ns'], e['impulse_Ns'])} |"
        ),
        f"| force NCC against the elastic run | 1 | {p['vs_elastic']['ncc_force']:.4f} | |",
        (
            f"| force NCC against the 1D theory (elastic; {th['peak_force_N']:.1f} N, "
            f"{1e6 * th['contact_s']:.0f} us) | {e['vs_theory']['ncc_force']:.5f} | "
            f"{p['vs_theory']['ncc_force']:.4f} | |"
        ),
        (
            f"| b2 free-end velocity NCC against the elastic run | 1 | "
            f"{p['vs_elastic']['ncc_b2_free_end']:.4f} | |"
        ),
        (
            f"| striker velocity after contact (v0 - J / m1) | "
            f"{e['striker_velocity_after_mps']:.4f} m/s | {p['striker_velocity_after_mps']:.4f} m/s | |"
        ),
        (
            f"| b2 velocity after contact (J / m2) | {v2['elastic']:.3f} m/s | "
            f"{v2['plastic']:.3f} m/s | {_pct(v2['plastic'], v2['elastic'])} |"
        ),
        (
            f"| restitution J / (m* v0) - 1 | {e['restitution']:.3f} (theory {e_theory:.3f}) | "
            f"{p['restitution']:.3f} | |"
        ),
        (
            f"| plastic work (b1 + b2) | 0 | {wp[0]:.0f} + {wp[1]:.0f} uJ = {100 * wp_frac:.1f} % "
            f"of the {energy_mJ:.1f} mJ impact energy | |"
        ),
        (
            f"| total energy at the end, against E(0) | {100 * e['energy_rel_error']:.2f} % | "
            f"{100 * p['energy_rel_error']:.2f} % (the plastic work, to {_e1(closes)} of E(0)) | |"
        ),
        (
            f"| permanent indentation b1 / b2 | 0 | "
            f"{1e6 * pl['b1']['permanent_indentation_m']:.1f} / "
            f"{1e6 * pl['b2']['permanent_indentation_m']:.1f} um | |"
        ),
        (
            f"| peak equivalent plastic strain b1 / b2 (cells yielded) | 0 | "
            f"{pl['b1']['peak_equivalent_plastic_strain']:.3f} ({pl['b1']['plastic_cells']}) / "
            f"{pl['b2']['peak_equivalent_plastic_strain']:.3f} ({pl['b2']['plastic_cells']}) | |"
        ),
        f"b1 {e['dof']['b1']:,} DOF, b2 {e['dof']['b2']:,}):",
        (
            f"Steps: {e['n_steps']} elastic, {p['n_steps']} plastic, {_cuts(e, p)}; the plastic run "
            f"took {p['cpu_time_s'] / e['cpu_time_s']:.1f} times the elastic one's CPU "
            f"({p['cpu_time_s']:.0f} s against {e['cpu_time_s']:.0f} s,"
        ),
        (
            f"rebound with e = {e['restitution']:.2f}: they leave with {100 * _vibration(e, v0):.1f} % "
            "of the impact energy in vibration."
        ),
    ]


def _cuts(*rows: dict) -> str:
    """'none unconverged, no cuts' where no run had either (else the counts)."""
    if any(r["steps_not_converged"] or r["step_cuts"] for r in rows):
        return ", ".join(f"{r['steps_not_converged']} / {r['step_cuts']}" for r in rows)
    return "none unconverged, no cuts"


def _vibration(row: dict, v0: float) -> float:
    """The share of the impact energy left in vibration: 1 - (m1 v1^2 + m2 v2^2) / (m1 v0^2),
    m1 = J / (v0 - v1), m2 = J / v2 (the rods' rigid-body motion after the contact)."""
    j, v1 = row["impulse_Ns"], row["striker_velocity_after_mps"]
    v2 = row["restitution"] * v0 + v1
    m1, m2 = j / (v0 - v1), j / v2
    return 1 - (m1 * v1**2 + m2 * v2**2) / (m1 * v0**2)


def _mvm_row(name: str, r: dict, fe: dict, verdict: str) -> str:
    b2, fe_b2 = r["plastic"]["b2"], fe["plastic"]["b2"]
    vs = r["vs_plastic"]
    dof = r["dof"]["b2"]  # the reduced b2 with its 6 frame coordinates
    work, dent = _work_uJ(r, "b2"), 1e6 * b2["permanent_indentation_m"]
    out = b2["cells_yield_outside_retained"]
    outside = f"{out} (in {b2['steps_yield_outside_retained']} steps)" if out else "0"
    return (
        f"| {name} | {dof:,} | {vs['ncc_force']:.5f} | {100 * vs['peak_err']:+.2f} % | "
        f"{100 * vs['impulse_err']:+.2f} % | {work:,.0f} uJ ({_pct(work, _work_uJ(fe, 'b2'))}) | "
        f"{dent:.3f} um ({_pct(dent, 1e6 * fe_b2['permanent_indentation_m'])}) | "
        f"{b2['plastic_cells']} | {outside} | {verdict} |"
    )


def mvm_table_rows(record: dict, mvm: dict) -> list[str]:
    """The page's table 'MVM b2 on the 1 m rods' (the full-FE row and the benchmark's MVM
    rows; the whole-cell column is left out: the record does not hold it; the 5-5 row is the
    select study's, one_metre_select_ncc.csv) and the sentences after it that read the runs
    (7-5's plastic strain and b1's work, the CPU), from one_metre.json and one_metre_mvm.json."""
    fe = _rows(record)["plastic"]
    runs = _rows(mvm)
    b2 = fe["plastic"]["b2"]
    rows = [
        (
            f"| full FE | {fe['dof']['b2']:,} | all | 1 | {fe['peak_force_N']:.1f} N | "
            f"{1e3 * fe['impulse_Ns']:.2f} mN s | {_work_uJ(fe, 'b2'):,.0f} uJ | "
            f"{1e6 * b2['permanent_indentation_m']:.3f} um | {b2['plastic_cells']} | - | |"
        )
    ]
    names = {"mvm 5-7:37": ("5-7", "invalid (plastic guard)"), "mvm 7-5:37": ("**7-5**", None)}
    for run, (name, verdict) in names.items():
        r = runs[run]
        rows.append(_mvm_row(name, r, fe, verdict or "**holds the zone**"))
    r75, r57 = runs["mvm 7-5:37"], runs["mvm 5-7:37"]
    alpha = [r["plastic"]["b2"]["peak_equivalent_plastic_strain"] for r in (r75, fe)]
    b1 = _pct(_work_uJ(r75, "b1"), _work_uJ(fe, "b1"))
    cpu = [r["cpu_time_s"] for r in (r75, fe, r57)]
    rows += [
        f"dent and its peak plastic strain ({alpha[0]:.4f} against {alpha[1]:.4f}) are full FE's",
        f"b1's plastic work (full FE in both) moves by {b1[:-2]} %.",
        (
            f"the 7-5 run took {cpu[0]:.0f} s of CPU against the full-FE plastic run's {cpu[1]:.0f} s "
            f"({cpu[0] / cpu[1]:.2f} times; 5-7: {cpu[2]:.0f} s, {cpu[2] / cpu[1]:.2f} times;"
        ),
    ]
    return rows


def _missing(rows: list[str], page: str) -> list[str]:
    """The rows not on the page; an MVM row is matched with its whole-cell column cut out, a
    sentence across the page's line breaks."""
    lines = page.splitlines()
    cut = [" | ".join(x for k, x in enumerate(line.split(" | ")) if k != 2) for line in lines]
    text = " ".join(page.split())
    return [r for r in rows if not any(r in line for line in (*lines, *cut, text))]


def test_one_metre_table_is_its_record():
    record = _load("one_metre.json")
    missing = _missing(one_metre_table_rows(record, _v0(record)), PAGE.read_text())
    assert not missing, f"docs/plasticity.md lacks one_metre.json's rows: {missing}"


def test_one_metre_mvm_table_is_its_record():
    rows = mvm_table_rows(_load("one_metre.json"), _load("one_metre_mvm.json"))
    missing = _missing(rows, PAGE.read_text())
    assert not missing, f"docs/plasticity.md lacks one_metre_mvm.json's rows: {missing}"


def test_mvm_record_reuses_the_stored_full_fe_runs():
    """one_metre_mvm.json's elastic and plastic rows are one_metre.json's (--reuse): the
    same stamps, so its MVM rows were compared with the stored full-FE run."""
    fe, mvm = _rows(_load("one_metre.json")), _rows(_load("one_metre_mvm.json"))
    for run in ("elastic", "plastic"):
        assert mvm[run]["provenance"] == fe[run]["provenance"]
        assert mvm[run]["peak_force_N"] == fe[run]["peak_force_N"]


@pytest.mark.parametrize("field", ["peak_force_N", "restitution"])
def test_table_rows_read_every_column(field):
    """Another number in the record is another row: the rows are made from the record."""
    record = _load("one_metre.json")
    rows = one_metre_table_rows(record, _v0(record))
    moved = json.loads(json.dumps(record))
    _rows(moved)["plastic"][field] *= 1.01
    assert one_metre_table_rows(moved, _v0(record)) != rows
