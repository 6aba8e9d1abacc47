"""The two seed-mesh selection grids of docs/seed_reproduction.md come from their stamped
records (issue 51 item 4): the Craig-Bampton grid (`flexmvm select`,
docs/seed_reproduction/select_cb_ncc.csv + select_cb_selection.json) and the eq. (4) grid
(`benchmarks/seed_reproduction.py --csv`, grid_eq4_ncc.csv + grid_eq4_meta.json). Each table,
its line naming the record (runs, time, the smallest model passing NCC >= 0.99) and the grid
figures the claims table quotes are remade here from the records and must stand on the page as
they are; a record remade with other numbers fails this test until the page says what the
record says. Reads JSON, CSV and Markdown only (the other seed-reproduction tables:
tests/test_page_figures.py, tests/test_seed_material_pages.py).
"""

from __future__ import annotations

import csv
import itertools
import json
from pathlib import Path

from flexmvm.runs.guard import invalid_reason

ROOT = Path(__file__).resolve().parents[1]
RECORDS = ROOT / "docs" / "seed_reproduction"
PAGE = ROOT / "docs" / "seed_reproduction.md"

#: the mode counts of both grids (select's default 7:43:6) and the rows each table shows
MODES = (7, 13, 19, 25, 31, 37, 43)
CB_ROWS = ("1-1", "2-1", "4-1", "1-2", "2-2", "1-5", "4-5")
EQ4_ROWS = ("1-1", "2-1", "3-1", "1-2", "1-3", "2-2", "1-5", "2-3", "3-3", "4-5")
#: the seed's accuracy target (select's default --target)
NCC_MIN = 0.99


def _num(v: str):
    """A CSV cell as a number (int, float) or None (empty); other text as it is."""
    if v == "":
        return None
    for kind in (int, float):
        try:
            return kind(v)
        except ValueError:
            pass
    return v


def _table(name: str) -> dict[tuple[str, int], dict]:
    """{(selection 'i-j', modes): row, its cells as numbers} of a grid's CSV record."""
    with open(RECORDS / name, newline="") as fh:
        rows = [{k: _num(v) for k, v in r.items()} for r in csv.DictReader(fh)]
    return {(f"{r['layers']}-{r['laps']}", r["modes"]): r for r in rows}


def _dof_total(row: dict) -> int:
    """DOF with the 6 frame coordinates (select's ncc.csv has the elastic count, dof)."""
    return row["dof_total"] if "dof_total" in row else row["dof"] + 6


def _missing(rows: list[str]) -> list[str]:
    """The rows not on the page (whitespace runs as one space: the text lines wrap)."""
    page = " ".join(PAGE.read_text().split())
    return [row for row in rows if " ".join(row.split()) not in page]


def grid_rows(table: dict, selections: tuple[str, ...], key: str = "ncc_force") -> list[str]:
    """A grid table: one row per selection, '| i-j (nodes) |' then the NCC (``key``) at each
    mode count to four digits."""
    rows = []
    for sel in selections:
        cells = " | ".join(f"{table[sel, m][key]:.4f}" for m in MODES)
        rows.append(f"| {sel} ({table[sel, MODES[0]]['nodes']}) | {cells} |")
    return rows


def smallest(table: dict, key: str = "ncc_force", guard: bool = True) -> tuple[str, int, dict]:
    """The smallest model (fewest DOF, then the higher NCC) whose ``key`` reaches NCC_MIN,
    with ``guard`` only among the runs inside their model's validity (runs.guard's rule, the
    one `flexmvm select` applies): (selection, modes, row)."""
    passing = [
        (k, r)
        for k, r in table.items()
        if r[key] >= NCC_MIN and not (guard and invalid_reason(r) is not None)
    ]
    (sel, m), row = min(passing, key=lambda kr: (_dof_total(kr[1]), -kr[1][key]))
    return sel, m, row


def answer(
    table: dict, key: str = "ncc_force", guard: bool = True, frame: str = " with the frame"
) -> str:
    """'i-j + m, N DOF with the frame, NCC x.xxxx' of :func:`smallest`."""
    sel, m, row = smallest(table, key, guard)
    return f"{sel} + {m}, {_dof_total(row)} DOF{frame}, NCC {row[key]:.4f}"


def test_cb_grid_is_its_record():
    """The Craig-Bampton table (NCC over the contact window), its runs and its answer, which is
    selection.json's and the table's smallest model inside the guard."""
    table = _table("select_cb_ncc.csv")
    sel = json.loads((RECORDS / "select_cb_selection.json").read_text())
    assert answer(table) == (
        f"{sel['layers']}-{sel['laps']} + {sel['modes']}, {sel['dof_total']} DOF with the frame, "
        f"NCC {sel['ncc_force']:.4f}"
    )
    rows = grid_rows(table, CB_ROWS) + [
        f"(`select_cb_ncc.csv`, `select_cb_selection.json`; {sel['runs']} runs,",
        f"smallest passing ncc >= 0.99 inside the guard: {answer(table)}):",
    ]
    missing = _missing(rows)
    assert not missing, f"docs/seed_reproduction.md lacks the CB grid's rows: {missing}"


