"""docs/slider_crank.md and docs/interface_basis.md say what their stamped records say (issue 51
item 4): the slider-crank's table, run checks and CPU times are remade here from
docs/slider_crank/numbers.json, the interface basis's table from docs/interface_basis/front.csv
(stamped by front.json beside it); a record remade with other numbers fails this test until the
page says what the record says. Reads JSON, CSV and Markdown only; no run.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
SLIDER = DOCS / "slider_crank"
FRONT = DOCS / "interface_basis"
REF = "full_4mm_h100us"
#: the halved element size's and the halved step's runs
CONVERGENCE = ("full_8mm_h100us", "full_4mm_h50us")
#: the side-by-side cost of the slider_crank showcase (stamped, quiet machine)
BENCH = ROOT / "benchmarks" / "results" / "showcases_2026-11-29_quiet.json"


def _missing(rows: list[str], page: Path) -> list[str]:
    text = page.read_text()
    return [r for r in rows if r not in text]


def ncc_text(x: float) -> str:
    """An NCC to two significant digits of 1 - NCC (0.99937, 0.999983, 0.99999936)."""
    gap = 1.0 - x
    if gap <= 0.0:
        return f"{x:.4f}"
    decimals = max(4, 1 - math.floor(math.log10(gap)))
    return f"{x:.{decimals}f}"


def sig2(x: float) -> str:
    """x to two significant digits, fixed point (0.014, 0.0025)."""
    decimals = max(0, 1 - math.floor(math.log10(abs(x))))
    return f"{x:.{decimals}f}"


#: docs/slider_crank.md's names of figure.py's cases
SLIDER_NAMES = {
    "full_4mm_h100us": "full FE, 4 mm (10,524 DOF), h = 100 us",
    "full_8mm_h100us": "full FE, 8 mm (4,860 DOF), h = 100 us",
    "full_4mm_h50us": "full FE, 4 mm, h = 50 us",
    "mvm_4mm_h100us": "MVM, 4 mm: end faces + 8 modes (230 coordinates), h = 100 us",
}


def slider_table_rows(rec: dict) -> list[str]:
    """The results table of docs/slider_crank.md from numbers.json: peaks to 1 um, NCC to two
    digits of 1 - NCC, the largest difference to two digits."""
    rows = []
    for case, name in SLIDER_NAMES.items():
        hi, lo = rec["peaks_mm"][case]
        if case == REF:
            rows.append(f"| {name} | {hi:.3f} | {lo:.3f} | — | — |")
            continue
        ncc = ncc_text(rec["ncc"][f"{case} vs {REF}"])
        diff = sig2(rec["max_difference_mm"][f"{case} - {REF}"])
        rows.append(f"| {name} | {hi:.3f} | {lo:.3f} | {ncc} | {diff} |")
    hi, lo = rec["peaks_mm"]["theory_3_modes"]
    ncc = ncc_text(rec["ncc"][f"{REF} vs theory_3_modes"])
    rows.append(
        f"| pinned-pinned beam, 3 modes (theory) | {hi:.3f} | {lo:.3f} | {ncc} (against the "
        "full FE) | — |"
    )
    return rows


def slider_run_lines(rec: dict, bench: dict) -> list[str]:
    """The page's words on the runs' checks, convergence, reference beam and cost, from
    numbers.json (summary entries under their current keys, CPU times) and, for the side-by-side
    cost, the stamped showcase benchmark's slider_crank row (BENCH)."""
    s, cpu, peaks = rec["summary"], rec["cpu_s"], rec["peaks_mm"]
    floor = sum(v["steps_on_roundoff_floor"] for v in s.values())
    cuts = sum(v["step_cuts"] for v in s.values())
    drift = max(v["max_joint_drift"] for v in s.values())
    span = peaks[REF][0] - peaks[REF][1]
    mesh, step = (rec["max_difference_mm"][f"{c} - {REF}"] for c in CONVERGENCE)
    beam = [100 * (r / t - 1) for r, t in zip(peaks[REF], peaks["theory_3_modes"])]
    row = next(r for r in bench["rows"] if r["scenario"] == "slider_crank")
    mvm = rec["max_difference_mm"][f"mvm_4mm_h100us - {REF}"]
    return [
        (
            f"steps on the round-off floor (`steps_on_roundoff_floor`): {floor}; step cuts: {cuts}; "
            f"largest joint drift (`max_joint_drift`): {drift:.1e} m."
        ),
        (
            f"the step by at most {sig2(step)} mm: {100 * mesh / span:.1f} % and "
            f"{100 * step / span:.1f} % of its {span:.1f} mm range."
        ),
        (
            f"The full FE's peaks are {beam[0]:.1f} % (+) and {beam[1]:.1f} % (-) above the beam's, "
            f"NCC {rec['ncc'][f'{REF} vs theory_3_modes']:.4f} over the revolution."
        ),
        (
            f"NCC {ncc_text(rec['ncc'][f'mvm_4mm_h100us vs {REF}'])}, peaks within "
            f"{_peak_spread(rec):.2f} %, largest difference {sig2(1e3 * mvm)} um."
        ),
        (
            f"full FE {row['full']['sim_cpu_s']:.1f} s CPU, MVM {row['reduced']['sim_cpu_s']:.1f} s, "
            f"MVM {row['cpu_ratio']:.1f} times cheaper."
        ),
        (
            f"full FE 4 mm {cpu['full_4mm_h100us']:,.0f} s, 8 mm {cpu['full_8mm_h100us']:,.0f} s, "
            f"4 mm at 50 us {cpu['full_4mm_h50us']:,.0f} s, MVM {cpu['mvm_4mm_h100us']:,.0f} s."
        ),
    ]


