"""Rod mesh generator (flexmvm.mesh.rod) and mesh quality checks (flexmvm.mesh.quality)."""

import math

import numpy as np
import pytest

from flexmvm.errors import InputError, MeshError
from flexmvm.mesh import (
    CellBlock,
    CellType,
    EndShape,
    Mesh,
    RodSpec,
    check_quality,
    graded_lengths,
    mesh_volume,
    rod_mesh,
)
from flexmvm.mesh.quality import HEX27_IJK

FLAT = RodSpec()
HEMI = RodSpec(end_a=EndShape.HEMISPHERE)


@pytest.fixture(scope="module")
def flat():
    return rod_mesh(FLAT)


@pytest.fixture(scope="module")
def hemi():
    return rod_mesh(HEMI)


def _quadratic_arc_area_error(n_arcs: int) -> float:
    """Relative area error of a circle drawn by n quadratic arcs with all three nodes on it.

    Area under one arc of half-angle a = triangle (O, P0, P2) + 4/3 triangle (P0, P1, P2).
    """
    a = np.pi / n_arcs
    arc = np.sin(a) * np.cos(a) + 4 / 3 * np.sin(a) * (1 - np.cos(a))
    return (arc - a) / a


def test_counts_are_consistent(flat):
    """Nodes = layers x section nodes; cells = axial elements x section quads; the default
    section (2x2 core, 3 rings) has 25 + 6*16 = 121 nodes and 4 + 3*8 = 28 quads."""
    m = flat.mesh
    assert flat.n_laps == 1 + 2 + 2 * 3
    assert m.n_nodes == 121 * flat.n_layers
    assert m.n_cells == 28 * (flat.n_layers - 1) // 2
    assert m.cells[0].cell_type is CellType.HEX27
    assert np.array_equal(np.unique(m.cells[0].connectivity), np.arange(m.n_nodes))
    assert flat.node_layer.min() == 1 and flat.node_layer.max() == flat.n_layers
    per_lap = np.bincount(flat.node_lap)[1:] // flat.n_layers
    assert per_lap.tolist() == [1, 8, 16] + [16] * 6


def test_volume_flat_rod(flat):
    """Volume of a flat-ended rod is pi r^2 L up to the quadratic arcs of the circle.

    16 circle nodes (8 quadratic arcs): the arc area error is -7.78e-4 relative (computed in
    closed form below); the measured mesh volume must equal it to 1e-9 and be within 1e-3.
    """
    r, L = FLAT.radius_m, FLAT.length_m
    err = mesh_volume(flat.mesh) / (math.pi * r * r * L) - 1
    assert abs(err) < 1e-3
    assert err == pytest.approx(_quadratic_arc_area_error(8), abs=1e-9)


def test_volume_hemispherical_rod(hemi):
    """Volume with a hemispherical end A: pi r^2 (L - r) + 2/3 pi r^3 within 1e-3 relative
    (measured -8.0e-4: the cylinder's arc error plus the cap's quadratic meridians)."""
    r, L = HEMI.radius_m, HEMI.length_m
    exact = math.pi * r * r * (L - r) + 2 / 3 * math.pi * r**3
    assert abs(mesh_volume(hemi.mesh) / exact - 1) < 1e-3


def test_short_rod_both_caps_volume():
    """Short rod (L = 6 r) with two caps, so the caps weigh ~30 % of the volume.

    The cap block's outer ring spans 62 degrees of meridian with one quadratic element: the cap
    volume is low by ~3.1e-3 of the hemisphere volume; total measured -1.66e-3, bound 2e-3.
    """
    spec = RodSpec(length_m=0.06, end_a="hemisphere", end_b="hemisphere")
    rm = rod_mesh(spec)
    check_quality(rm.mesh)
    r, L = spec.radius_m, spec.length_m
    exact = math.pi * r * r * (L - 2 * r) + 4 / 3 * math.pi * r**3
    assert abs(mesh_volume(rm.mesh) / exact - 1) < 2e-3


