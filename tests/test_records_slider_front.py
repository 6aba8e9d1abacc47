"""docs/slider_crank.md and docs/interface_basis.md say what their stamped records say (issue 51
item 4): the slider-crank's table, run checks and CPU times are remade here from
docs/slider_crank/numbers.json, the interface basis's table from docs/interface_basis/front.csv
(stamped by front.json beside it); a record remade with other numbers fails this test until the
page says what the record says. Reads JSON, CSV and Markdown only; no run.
"""

from __future__ import annotations

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
