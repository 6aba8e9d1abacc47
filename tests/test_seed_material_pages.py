"""The material-study tables of docs/seed_reproduction.md come from their stamped records
(issue 51 item 4), as tests/test_study_pages.py does for docs/studies.md: each force-NCC
table, its line of runs and wall times and its line of means is remade here from
docs/seed_reproduction/materials_<mesh>_<kind>.json|csv (`flexmvm study materials`) and must
stand on the page as it is; a record remade with other numbers fails this test until the page
says what the record says. Reads JSON, CSV and Markdown only.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

from flexmvm.results.summary_keys import with_current_keys

ROOT = Path(__file__).resolve().parents[1]
RECORDS = ROOT / "docs" / "seed_reproduction"
PAGE = ROOT / "docs" / "seed_reproduction.md"
STUDY_REFS = ROOT / "docs" / "studies" / "materials"

#: the mode counts each table shows (its record's grid: seed mesh 7:43:6, default 7:43:12)
SEED_MODES = (7, 13, 19, 25, 31, 37, 43)
DEFAULT_MODES = (7, 19, 31, 43)


def _record(name: str) -> tuple[dict, list[dict]]:
    """materials.json and materials.csv of one study, as copied under docs/."""
    with open(RECORDS / f"{name}.csv", newline="") as fh:
        table = list(csv.DictReader(fh))
    return json.loads((RECORDS / f"{name}.json").read_text()), table


def _missing(rows: list[str]) -> list[str]:
    """The rows not on the page (whitespace runs as one space: the text lines wrap)."""
    page = " ".join(PAGE.read_text().split())
    return [row for row in rows if " ".join(row.split()) not in page]


def _cells(table: list[dict], material: str, sel: str) -> dict[int, dict]:
    return {int(r["modes"]): r for r in table if (r["material"], r["selection"]) == (material, sel)}


def ncc_rows(
    materials: dict, table: list[dict], modes: tuple[int, ...], cb: list[dict] | None = None
) -> list[str]:
    """The NCC table: force NCC per mode count (four digits), the peak error at the last mode
    count (0.1 %) and, given the Craig-Bampton study ``cb`` of the same grid, its NCC there."""
    rows = []
    for m in materials["materials"]:
        for sel in materials["selections"]:
            cells = _cells(table, m, sel)
            nccs = " | ".join(f"{float(cells[n]['ncc_force']):.4f}" for n in modes)
            row = f"| {m} | {sel} | {nccs} | {100 * float(cells[modes[-1]]['peak_err']):+.1f} % |"
            if cb is not None:
                row += f" {float(_cells(cb, m, sel)[modes[-1]]['ncc_force']):.4f} |"
            rows.append(row)
    return rows


def summary_lines(name: str, materials: dict, table: list[dict]) -> list[str]:
    """The line naming the record (runs, range of wall times per run, 0.1 s) and the line of
    mean NCC per material in the observed order (four digits) and whether the seed's ordering
    holds (materials.json's seed_ordering_holds)."""
    walls = [float(r["wall_time_s"]) for r in table]
    means = " > ".join(
        f"{m} {materials['materials'][m]['mean_ncc_force']:.4f}"
        for m in materials["observed_order"]
    )
    return [
        f"(`{name}.csv`; {len(table)} runs, {min(walls):.1f}-{max(walls):.1f} s each",
        f"Mean: {means}, {'holds' if materials['seed_ordering_holds'] else 'does not hold'}",
    ]


def _check(name: str, modes: tuple[int, ...], cb: str | None = None) -> None:
    materials, table = _record(name)
    other = None if cb is None else _record(cb)[1]
    rows = ncc_rows(materials, table, modes, other) + summary_lines(name, materials, table)
    missing = _missing(rows)
    assert not missing, f"docs/seed_reproduction.md lacks {name}'s rows: {missing}"


def test_default_mesh_cb_table_is_its_record():
    _check("materials_default_mesh_cb", DEFAULT_MODES)


def test_default_mesh_eq4_table_is_its_record():
    """Its last column is the Craig-Bampton record's NCC at 43 modes."""
    _check("materials_default_mesh_eq4", DEFAULT_MODES, cb="materials_default_mesh_cb")


def test_seed_mesh_cb_table_is_its_record():
    _check("materials_seed_mesh_cb", SEED_MODES)


def test_seed_mesh_eq4_table_is_its_record():
    _check("materials_seed_mesh_eq4", SEED_MODES)


def default_reference_cells(materials: dict) -> list[str]:
    """The references table's default-mesh cells: peak (0.1 N, % against the theory's peak
    to 0.1) and contact interval (1 us) of each material's reference, read from
    docs/studies/materials/<material>/reference.json (the same references: same command)."""
    cells = []
    for m, t in materials["materials"].items():
        ref = json.loads((STUDY_REFS / m / "reference.json").read_text())
        s = with_current_keys(ref["summary"])
        peak, (a, b) = s["max_contact_force_interval_mean_N"], s["contact_intervals_s"][-1]
        err = 100 * (peak / t["theory_peak_force_N"] - 1)
        cells.append(f"| {peak:.1f} N ({err:+.1f} %) | {1e6 * a:.0f}..{1e6 * b:.0f} us |")
    return cells


def test_default_mesh_references_are_their_records():
    missing = _missing(default_reference_cells(_record("materials_default_mesh_cb")[0]))
    assert not missing, f"docs/seed_reproduction.md lacks the references' cells: {missing}"


def test_ncc_rows_read_every_column():
    """The rows are made from the record's numbers: another NCC is another row."""
    cells = [
        {"material": "W", "selection": "1-1", "modes": str(n), "ncc_force": "0.92"}
        | {"peak_err": "0.048"}
        for n in DEFAULT_MODES
    ]
    rec = {"materials": {"W": {}}, "selections": ["1-1"]}
    one = ncc_rows(rec, cells, DEFAULT_MODES, cb=cells)[0]
    assert one == "| W | 1-1 | 0.9200 | 0.9200 | 0.9200 | 0.9200 | +4.8 % | 0.9200 |"
    cells[1] = cells[1] | {"ncc_force": "0.93"}
    assert ncc_rows(rec, cells, DEFAULT_MODES)[0] != one
