"""The references of docs/seed_reproduction.md's material study are stored and are the ones
the studies were scored against (issue 51 item 4): each study's materials.json names, per
material, the provenance stamp of its full-FE reference and the SHA-256 of that reference's
history (studies.reference_run); the reference.json files under
docs/seed_reproduction/references/<mesh>/<material>/ (copied from the study directories) must
carry that stamp and that SHA-256, and the page's references table, its line of wall times and
its sentences on the gap to the theory are remade here from them. Reads JSON and Markdown only.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from flexmvm.results.summary_keys import with_current_keys

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs" / "seed_reproduction"
REFS = DOCS / "references"
PAGE = ROOT / "docs" / "seed_reproduction.md"
MESHES = ("seed_mesh", "default_mesh")
#: the striker's brass has table 2's Cu constants (the page says so)
STRIKER = "Cu"


def _json(path: Path) -> dict:
    return json.loads(path.read_text())


def _reference(mesh: str, material: str) -> dict:
    return _json(REFS / mesh / material / "reference.json")


def _page() -> str:
    return " ".join(PAGE.read_text().split())


@pytest.mark.parametrize("mesh", MESHES)
@pytest.mark.parametrize("kind", ("cb", "eq4"))
def test_stored_references_are_the_studies_references(mesh, kind):
    """Same stamp (code, libraries, resolved scenario) and same history bytes: both studies of
    a mesh were scored against the stored runs (the eq. (4) studies against the same runs as
    the Craig-Bampton ones)."""
    record = _json(DOCS / f"materials_{mesh}_{kind}.json")
    for material, prov in record["provenance"].items():
        ref = _reference(mesh, material)
        assert ref["provenance"] == prov["reference"], (mesh, kind, material)
        assert ref["history"]["sha256"] == prov["reference_sha256"], (mesh, kind, material)
        assert ref["identity"]["body"] == record["body"]


def _peak_and_end(mesh: str, material: str) -> tuple[float, float]:
    s = with_current_keys(_reference(mesh, material)["summary"])
    (start, end), *_ = s["contact_intervals_s"]
    assert start == 0.0
    return s["max_contact_force_interval_mean_N"], end


def _length_m(material: str) -> float:
    sc = _reference("seed_mesh", material)["identity"]["scenario"]
    return next(b for b in sc["bodies"] if b["name"] == "b2")["rod"]["length_m"]


def _materials() -> dict:
    """materials.json's materials in the seed's order (the page's), W, Cu, Al, PA6."""
    record = _json(DOCS / "materials_seed_mesh_cb.json")
    return {m: record["materials"][m] for m in record["seed_order"]}


def reference_rows(materials: dict) -> list[str]:
    """The references table, one row per material in ``materials``' order: per mesh the peak (0.1 N, % against the theory's peak to 0.1)
    and contact interval (1 us); the theory's peak and duration (materials.json); b2's share
    of the contact compliance, (1 - nu^2)/E over the sum with the striker's, its bar wave
    speed sqrt(E/rho) and wave return 2L/c2."""
    brass = materials[STRIKER]
    rows = []
    for m, t in materials.items():
        cells = []
        for mesh in MESHES:
            peak, end = _peak_and_end(mesh, m)
            err = 100 * (peak / t["theory_peak_force_N"] - 1)
            cells.append(f"{peak:.1f} N ({err:+.1f} %) | 0..{1e6 * end:.0f} us")
        c = [(1 - d["nu"] ** 2) / d["E_pa"] for d in (t, brass)]
        c2 = math.sqrt(t["E_pa"] / t["rho_kg_m3"])
        theory = f"{t['theory_peak_force_N']:.1f} N | {1e6 * t['theory_contact_duration_s']:.0f} us"
        rest = f"{c[0] / sum(c):.2f} | {c2:.0f} m/s | {2e6 * _length_m(m) / c2:.0f} us"
        rows.append(f"| {m} | {' | '.join(cells)} | {theory} | {rest} |")
    return rows


def gap_sentences(materials: dict) -> list[str]:
    """The wall times of the references (1 s) and how far they are from the theory: seed
    mesh, peak above and contact shorter (whole %); default mesh, the largest |gap| (0.1 %)."""
    out, gaps = [], {}
    for mesh in MESHES:
        walls = [_reference(mesh, m)["summary"]["wall_time_s"] for m in materials]
        out.append(f"{mesh.replace('_', ' ')} {min(walls):.0f}-{max(walls):.0f} s")
        peak, dur = [], []
        for m, t in materials.items():
            p, end = _peak_and_end(mesh, m)
            peak.append(100 * (p / t["theory_peak_force_N"] - 1))
            dur.append(100 * (end / t["theory_contact_duration_s"] - 1))
        gaps[mesh] = peak, dur
    peak, dur = gaps["seed_mesh"]
    out.append(
        f"peak +{min(peak):.0f} % to +{max(peak):.0f} % and contact "
        f"{-max(dur):.0f} % to {-min(dur):.0f} % shorter"
    )
    peak, dur = gaps["default_mesh"]
    out.append(
        f"agree with the theory to {max(map(abs, peak)):.1f} % in peak and "
        f"{max(map(abs, dur)):.1f} % in duration"
    )
    return out


def test_page_reference_table_is_the_stored_references():
    materials = _materials()
    page = _page()
    lines = reference_rows(materials) + gap_sentences(materials)
    missing = [line for line in lines if line not in page]
    assert not missing, f"docs/seed_reproduction.md lacks: {missing}"
    assert "seed_reproduction/references/" in page


def test_reference_rows_read_the_stored_numbers():
    """Another peak is another row (the row is made from the numbers, not copied)."""
    materials = _materials()
    one = reference_rows(materials)[0]
    assert one.startswith("| W | 1575.0 N (+13.7 %) | 0..595 us | 1404.3 N (+1.4 %)")
    other = {
        m: t | {"theory_peak_force_N": 1.01 * t["theory_peak_force_N"]}
        for m, t in materials.items()
    }
    assert reference_rows(other)[0] != one
