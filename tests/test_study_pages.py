"""The tables of docs/studies.md come from the studies' stamped records (issue 51 item 4), as
tests/test_page_figures.py does for other pages: each table is remade here from its record
under docs/studies/ (selection.json, selection_search.json, replays/, ncc.csv, reference.json) and
must stand on the page as it is; a record remade with other
numbers fails this test until the page says what the record says. Reads JSON, CSV and
Markdown only.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

from flexmvm.results.summary_keys import with_current_keys

ROOT = Path(__file__).resolve().parents[1]
STUDIES = ROOT / "docs" / "studies"
PAGE = ROOT / "docs" / "studies.md"
SEL, STRIKER, MATS = (
    STUDIES / "selection",
    STUDIES / "selection_full_striker",
    STUDIES / "materials",
)

#: the material study's modes on the page (the record's grid: 7:43:12)
MAT_MODES = (7, 19, 31, 43)


def _json(path: Path) -> dict:
    return json.loads(path.read_text())


def _csv(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _missing(rows: list[str]) -> list[str]:
    page = PAGE.read_text().replace("**", "")
    return [row for row in rows if row not in page]


def _model(s: dict) -> str:
    return f"{s['layers']}-{s['laps']} + {s['modes']}"


def selection_table_rows(ncc: list[dict]) -> list[str]:
    """The 140-run table: force NCC (four digits) per selection (rows by retained nodes) and
    mode count (columns), from ncc.csv."""
    modes = sorted({int(r["modes"]) for r in ncc})
    cell = {(r["layers"], r["laps"], int(r["modes"])): r for r in ncc}
    sels = sorted(
        {(r["layers"], r["laps"]) for r in ncc}, key=lambda s: int(cell[(*s, 7)]["nodes"])
    )
    rows = [f"| selection (nodes) | {' | '.join(map(str, modes))} |"]
    for i, j in sels:
        nccs = " | ".join(f"{float(cell[(i, j, m)]['ncc_force']):.4f}" for m in modes)
        rows.append(f"| {i}-{j} ({cell[(i, j, 7)]['nodes']}) | {nccs} |")
    return rows


def _target(t: dict) -> str:
    """A target as the command line writes it: ``ncc>=0.99,peak<=0.02``."""
    peak = "" if t["peak_err_max"] is None else f",peak<={t['peak_err_max']:g}"
    return f"ncc>={t['ncc_min']:g}{peak}"


def search_row(brute: dict, search: dict) -> str:
    """The --search table's row of the target both records were run for."""
    assert brute["target"] == search["target"] and search["search"] and not brute["search"]
    return (
        f"| `{_target(brute['target'])}` | {_model(brute)} ({brute['dof']} DOF) | "
        f"{_model(search)} | {search['runs']} runs |"
    )


#: the --search table's other targets: their records, replays on the 140 stored cases
REPLAYS = ("ncc0.95", "ncc0.99-peak0.02", "ncc0.999", "ncc0.9999")


def _ref_cell(ref: dict) -> str:
    s = with_current_keys(ref["summary"])
    return (
        f"{s['max_contact_force_interval_mean_N']:.1f} N / {1e3 * s['contact_intervals_s'][-1][1]:.3f} ms, "
        f"{s['wall_time_s']:.0f} s"
    )


def striker_rows(seed_sel: dict, seed_ncc: list[dict], seed_ref: dict, full: dict) -> list[str]:
    """The striker check's table: each side's reference (peak, end of contact, wall time),
    answer and mean wall time per run (of the 140-run study: its 21 runs of the grid of the
    full-striker study)."""
    sel, ncc, ref = full["selection"], full["ncc"], full["reference"]
    grid = {(r["layers"], r["laps"], r["modes"]) for r in ncc}
    sub = [r for r in seed_ncc if (r["layers"], r["laps"], r["modes"]) in grid]
    assert len(sub) == len(ncc) == 21

    def answer(s: dict) -> str:
        return f"{s['layers']}-{s['laps']} + {s['modes']} modes, {s['dof']} DOF, NCC {s['ncc_force']:.4f}"

    def wall(rows: list[dict]) -> str:
        return f"{sum(float(r['wall_time_s']) for r in rows) / len(rows):.1f} s"

    return [
        f"| reference peak / contact | {_ref_cell(seed_ref)} | {_ref_cell(ref)} |",
        f"| smallest model for ncc >= 0.99 | {answer(seed_sel)} | {answer(sel)} |",
        f"| mean wall time per run | {wall(sub)} | {wall(ncc)} |",
    ]


def test_selection_table_is_its_record():
    missing = _missing(selection_table_rows(_csv(SEL / "ncc.csv")))
    assert not missing, f"docs/studies.md lacks the record's rows: {missing}"


