"""Figures on the user pages come from a stored, stamped record (issue 51 item 4): the tables
below are remade here from their record and must stand on the page as they are; a record
remade with other numbers fails this test until the page says what the record says. Reads
JSON and Markdown only.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

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


#: docs/seed_reproduction.md's names of benchmarks/seed_reproduction.py's model kinds
SEED_KINDS = {"mvm-seed": "eq. (4)", "mvm-seed-fixed": "eq. (4)-fixed", "mvm": "CB"}
SEED_PAGE = DOCS / "seed_reproduction.md"


def _seed_name(model: str, with_modes: bool) -> str:
    """'mvm-seed:1-1:37' -> 'eq. (4) 1-1 + 37' (or 'eq. (4) 1-1'); 'full' -> 'full FE'."""
    if model == "full":
        return "full FE"
    kind, sel, modes = model.split(":")
    return f"{SEED_KINDS[kind]} {sel}" + (f" + {modes}" if with_modes else "")


def _sci(x: float, decimals: int = 1) -> str:
    """4.7e-8 as the page writes it (no zero-padded exponent)."""
    mant, exp = f"{x:.{decimals}e}".split("e")
    return f"{mant}e{int(exp)}"


def _nccs(v: dict) -> str:
    """'contact / whole': force NCC over the contact window and over the run's window."""
    return f"{v['ncc_force']:.4f} / {v['ncc_force_whole']:.4f}"


def seed_mesh_table_rows(record: dict) -> list[str]:
    """The seed-mesh model table of docs/seed_reproduction.md from its record
    (docs/seed_reproduction/seed_mesh_1-1_37.json): NCC to four digits, errors in % to two,
    forces to 0.1 N, the contact's end to 0.1 us (the step is 0.5 us)."""
    rows = []
    body = record["body"]
    for r in record["rows"]:
        v = r.get("vs_full")
        errs = (
            "- | - | - | -"
            if v is None
            else f"{_nccs(v)} | {100 * v['peak_err']:+.2f} % | "
            f"{100 * v['impulse_err']:+.2f} % | {100 * v['duration_err']:+.2f} %"
        )
        end = 1e6 * r["contact_intervals_s"][0][1]
        rows.append(
            f"| {_seed_name(r['model'], True)} | {r['dof'][body]:,} | {errs} | "
            f"{r['max_contact_force_N']:.1f} N | {end:.1f} us | {_sci(r['max_penetration_m'])} m | "
            f"{_nccs(r['vs_theory'])} |"
        )
    return rows


def default_mesh_table_rows(record: dict) -> list[str]:
    """The default-mesh table of docs/seed_reproduction.md from its record
    (docs/seed_reproduction/default_mesh_37modes.json): penetrations in um to two digits."""
    rows = []
    body = record["body"]
    for r in record["rows"]:
        pen = r["max_penetration_by_direction_m"]
        depth = f"{1e6 * pen['b2 nodes into b1']:.2f} / {1e6 * pen['b1 nodes into b2']:.2f} um"
        v = r.get("vs_full")
        if v is None:
            end = 1e6 * r["contact_intervals_s"][0][1]
            cells = f"- | {r['max_contact_force_N']:.1f} N | {end:.0f} us"
        else:
            cells = f"{_nccs(v)} | {100 * v['peak_err']:+.2f} % | {100 * v['duration_err']:+.2f} %"
        rows.append(f"| {_seed_name(r['model'], False)} | {r['dof'][body]:,} | {cells} | {depth} |")
    return rows


def _ratio(x: float) -> str:
    return f"{x:.3f}" if x < 10 else f"{x:.1f}"


#: the stiffness table's columns: (basis, selection) of docs/seed_reproduction/stiffness.json
STIFF_COLUMNS = [
    ("mvm", "1-1"),
    ("mvm-seed", "1-1"),
    ("mvm-seed-fixed", "1-1"),
    ("mvm", "1-3"),
    ("mvm-seed", "1-3"),
    ("mvm-seed-fixed", "1-3"),
    ("mvm-seed", "2-2"),
    ("mvm-seed", "1-5"),
]
STIFF_ROWS = [
    ("seed", "point", "seed, point on the centre node"),
    ("default", "hertz", "default, Hertz pressure a = {a} mm"),
    ("default", "point", "default, point on the centre node"),
]


