"""docs/studies.md's paragraph on the shipped scheme ("The answer holds on the shipped scheme")
comes from its stamped record, docs/studies/selection/scheme_side_by_side.json
(benchmarks/study_scheme.py, issue 51 item 4): its figures are remade here from the record and
must stand on the page as they are; the study-scheme column must reproduce the 140-run table
(docs/studies/selection/ncc.csv) to the four digits the page claims. Reads JSON, CSV and
Markdown only.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SELECTION = ROOT / "docs" / "studies" / "selection"
RECORD = SELECTION / "scheme_side_by_side.json"
PAGE = ROOT / "docs" / "studies.md"
SHIPPED, STUDY = "shipped scheme", "study scheme"


def _rows(record: dict, scheme: str) -> dict[str, dict]:
    return {r["model"]: r for r in record[scheme]["rows"]}


def _mean_cpu(record: dict, scheme: str) -> float:
    cpu = [r["cpu_s"] for r in record[scheme]["rows"]]
    return sum(cpu) / len(cpu)


def page_figures(record: dict) -> list[str]:
    """The paragraph's figures: the answer's NCC (four digits) and peak error (0.1 %) on the
    shipped scheme; 2-2 + 43's NCC on both schemes and its guard share on the shipped one
    (whole %); the CPU of a candidate, shipped over study scheme (mean over the candidates of
    one process, two digits), and the range of the extra coordinates (the patch fields)."""
    shipped, study = _rows(record, SHIPPED), _rows(record, STUDY)
    answer, two = shipped["1-3 + 25"], shipped["2-2 + 43"]
    extra = [shipped[m]["dof"] - study[m]["dof"] for m in shipped]
    ratio = _mean_cpu(record, SHIPPED) / _mean_cpu(record, STUDY)
    return [
        f"1-3 + 25 reads NCC {answer['ncc_force']:.4f} (peak {100 * answer['peak_err']:+.1f} %)",
        f"2-2 + 43 reads NCC {two['ncc_force']:.4f} ({study['2-2 + 43']['ncc_force']:.4f} here)",
        f"({100 * two['guard_outside_fraction']:.0f} % of its impulse on nodes held stiff)",
        f"{ratio:.2f} x the CPU and has {min(extra)} to {max(extra)} more coordinates",
    ]


def _grid() -> dict[str, float]:
    """The 140-run table's force NCC by model ("1-3 + 25")."""
    with open(SELECTION / "ncc.csv", newline="") as fh:
        return {
            f"{r['layers']}-{r['laps']} + {r['modes']}": float(r["ncc_force"])
            for r in csv.DictReader(fh)
        }


def test_page_paragraph_is_the_record():
    record = json.loads(RECORD.read_text())
    page = " ".join(PAGE.read_text().split())
    missing = [f for f in page_figures(record) if f not in page]
    assert not missing, f"docs/studies.md lacks the side-by-side's figures: {missing}"


def test_study_column_reproduces_the_grid_to_four_digits():
    """The page says so; the same scheme, settings and reference as the 140-run table."""
    record, grid = json.loads(RECORD.read_text()), _grid()
    off = {
        m: (r["ncc_force"], grid[m])
        for m, r in _rows(record, STUDY).items()
        if f"{r['ncc_force']:.4f}" != f"{grid[m]:.4f}"
    }
    assert not off, f"study-scheme NCC against ncc.csv: {off}"


def test_record_carries_each_runs_stamp():
    """Every run of the record (references and candidates, both schemes) has its stamp."""
    record = json.loads(RECORD.read_text())
    for scheme in (SHIPPED, STUDY):
        side = record[scheme]
        stamps = [side["reference_provenance"], *(r["provenance"] for r in side["rows"])]
        assert all({"key", "code", "libraries", "scenario_sha256"} <= set(s) for s in stamps)
        assert len({s["key"] for s in stamps}) == len(stamps), scheme
    assert record["meta"]["provenance"]["settings"]["t_end_s"] == 8e-4
