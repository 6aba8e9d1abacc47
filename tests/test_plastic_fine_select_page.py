"""docs/plasticity.md's figures from two stamped records of the seed case with yielding rods
(issue 51 item 4), as tests/test_page_figures.py does for other pages: the short plastic rods
on the finer contact mesh (docs/seed_plastic/short_rods_fine_mesh_plastic.json, from
``benchmarks/seed_plastic.py --fine-mesh``, against the default mesh's plastic run in
short_rods.json). Each figure is remade here from its record and must stand on the page as it
is. Reads JSON and Markdown only; no run.
"""

from __future__ import annotations

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