def stiffness_table_rows(record: list) -> list[str]:
    """The static stiffness table of docs/seed_reproduction.md from its record
    (docs/seed_reproduction/stiffness.json): compliance to four digits, its local part to
    three, the stiffness ratios to three decimals (one above 10)."""
    meshes = {m["mesh"]: m for m in record}
    rows = []
    for mesh, load, label in STIFF_ROWS:
        m = meshes[mesh]
        by = {(r["basis"], r["selection"]): r for r in m["rows"]}
        full = by[("full", "-")]
        c, local = full[f"{load}_compliance_m_per_N"], full[f"{load}_local_m_per_N"]
        ratios = " | ".join(_ratio(by[k][f"{load}_stiffness_vs_full"]) for k in STIFF_COLUMNS)
        name = label.format(a=f"{1e3 * m['hertz_radius_m']:.3f}")
        rows.append(f"| {name} | {_sci(c, 3)} m/N ({_sci(local, 2)}) | {ratios} |")
    return rows


def guard_table_rows(record: dict) -> list[str]:
    """The "Inside the guard" table of docs/seed_reproduction.md from its record
    (docs/seed_reproduction/guard_valid_models.json): Craig-Bampton rows first, by DOF; the
    guard's share of b2's impulse outside the kept nodes to 1 %, NCC to four digits."""
    rows = sorted(
        record["rows"][1:], key=lambda r: (r["model"].split(":")[0] != "mvm", r["dof"]["b2"])
    )
    out = []
    for r in rows:
        v, g = r["vs_full"], r["reduced_contact_guard"]["b2"]
        share = g["impulse_fraction_outside"]
        guard = (
            "inside"
            if not share
            else f"{100 * share:.0f} % on {g['nodes_loaded_outside']} nodes outside"
        )
        out.append(
            f"| {_seed_name(r['model'], True)} | {r['dof']['b2']:,} | {guard} | {_nccs(v)} | "
            f"{100 * v['peak_err']:+.2f} % |"
        )
    return out


def _missing(rows: list[str]) -> list[str]:
    page = SEED_PAGE.read_text().replace("**", "")
    return [row for row in rows if row not in page]


@pytest.mark.parametrize(
    ("name", "table_rows", "n_rows"),
    [
        ("seed_mesh_1-1_37.json", seed_mesh_table_rows, 4),
        ("guard_valid_models.json", guard_table_rows, 19),
        ("default_mesh_37modes.json", default_mesh_table_rows, 9),
        ("stiffness.json", stiffness_table_rows, None),
    ],
)
def test_seed_reproduction_table_is_its_record(name, table_rows, n_rows):
    """Each table of docs/seed_reproduction.md, row by row, from its record."""
    record = json.loads((DOCS / "seed_reproduction" / name).read_text())
    rows = table_rows(record)
    assert rows and (n_rows is None or len(rows) == n_rows)
    missing = _missing(rows)
    assert not missing, f"docs/seed_reproduction.md lacks {name}'s rows: {missing}"


def test_guard_table_marks_the_lap_1_selections_outside():
    rows = guard_table_rows(
        json.loads((DOCS / "seed_reproduction" / "guard_valid_models.json").read_text())
    )
    assert [r.split(" | ")[0] for r in rows if "outside" in r] == [
        "| CB 1-1 + 31",
        "| eq. (4) 2-1 + 37",
    ]


def test_seed_table_rows_read_every_column():
    """The seed-mesh rows are made from the record's numbers: another peak is another row."""
    v = {"ncc_force": 0.9245, "ncc_force_whole": 0.9864, "peak_err": 0.0714}
    v |= {"impulse_err": -0.0082, "duration_err": -0.0272}
    r = {
        "model": "mvm-seed:1-1:37",
        "dof": {"b2": 46},
        "vs_full": v,
        "vs_theory": {"ncc_force": 0.4625, "ncc_force_whole": 0.6164},
        "max_contact_force_N": 755.6,
        "contact_intervals_s": [[0.0, 4.23e-4]],
        "max_penetration_m": 4.77e-8,
    }
    one = seed_mesh_table_rows({"body": "b2", "rows": [r]})[0]
    assert one == (
        "| eq. (4) 1-1 + 37 | 46 | 0.9245 / 0.9864 | +7.14 % | -0.82 % | -2.72 % | 755.6 N | "
        "423.0 us | 4.8e-8 m | 0.4625 / 0.6164 |"
    )
    assert (
        seed_mesh_table_rows({"body": "b2", "rows": [r | {"max_contact_force_N": 756.0}]})[0] != one
    )
