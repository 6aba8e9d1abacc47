"""docs/plasticity.md's figures from two stamped records of the seed case with yielding rods
(issue 51 item 4), as tests/test_page_figures.py does for other pages: the short plastic rods
on the finer contact mesh (docs/seed_plastic/short_rods_fine_mesh_plastic.json, from
``benchmarks/seed_plastic.py --fine-mesh``, against the default mesh's plastic run in
short_rods.json), and `flexmvm select` on the 1 m plastic rods (one_metre_select_ncc.csv and
its stamped one_metre_select_selection.json: the answer and the 1 m table's 5-5 and 7-5
columns the study measures). Each figure is remade here from its record and must stand on the
page as it is. Reads JSON, CSV and Markdown only; no run.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PLASTIC = ROOT / "docs" / "seed_plastic"
PAGE = ROOT / "docs" / "plasticity.md"
#: the command that makes the fine-mesh record (OUT/seed_plastic.json), as the page gives it
FINE_COMMAND = "python benchmarks/seed_plastic.py OUT --fine-mesh --skip-elastic --mvm ''"


def _json(path: Path) -> dict:
    return json.loads(path.read_text())


def _page() -> str:
    """The page with its line breaks and runs of blanks as one blank (a sentence may wrap)."""
    return " ".join(PAGE.read_text().replace("**", "").split())


def _missing(phrases: list[str]) -> list[str]:
    page = _page()
    return [p for p in phrases if p not in page]


def _plastic_row(record: dict) -> dict:
    (row,) = [r for r in record["rows"] if r["run"] == "plastic"]
    return row


def _duration_us(row: dict) -> float:
    iv = row["contact_intervals_s"]
    return 1e6 * (iv[-1][1] - iv[0][0])


def fine_mesh_phrases(fine: dict, coarse: dict) -> list[str]:
    """The mesh caveat's figures: the fine-mesh plastic run and, in brackets or as a change,
    the default mesh's (its plastic row); percentages to the digit the page gives."""
    f, c = _plastic_row(fine), _plastic_row(coarse)
    mesh = fine["rod_mesh"]
    pf, pc = f["plastic"], c["plastic"]

    def change(a: float, b: float, digits: int = 0) -> str:
        return f"{100 * (a / b - 1):+.{digits}f} %"

    wf = [1e6 * pf[b]["plastic_work_J"] for b in ("b1", "b2")]
    wc = [1e6 * pc[b]["plastic_work_J"] for b in ("b1", "b2")]
    af = " / ".join(f"{pf[b]['peak_equivalent_plastic_strain']:.4f}" for b in ("b1", "b2"))
    ac = " / ".join(f"{pc[b]['peak_equivalent_plastic_strain']:.4f}" for b in ("b1", "b2"))
    df = [1e6 * pf[b]["permanent_indentation_m"] for b in ("b1", "b2")]
    dc = [1e6 * pc[b]["permanent_indentation_m"] for b in ("b1", "b2")]
    mesh_phrase = f"first element {1e3 * mesh['first_element_m']:.2f} mm, {mesh['core_elements']}"
    peak = f"{change(f['peak_force_N'], c['peak_force_N'], 1)} from the coarse plastic run"
    work = f"{change(wf[0], wc[0])}, {change(wf[1], wc[1])}"
    return [
        f"{mesh_phrase} core elements",
        f"{sum(f['dof'].values()):,} DOF",
        f"peak {f['peak_force_N']:.1f} N ({peak})",
        f"contact {_duration_us(f):.0f} us ({change(_duration_us(f), _duration_us(c))})",
        f"e {f['restitution']:.3f} ({c['restitution']:.3f})",
        f"plastic work {wf[0]:.0f} + {wf[1]:.0f} uJ ({work})",
        f"peak plastic strain {af} ({ac})",
        f"dent b1 {df[0]:.2f} um and b2 {df[1]:.2f} um ({dc[0]:.1f} and {dc[1]:.2f} um)",
    ]


