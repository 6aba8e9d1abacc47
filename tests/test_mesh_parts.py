"""Parts meshed with gmsh (flexmvm.mesh.parts) and the meshes of the shipped scenarios on them.
Tests that mesh need gmsh and are skipped without it; the rest run everywhere."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from flexmvm.errors import InputError
from flexmvm.mesh import CellType, mesh_volume, read_mesh
from flexmvm.mesh.parts import Refinement, arm, beam, block, main, sphere
from flexmvm.scenarios import load_scenario

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
CELL = {1: CellType.TET4, 2: CellType.TET10}


@pytest.fixture
def gmsh():
    return pytest.importorskip("gmsh")


def _area(fs, nodes):
    """Area [m^2] of a facet set's triangles."""
    p = nodes[fs.tris]
    return 0.5 * float(np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum())


@pytest.mark.parametrize("order", [1, 2])
def test_block_and_beam_volumes_and_groups(gmsh, tmp_path, order):
    """Flat-faced parts are meshed exactly: volume lx ly lz and L w h to 1e-12 (straight-sided
    tets, exact quadrature), tet4 or tet10 by ``order``; the beam's ``mid_top`` patch (patch_m x
    w) is part of ``top`` (L x w) too, ``end_b`` lies at x = L; the refinement makes elements
    near its point smaller than elsewhere."""
    m = read_mesh(block(tmp_path / "block.msh", 0.06, 0.05, 0.03, 0.015, order=order))
    assert [b.cell_type for b in m.cells] == [CELL[order]]
    assert mesh_volume(m) == pytest.approx(0.06 * 0.05 * 0.03, rel=1e-12)
    assert _area(m.facet_set("top"), m.nodes) == pytest.approx(0.06 * 0.05, rel=1e-12)
    assert np.allclose(m.nodes[m.node_set("bottom"), 2], -0.03)
    refine = Refinement((0.1, 0.0, 0.0), 1e-3, 2e-3, 8e-3)
    m = read_mesh(
        beam(
            tmp_path / "beam.msh", 0.2, 0.01, 0.012, 0.005, patch_m=0.02, order=order, refine=refine
        )
    )
    assert mesh_volume(m) == pytest.approx(0.2 * 0.01 * 0.012, rel=1e-12)
    assert _area(m.facet_set("top"), m.nodes) == pytest.approx(0.2 * 0.01, rel=1e-12)
    assert _area(m.facet_set("mid_top"), m.nodes) == pytest.approx(0.02 * 0.01, rel=1e-12)
    assert np.all(np.isin(m.node_set("mid_top"), m.node_set("top")))
    assert np.allclose(m.nodes[m.node_set("end_b"), 0], 0.2)
    conn = m.cells[0].connectivity[:, :4]
    edge = np.linalg.norm(m.nodes[conn[:, 1]] - m.nodes[conn[:, 0]], axis=1)
    near = np.linalg.norm(m.nodes[conn].mean(axis=1) - refine.point_m, axis=1) < 2e-3
    assert edge[near].mean() < 0.5 * edge[~near].mean()


@pytest.mark.parametrize(("order", "size", "bound"), [(1, 0.3, 0.3**2 / 2), (2, 0.3, 2e-3)])
def test_sphere_volume_within_faceting_error(gmsh, tmp_path, order, size, bound):
    """Sphere R = 1 with elements of size h = 0.3. tet4: the mesh is a polyhedron inscribed in
    the sphere; a flat triangle of circumradius rho under the sphere leaves a mean gap of about
    rho^2 / (4 R), with rho ~ h / sqrt(3) a relative volume deficit of ~3 rho^2 / (4 R^2) =
    h^2 / (4 R^2) = 2.3 %: asserted smaller than the sphere and within h^2 / (2 R^2) (margin 2
    for gmsh's edges longer than h). tet10: gmsh puts the midside nodes on the sphere, the faces
    are quadratic and the error falls to O(h^4) (here ~5e-4): asserted within 2e-3. The groups
    ``front`` (cap within 30 degrees of the -z pole) and ``back`` tile the skin."""
    m = read_mesh(sphere(tmp_path / "s.msh", 1.0, size, order=order))
    exact = 4.0 / 3.0 * math.pi
    err = mesh_volume(m) / exact - 1.0
    assert abs(err) <= bound
    if order == 1:
        assert err < 0
    skin, front, back = (m.facet_set(n) for n in ("surface", "front", "back"))
    assert front.n_facets + back.n_facets == skin.n_facets
    assert np.all(m.nodes[front.nodes, 2] <= -math.cos(math.radians(30)) + 1e-9)


@pytest.mark.parametrize("leg", [0.0, 0.03])
def test_arm_volume_and_pivot(gmsh, tmp_path, leg):
    """Arm (hub R = 12 mm with a hole r = 5 mm, bar 80 x 16 mm, 6 mm thick; straight or with a
    30 mm leg): volume = thickness x (hub disk + bar + leg - their overlaps - hole); its two
    circles are faceted with chords <= h, each polygon's area off by at most pi h^2 / 6
    (pi rho^2 (1 - sin(t)/t) ~ pi rho^2 t^2 / 6 with t = h / rho): asserted within twice that.
    The ``hub`` group is the hole's face (every node at r from the z axis), ``tip`` the free
    end face."""
    L, w, t, R, r, h = 0.08, 0.016, 0.006, 0.012, 0.005, 0.004
    m = read_mesh(arm(tmp_path / "arm.msh", L, w, t, R, r, h, leg_m=leg))
    overlap = quad(lambda x: 2 * min(w / 2, math.sqrt(max(R * R - x * x, 0.0))), 0.0, R)[0]
    area = math.pi * R**2 + L * w - overlap + (w * (leg + w) - w * w if leg else 0.0)
    expected = t * (area - math.pi * r**2)
    assert abs(mesh_volume(m) - expected) <= 2 * t * math.pi * h**2 / 6
    hub = m.nodes[m.node_set("hub")]
    assert np.allclose(np.hypot(hub[:, 0], hub[:, 1]), r, rtol=1e-6)
    tip = m.nodes[m.node_set("tip")]
    if leg:
        assert np.allclose(tip[:, 1], -w / 2 - leg)
    else:
        assert np.allclose(tip[:, 0], L)


def test_missing_gmsh_is_one_line(monkeypatch, tmp_path):
    """Without gmsh a part cannot be meshed: one-line InputError naming the dependency."""
    monkeypatch.setitem(sys.modules, "gmsh", None)
    with pytest.raises(InputError, match="optional dependency gmsh") as info:
        block(tmp_path / "b.msh", 1.0, 1.0, 1.0, 0.5)
    assert "\n" not in str(info.value)


def test_scenario_meshes_regenerate_small(gmsh, tmp_path, capsys):
    """``python -m flexmvm.mesh.parts DIR`` writes the meshes the shipped scenarios name, each
    under 2 MB, with the groups their contacts use."""
    assert main([str(tmp_path)]) == 0
    names = {p.name for p in tmp_path.iterdir()}
    for scenario in ("sphere_block", "sphere_beam", "arm_stop"):
        sc = load_scenario(SCENARIOS / f"{scenario}.toml")
        for body in sc.bodies:
            assert body.mesh_file.name in names
            assert (tmp_path / body.mesh_file.name).stat().st_size < 2e6
            assert body.mesh_file.stat().st_size < 2e6
        mesh = read_mesh(tmp_path / sc.body(sc.contacts[0].master_body).mesh_file.name)
        assert mesh.facet_set(sc.contacts[0].master_surface).n_facets > 0
    assert "wrote" in capsys.readouterr().out