def _peak_spread(rec: dict) -> float:
    """The MVM's larger peak difference from the full FE's, in % of that peak."""
    ref, mvm = rec["peaks_mm"][REF], rec["peaks_mm"]["mvm_4mm_h100us"]
    return max(100 * abs(m - r) / abs(r) for m, r in zip(mvm, ref))


def test_slider_crank_page_is_its_record():
    rec = json.loads((SLIDER / "numbers.json").read_text())
    lines = slider_run_lines(rec, json.loads(BENCH.read_text()))
    missing = _missing(slider_table_rows(rec) + lines, DOCS / "slider_crank.md")
    assert not missing, f"docs/slider_crank.md lacks what numbers.json says: {missing}"


def test_slider_crank_record_is_stamped_per_run_with_current_keys():
    """Every case of numbers.json has its run's stamp and its summary under the current names
    (results.summary_keys: no renamed key)."""
    from flexmvm.results.summary_keys import RENAMED_KEYS

    rec = json.loads((SLIDER / "numbers.json").read_text())
    assert set(rec["provenance"]) == set(SLIDER_NAMES)
    assert all({"key", "code", "libraries"} <= set(p) for p in rec["provenance"].values())
    assert not [k for s in rec["summary"].values() for k in s if k in RENAMED_KEYS]


def test_slider_rows_read_every_number():
    rec = json.loads((SLIDER / "numbers.json").read_text())
    rows = slider_table_rows(rec)
    rec["peaks_mm"]["mvm_4mm_h100us"][0] += 0.001
    assert slider_table_rows(rec) != rows
    assert ncc_text(0.9993743) == "0.99937" and ncc_text(0.99999936) == "0.99999936"
    assert sig2(0.0024833) == "0.0025" and sig2(0.0138819) == "0.014"


#: docs/interface_basis.md's table: front.csv's row name -> the page's name, in the page's order
FRONT_NAMES = {
    "p1+0": "p1 + 0",
    "p1+1": "p1 + 1",
    "p1+2": "p1 + 2",
    "p1+3": "p1 + 3",
    "p1+4": "p1 + 4",
    "p3+3": "p3 + 3",
    "p3+5": "p3 + 5",
    "p5+5": "p5 + 5",
    "p1+10": "p1 + 10",
    "p1+10f": "p1 + 10 by frequency",
    "interface:0.3:10": "radius 0.3 mm + 10",
    "interface:0.6:10": "radius 0.6 mm + 10",
    "interface:0.8:10": "radius 0.8 mm + 10",
    "p3+10": "p3 + 10",
    "p8+5": "p8 + 5",
    "p5+10f": "p5 + 10 by frequency",
    "p8+10": "p8 + 10 (shipped)",
    "p3+20": "p3 + 20",
    "p5+20f": "p5 + 20 by frequency",
    "p8+20": "p8 + 20",
    "p1+39": "p1 + 39",
    "p5+35f": "p5 + 35 by frequency",
    "p8+32": "p8 + 32",
    "part-5": "no patch, 5 modes",
    "part-10": "no patch, 10 modes",
    "part-20": "no patch, 20 modes",
    "mvm-1-1+37": "MVM 1-1 + 37 (seed)",
    "mvm-1-3+25": "MVM 1-3 + 25 (study winner)",
}