@pytest.mark.parametrize("spec", [FLAT, HEMI, RodSpec(end_b="hemisphere", core_elements=1)])
def test_jacobians_positive(spec):
    """check_quality passes: every Jacobian (corners, centre, Gauss points) is positive."""
    check_quality(rod_mesh(spec).mesh)


def test_selection(flat, hemi):
    """selection(1, 1) is the single axis node at x = 0 (the apex for a hemisphere); sizes of
    i-j selections follow the section's lap counts; a too large i raises InputError."""
    for rm in (flat, hemi):
        sel = rm.selection(1, 1)
        assert sel.tolist() == rm.mesh.node_set("end_a_centre").tolist()
        assert np.allclose(rm.mesh.nodes[sel[0]], 0.0)
    per_lap = [1, 8, 16] + [16] * 6
    assert len(flat.selection(3, 2)) == 3 * 9
    assert len(flat.selection(5, 9)) == 5 * sum(per_lap)
    assert len(flat.selection(flat.n_layers, flat.n_laps)) == flat.mesh.n_nodes
    with pytest.raises(InputError, match=f"1..{flat.n_layers}"):
        flat.selection(99, 1)
    with pytest.raises(InputError, match="1..9"):
        flat.selection(1, 0)


def test_reference_nodes_on_axes_at_end_b(flat):
    """The circle at end B has nodes on the +y, +z, -y, -z axes (exact zeros in the other
    coordinate) for the 3-2-1 reference condition."""
    m = flat.mesh
    ids = np.intersect1d(m.node_set("end_b"), m.node_set("side"))
    yz = m.nodes[ids, 1:] / FLAT.radius_m
    for target in ([1, 0], [0, 1], [-1, 0], [0, -1]):
        assert np.any(np.all(yz == target, axis=1))
    assert np.allclose(m.nodes[ids, 0], FLAT.length_m)


def _facet_normals(mesh, name):
    q = mesh.nodes[mesh.facet_set(name).quads]
    return np.cross(q[:, 2] - q[:, 0], q[:, 3] - q[:, 1]), q.mean(axis=1)