def test_fine_mesh_figures_are_its_record():
    fine = _json(PLASTIC / "short_rods_fine_mesh_plastic.json")
    coarse = _json(PLASTIC / "short_rods.json")
    assert [r["run"] for r in fine["rows"]] == ["plastic"]  # "no elastic run on it"
    assert fine["rod_mesh"] == {"first_element_m": 0.15e-3, "core_elements": 4}
    missing = _missing([*fine_mesh_phrases(fine, coarse), FINE_COMMAND])
    assert not missing, f"docs/plasticity.md lacks the fine-mesh record's figures: {missing}"


def test_fine_mesh_phrases_read_the_record():
    """Another peak or another plastic work is another phrase."""
    fine = _json(PLASTIC / "short_rods_fine_mesh_plastic.json")
    coarse = _json(PLASTIC / "short_rods.json")
    one = fine_mesh_phrases(fine, coarse)
    row = _plastic_row(fine)
    other = {**fine, "rows": [{**row, "peak_force_N": row["peak_force_N"] + 0.1}]}
    assert fine_mesh_phrases(other, coarse)[2] != one[2]
    b1 = {**row["plastic"]["b1"], "plastic_work_J": 1.1 * row["plastic"]["b1"]["plastic_work_J"]}
    other = {**fine, "rows": [{**row, "plastic": {**row["plastic"], "b1": b1}}]}
    assert fine_mesh_phrases(other, coarse)[5] != one[5]


#: `flexmvm select` on the 1 m plastic rods: its ncc.csv and selection.json, stored side by side
SELECT_CSV = PLASTIC / "one_metre_select_ncc.csv"
SELECT_JSON = PLASTIC / "one_metre_select_selection.json"
#: the frame coordinates the page's 1 m table adds to the study's DOF (3 x nodes + modes)
FRAME_DOF = 6


def _rows(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _sel(r: dict) -> str:
    return f"{r['layers']}-{r['laps']}"


def select_phrases(selection: dict, ncc: list[dict]) -> list[str]:
    """The 1 m select's answer (model, DOF, force NCC to six digits) and, per study row, the
    page's 1 m table columns the study measures: DOF with the frame's 6, force NCC (five
    digits), peak and impulse errors, cells outside the region at yield and the verdict
    (runs.guard's plastic guard: any such cell makes the row invalid)."""
    answer = f"{_sel(selection)} + {selection['modes']}"
    invalid = [_sel(r) for r in ncc if int(r["plastic_cells_outside"]) > 0]
    found = f"{selection['dof']:,} DOF, NCC {selection['ncc_force']:.6f}"
    phrases = [f"answers {answer}, {found}, with {' and '.join(invalid)} invalid by the guard"]
    for r in ncc:
        cells = int(r["plastic_cells_outside"])
        verdict = "invalid (plastic guard)" if cells else "holds the zone"
        errors = f"{100 * float(r['peak_err']):+.2f} % | {100 * float(r['impulse_err']):+.2f} %"
        phrases += [
            f"| {_sel(r)} | {int(r['dof']) + FRAME_DOF:,} | ",
            f"| {float(r['ncc_force']):.5f} | {errors} | ",
            f"| {cells} | {verdict} |",
        ]
    return phrases


def test_one_metre_select_figures_are_its_record():
    selection = _json(SELECT_JSON)
    ncc = _rows(SELECT_CSV)
    assert selection["passed"] and [_sel(r) for r in ncc] == ["5-5", "7-5"]
    (answer,) = [r for r in ncc if _sel(r) == _sel(selection)]  # the same study: its row
    assert float(answer["ncc_force"]) == selection["ncc_force"]
    assert int(answer["dof"]) == selection["dof"]
    missing = _missing([*select_phrases(selection, ncc), SELECT_JSON.name])
    assert not missing, f"docs/plasticity.md lacks the 1 m select's figures: {missing}"


def test_select_phrases_read_the_record():
    """Another NCC or another count of cells outside is another phrase."""
    selection, ncc = _json(SELECT_JSON), _rows(SELECT_CSV)
    one = select_phrases(selection, ncc)
    assert select_phrases({**selection, "ncc_force": 0.9998}, ncc)[0] != one[0]
    quiet = [{**r, "plastic_cells_outside": "0"} for r in ncc]
    assert select_phrases(selection, quiet)[0] != one[0]
    assert select_phrases(selection, quiet)[3] != one[3]