def pct(x: float, always: int | None = None) -> str:
    """A relative error in %, signed: two decimals below 10 %, one above (+1.49 %, +32.4 %);
    ``always`` decimals if given."""
    v = 100 * x
    decimals = always if always is not None else (2 if abs(v) < 10 else 1)
    return f"{v:+.{decimals}f} %"


def front_rows(rows: dict[str, dict]) -> list[str]:
    """docs/interface_basis.md's table from front.csv: force NCC to four digits, peak and
    duration errors to two decimals (one from 10 % on), impulse errors to two, the impact-end
    probe NCC to three, the free-end one to four."""
    out = []
    for name, label in FRONT_NAMES.items():
        r = {k: float(v) for k, v in rows[name].items() if k not in ("name", "model", "commit")}
        out.append(
            f"| {label} | {int(r['dof'])} | {r['ncc_force']:.4f} | {pct(r['peak_err'])} | "
            f"{pct(r['impulse_err'], 2)} | {pct(r['duration_err'])} | "
            f"{r['ncc_b2_impact_end']:.3f} | {r['ncc_b2_free_end']:.4f} |"
        )
    return out


def read_front() -> dict[str, dict]:
    with open(FRONT / "front.csv", newline="") as fh:
        return {r["name"]: r for r in csv.DictReader(fh)}


def front_lines(rows: dict[str, dict]) -> list[str]:
    """The page's words from front.csv beside its table: the goal's smallest models, the
    shipped model, the reference's check and the guard's row of the 0.3 mm patch."""
    r = {
        n: {k: float(v) for k, v in row.items() if v and k not in ("name", "model", "commit")}
        for n, row in rows.items()
    }
    p12, p13, p810 = r["p1+2"], r["p1+3"], r["p8+10"]
    return [
        (
            f"(one patch vector + the first three axial modes: NCC {p13['ncc_force']:.4f}, "
            f"peak {pct(p13['peak_err'])});"
        ),
        (
            f"3 DOF (the first two axial modes) give NCC {p12['ncc_force']:.4f} with the peak "
            f"{100 * p12['peak_err']:.1f} % high."
        ),
        (
            f"18 DOF (eight patch radii + 10 modes): NCC {p810['ncc_force']:.4f}, peak "
            f"{pct(p810['peak_err'])}, b2 impact-end and free-end velocity NCC "
            f"{p810['ncc_b2_impact_end']:.3f} and {p810['ncc_b2_free_end']:.4f}."
        ),
        f"Its force NCC ({p810['ncc_force']:.5f})",
        f"(MVM 1-3 + 25 gives force NCC {r['mvm-1-3+25']['ncc_force']:.6f} against it",
        (
            f"| seed 0.8 ms, interface radius 0.3 mm + 10 | "
            f"{100 * r['interface:0.3:10']['guard_outside_fraction']:.0f} % | | |"
        ),
    ]


def test_interface_front_table_is_its_record():
    rows = read_front()
    missing = _missing(front_rows(rows) + front_lines(rows), DOCS / "interface_basis.md")
    assert not missing, f"docs/interface_basis.md lacks what front.csv says: {missing}"


def test_front_rows_read_every_column():
    rows = read_front()
    table = front_rows(rows)
    rows["p1+2"] = rows["p1+2"] | {"duration_err": "0.5"}
    assert front_rows(rows) != table
    assert pct(0.324) == "+32.4 %" and pct(-0.0015) == "-0.15 %" and pct(0.0048, 2) == "+0.48 %"