def test_eq4_grid_is_its_record():
    """The eq. (4) tables (over the contact window and over 0.8 ms), the CPU time of the record
    and the smallest models on either window, inside the guard and not."""
    table = _table("grid_eq4_ncc.csv")
    meta = json.loads((RECORDS / "grid_eq4_meta.json").read_text())
    assert meta["rows_csv"] == "grid_eq4_ncc.csv" and len(meta["run_keys"]) == len(table)
    whole = smallest(table, "ncc_force_whole", guard=False)
    rows = [
        *grid_rows(table, EQ4_ROWS),
        *grid_rows(table, EQ4_ROWS, "ncc_force_whole"),
        (
            f"(`grid_eq4_ncc.csv`, `grid_eq4_meta.json`; {len(table)} runs with peaks, penetrations "
            f"and the guard's share, {meta['cpu_time_total_s']:.0f} s CPU; smallest passing ncc >= "
            f"0.99 inside the guard: {answer(table)}), force NCC over the contact window:"
        ),
        (
            f"(smallest passing ncc >= 0.99: {answer(table, 'ncc_force_whole', False)}, "
            f"{'outside' if invalid_reason(whole[2]) else 'inside'} the guard; inside it "
            f"{answer(table, 'ncc_force_whole', frame='')}):"
        ),
    ]
    missing = _missing(rows)
    assert not missing, f"docs/seed_reproduction.md lacks the eq. (4) grid's rows: {missing}"


def _two(v: float) -> str:
    """An NCC to two digits, three where two would read 0.99 or more (the claims' series)."""
    return f"{v:.3f}" if round(v, 2) >= NCC_MIN else f"{v:.2f}"


def _sci(v: float) -> str:
    """4.7e-8, as the page writes a length (no exponent's leading zero)."""
    return f"{v:.1e}".replace("e-0", "e-")


def _largest_dip(table: dict, key: str = "ncc_force") -> tuple[str, float]:
    """The selection whose NCC falls most from one mode count to the next, and by how much."""
    dips = [
        (table[s, b][key] - table[s, a][key], s)
        for s in {k[0] for k in table}
        for a, b in itertools.pairwise(MODES)
    ]
    d, s = min(dips)
    return s, d


def claims_figures(cb: dict, eq: dict) -> list[str]:
    """The grid figures that "The claims, measured" and the grid section quote: 2-2 against
    1-5, NCC against the modes, the smallest models, the spread over selections, the
    penetrations of the eq. (4) grid."""
    w, c = "ncc_force_whole", "ncc_force"
    later = sum(cb["2-2", m][c] < cb["1-5", m][c] for m in MODES)
    series = ", ".join(_two(eq["1-1", m][w]) for m in MODES)
    (se, de), (sc, dc) = _largest_dip(eq), _largest_dip(cb)
    sel, m, row = smallest(eq, w, guard=False)
    pens = [r["max_penetration_m"] for r in eq.values()]
    layers = [eq[s, 37] for s in ("1-1", "2-1", "3-1")]
    spread = [[cb[k][c] for k in cb if k[1] == n] for n in (31, 37)]
    return [
        (
            f"37 modes: {eq['2-2', 37][w]:.4f} vs {eq['1-5', 37][w]:.4f}; 2-1, 2 nodes, "
            f"{eq['2-1', 37][w]:.4f}, beats 1-5"
        ),
        (
            f"37 modes: {eq['2-2', 37][c]:.4f} vs {eq['1-5', 37][c]:.4f}); CB (over the contact "
            f"window): no at {later} of 7 mode counts (25 modes {cb['2-2', 25][c]:.4f} vs "
            f"{cb['1-5', 25][c]:.4f}; 37 modes {cb['2-2', 37][c]:.4f} vs {cb['1-5', 37][c]:.4f})"
        ),
        f"(1-1: {series} for 7..43)",
        f"(from 7 to 13 it dips: eq. (4) {se} {de:+.4f}, CB {sc} {dc:+.4f})",
        f"over 0.8 ms: eq. (4) {sel} + {m} ({_dof_total(row) - 6} DOF, {row[w]:.4f})",
        "CB {} + {} ({} DOF with the frame, {:.4f})".format(*answer_parts(cb)),
        "eq. (4) {} + {} ({}, {:.4f})".format(*answer_parts(eq)),
        "the eq. (4) grid below finds **{} + {}** ({} DOF, {:.4f})".format(*answer_parts(eq)),
        "0.8 ms; {} over the contact window)".format(", ".join(f"{r[c]:.4f}" for r in layers)),
        "modes: {} over 0.8 ms;".format(", ".join(f"{r[w]:.4f}" for r in layers)),
        (
            f"(every selection {min(spread[0]):.4f}-{max(spread[0]):.4f} at 31 modes, "
            f"{min(spread[1]):.4f}-{max(spread[1]):.4f} at 37)"
        ),
        f"({_sci(min(pens))} to {_sci(max(pens))} m in every run of the eq. (4) grid;",
        "(37 modes: {})".format(
            ", ".join(f"{k} {100 * eq[k, 37]['peak_err']:+.1f} %" for k in ("1-1", "2-2", "4-5"))
        ),
    ]


def answer_parts(table: dict) -> tuple[str, int, int, float]:
    """(selection, modes, DOF with the frame, NCC) of the smallest model inside the guard over
    the contact window."""
    sel, m, row = smallest(table)
    return sel, m, _dof_total(row), row["ncc_force"]


def test_claims_quote_the_grids():
    """The claims table's and the grid section's figures from the two grid records."""
    figures = claims_figures(_table("select_cb_ncc.csv"), _table("grid_eq4_ncc.csv"))
    missing = _missing(figures)
    assert not missing, f"docs/seed_reproduction.md lacks the grids' figures: {missing}"
