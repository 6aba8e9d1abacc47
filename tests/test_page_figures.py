"""Figures on the user pages come from a stored, stamped record (issue 51 item 4): the tables
below are remade here from their record and must stand on the page as they are; a record
remade with other numbers fails this test until the page says what the record says. Reads
JSON and Markdown only.
"""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"

#: the beam page's names of the record's rows (docs/beam_impact/sphere_beam_theory.json)
BEAM_NAMES = {
    "theory, Hertz": "theory (Timoshenko + Hertz)",
    "theory, FE bending + local law": "theory, FE bending + FE local law",
}


def _windows(r: dict) -> str:
    return ", ".join(f"{a:.1f}-{b:.1f}" for a, b in r["contacts_us"])


def beam_table_rows(record: dict) -> list[str]:
    """docs/beam_impact.md's table, row by row, from its record (four digits as stored; the
    theory's probe NCC to three)."""
    rows = []
    for r in record["rows"]:
        name = BEAM_NAMES.get(r["model"], r["model"])
        if r["model"] == "full FE":
            rows.append(f"| {name} | {_windows(r)} | {r['peak_N']:.1f} | 1 | | | 1 |")
            continue
        probes = (
            f"{r['ncc_beam_mid_bottom']:.4f} / {r['ncc_beam_end_a']:.4f}"
            if r["model"] == "MVM"
            else f"{r['ncc_beam_mid_bottom']:.3f} / {r['ncc_beam_end_a']:.3f}"
        )
        rows.append(
            f"| {name} | {_windows(r)} | {r['peak_N']:.1f} | {r['ncc_force']:.4f} / "
            f"{r['ncc_force_whole']:.4f} | {100 * r['peak_err']:+.1f} % | "
            f"{100 * r['impulse_err']:+.1f} % | {probes} |"
        )
    return rows


def test_beam_impact_table_is_its_record():
    record = json.loads((DOCS / "beam_impact" / "sphere_beam_theory.json").read_text())
    page = (DOCS / "beam_impact.md").read_text()
    missing = [row for row in beam_table_rows(record) if row not in page]
    assert not missing, f"docs/beam_impact.md lacks the record's rows: {missing}"


def test_beam_table_rows_read_every_column():
    """The rows are made from the record's numbers: another peak is another row."""
    r = {
        "model": "MVM",
        "contacts_us": [[1.2, 80.3]],
        "peak_N": 257.5,
        "ncc_force": 1.0,
        "ncc_force_whole": 1.0,
        "peak_err": -0.0008,
        "impulse_err": -0.0001,
        "ncc_beam_mid_bottom": 0.9997,
        "ncc_beam_end_a": 0.9997,
    }
    one = beam_table_rows({"rows": [r]})[0]
    assert one == "| MVM | 1.2-80.3 | 257.5 | 1.0000 / 1.0000 | -0.1 % | -0.0 % | 0.9997 / 0.9997 |"
    assert beam_table_rows({"rows": [r | {"peak_N": 258.0}]})[0] != one