@pytest.mark.parametrize("which", ["flat", "hemi"])
def test_facet_normals_outward(which, flat, hemi):
    """Facet normals point outward: -x at a flat end A (away from the sphere centre (r, 0, 0)
    for a cap), +x at end B, radially outward on the side; facets cover end faces exactly."""
    rm = {"flat": flat, "hemi": hemi}[which]
    m, r = rm.mesh, rm.spec.radius_m
    n, c = _facet_normals(m, "end_a")
    out = np.array([-1.0, 0, 0]) if which == "flat" else c - [r, 0, 0]
    assert np.all(np.einsum("ij,ij->i", n, np.broadcast_to(out, n.shape)) > 0)
    n, _ = _facet_normals(m, "end_b")
    assert np.all(n[:, 0] > 0) and np.allclose(n[:, 1:], 0, atol=1e-12)
    n, c = _facet_normals(m, "side")
    assert np.all(np.einsum("ij,ij->i", n[:, 1:], c[:, 1:]) > 0)
    for name in ("end_a", "end_b", "side"):
        assert np.array_equal(m.facet_set(name).nodes, m.node_set(name))
    assert m.facet_set("end_a").n_facets == 4 * 28
    assert rm.faces9["side"].shape == (8 * (rm.n_layers - 1) // 2, 9)


def test_side_and_end_nodes_on_geometry(flat, hemi):
    """Side nodes lie on the cylinder (or its cap edge), cap surface nodes on the sphere."""
    for rm in (flat, hemi):
        p = rm.mesh.nodes[rm.mesh.node_set("side")]
        assert np.allclose(np.hypot(p[:, 1], p[:, 2]), rm.spec.radius_m, rtol=1e-12)
    r = HEMI.radius_m
    p = hemi.mesh.nodes[hemi.mesh.node_set("end_a")]
    assert np.allclose(np.linalg.norm(p - [r, 0, 0], axis=1), r, rtol=1e-12)
    assert np.all(p[:, 0] <= r + 1e-15)


def test_axial_grading(flat, hemi):
    """First axial element at end A has first_element_m (on the axis); lengths grow by at most
    `growth` and never exceed max_element_m; the rod length is met exactly."""
    for rm in (flat, hemi):
        axis = rm.mesh.nodes[rm.selection(rm.n_layers, 1), 0]
        ell = np.diff(axis[::2])
        assert ell[0] == pytest.approx(rm.spec.first_element_m, rel=1e-12)
        assert np.all(ell <= rm.spec.max_element_m * (1 + 1e-12))
        assert np.all(ell[1:] / ell[:-1] <= rm.spec.growth * (1 + 1e-9))
        assert axis[-1] == pytest.approx(rm.spec.length_m, rel=1e-15)
    ell = graded_lengths(1.0, 0.3e-3, 1.6, 0.04)
    assert ell.sum() == pytest.approx(1.0, rel=1e-14) and len(ell) == 34


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"radius_m": -1.0}, "radius_m"),
        ({"length_m": float("nan")}, "length_m"),
        ({"growth": 0.9}, "growth"),
        ({"n_rings": 0}, "n_rings"),
        ({"core_elements": 1.5}, "core_elements"),
        ({"core_half_width_m": 0.006}, "core_half_width_m"),
        ({"length_m": 0.015, "end_a": "hemisphere"}, "length_m"),
        ({"end_b": "cone"}, "end_b"),
        ({"cap_depth_m": 0.0}, "cap_depth_m"),
    ],
)
def test_spec_validation(kwargs, field):
    """Invalid specs raise a one-line InputError naming the field."""
    with pytest.raises(InputError, match=field) as info:
        RodSpec(**kwargs)
    assert "\n" not in str(info.value)


def _unit_hex27() -> np.ndarray:
    return HEX27_IJK / 2.0


def test_inverted_hex_raises():
    """Swapping two corner nodes of a hex27 inverts it: MeshError naming the type and cell."""
    x = np.vstack([_unit_hex27(), _unit_hex27() + [1.0, 0, 0]])
    conn = np.vstack([np.arange(27), 27 + np.arange(27)])
    check_quality(Mesh(x, (CellBlock(CellType.HEX27, conn),)))
    conn[1, [0, 1]] = conn[1, [1, 0]]
    with pytest.raises(MeshError, match=r"hexahedron27 cell 1 is inverted"):
        check_quality(Mesh(x, (CellBlock(CellType.HEX27, conn),)))


def test_flat_tet_raises():
    """A tetrahedron with four coplanar nodes is degenerate (det = 0): MeshError naming it."""
    x = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.3, 0.3, 0.0]])
    with pytest.raises(MeshError, match=r"tetra cell 0 is (degenerate|inverted)"):
        check_quality(Mesh(x, (CellBlock(CellType.TET4, [[0, 1, 2, 3]]),)))
    x[3, 2] = 1e-3
    check_quality(Mesh(x, (CellBlock(CellType.TET4, [[0, 1, 2, 3]]),)))


def test_volume_of_affine_cells():
    """mesh_volume is exact for affine cells: unit cube split as hex8, wedge6 and tet4 pieces,
    each mapped by the same affine map A: volume = det(A) to 1e-12."""
    rng = np.random.default_rng(1)
    a = np.eye(3) + 0.2 * rng.standard_normal((3, 3))
    cube = np.array(
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
    )
    x = cube @ a.T
    wedges = CellBlock(CellType.WEDGE6, [[0, 1, 3, 4, 5, 7], [1, 2, 3, 5, 6, 7]])
    for cells in ((CellBlock(CellType.HEX8, [np.arange(8)]),), (wedges,)):
        assert mesh_volume(Mesh(x, cells)) == pytest.approx(np.linalg.det(a), rel=1e-12)