def test_search_rows_are_their_records():
    pairs = [(_json(SEL / "selection.json"), _json(SEL / "selection_search.json"))]
    for name in REPLAYS:
        replay = SEL / "replays"
        pairs.append((_json(replay / f"{name}-brute.json"), _json(replay / f"{name}-search.json")))
    rows = [search_row(b, s) for b, s in pairs]
    missing = _missing(rows)
    assert not missing, f"docs/studies.md lacks the records' rows: {missing}"


def test_striker_table_is_its_records():
    full = {
        "selection": _json(STRIKER / "selection.json"),
        "ncc": _csv(STRIKER / "ncc.csv"),
        "reference": _json(STRIKER / "reference.json"),
    }
    rows = striker_rows(
        _json(SEL / "selection.json"), _csv(SEL / "ncc.csv"), _json(SEL / "reference.json"), full
    )
    missing = _missing(rows)
    assert not missing, f"docs/studies.md lacks the record's rows: {missing}"


#: the material study's modes on the page (the record's grid: 7:43:12)
MAT_MODES = (7, 19, 31, 43)
MATS = STUDIES / "materials"


def reference_rows(materials: dict, refs: dict[str, dict]) -> list[str]:
    """The material study's references against the 1D wave-Hertz theory (materials.json's
    theory, each <material>/reference.json's summary): forces to 0.1 N, times to 1 us."""
    rows = []
    for m, ref in refs.items():
        s, t = with_current_keys(ref["summary"]), materials["materials"][m]
        peak, end = s["max_contact_force_interval_mean_N"], s["contact_intervals_s"][-1][1]
        tp, te = t["theory_peak_force_N"], t["theory_contact_duration_s"]
        rows.append(
            f"| {m} | {peak:.1f} N | {tp:.1f} N ({100 * (peak / tp - 1):+.1f} %) | "
            f"{1e6 * end:.0f} us | {1e6 * te:.0f} us ({100 * (end / te - 1):+.1f} %) | "
            f"{s['momentum_rel_error']:.1e} | {100 * s['energy_rel_change']:+.2f} % |"
        )
    return rows


def material_rows(materials: dict, table: list[dict]) -> list[str]:
    """The material study's NCC table: force NCC at 7, 19, 31, 43 modes (four digits), the
    peak error at 43 modes, and the guard's range over the four (0 when none, ": invalid"
    when a run of the row is outside its model's validity, materials.json)."""
    invalid = {b["case"] for b in materials["guard_outside_validity"]}
    rows = []
    for m in materials["materials"]:
        for sel in materials["selections"]:
            cells = {
                int(r["modes"]): r for r in table if (r["material"], r["selection"]) == (m, sel)
            }
            nccs = " | ".join(f"{float(cells[n]['ncc_force']):.4f}" for n in MAT_MODES)
            guard = [100 * float(cells[n]["guard_outside_fraction"]) for n in MAT_MODES]
            lo, hi = min(guard), max(guard)
            g = "0" if hi == 0 else f"{lo:.1f}-{hi:.1f} %" if lo != hi else f"{lo:.1f} %"
            i, j = sel.split("-")
            if any(f"{m}-l{i}-j{j}-m{n}" in invalid for n in MAT_MODES):
                g += ": invalid"
            peak = 100 * float(cells[43]["peak_err"])
            rows.append(f"| {m} | {sel} | {nccs} | {peak:+.1f} % | {g} |")
    return rows


def test_material_tables_are_their_records():
    materials = _json(MATS / "materials.json")
    refs = {m: _json(MATS / m / "reference.json") for m in materials["materials"]}
    rows = reference_rows(materials, refs) + material_rows(materials, _csv(MATS / "materials.csv"))
    missing = _missing(rows)
    assert not missing, f"docs/studies.md lacks the record's rows: {missing}"


def test_material_rows_read_every_column():
    """The rows are made from the record's numbers: another NCC or guard is another row."""
    cells = [
        {"material": "W", "selection": "1-1", "modes": str(n), "ncc_force": "0.92"}
        | {"guard_outside_fraction": str(g), "peak_err": "0.048"}
        for n, g in zip(MAT_MODES, (0.997, 0.998, 0.999, 0.999))
    ]
    rec = {"materials": {"W": {}}, "selections": ["1-1"]}
    rec["guard_outside_validity"] = [{"case": "W-l1-j1-m7"}]
    one = material_rows(rec, cells)[0]
    assert one == "| W | 1-1 | 0.9200 | 0.9200 | 0.9200 | 0.9200 | +4.8 % | 99.7-99.9 %: invalid |"
    cells[0] = cells[0] | {"ncc_force": "0.93"}
    assert material_rows(rec, cells)[0] != one
