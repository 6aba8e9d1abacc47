"""meshio reading/writing (flexmvm.mesh.io); the gmsh tests are skipped without gmsh."""

import warnings

import meshio
import numpy as np
import pytest

from flexmvm.errors import MeshError
from flexmvm.mesh import CellType, RodSpec, mesh_volume, read_mesh, rod_mesh, write_mesh
from flexmvm.mesh.io import MeshWarning


def test_rod_round_trip_vtu(tmp_path):
    """Writing the hemispherical rod to .vtu and reading it back preserves nodes (bitwise: VTU
    stores float64), hexahedron27 connectivity, node sets (as point-data masks) and point data;
    the write is atomic: no temporary file is left beside the result."""
    rm = rod_mesh(RodSpec(length_m=0.2, end_a="hemisphere"))
    path = tmp_path / "rod.vtu"
    u = rm.mesh.nodes * 1e-3
    write_mesh(path, rm.mesh, point_data={"u": u}, cell_data={"id": np.arange(rm.mesh.n_cells)})
    assert [p.name for p in tmp_path.iterdir()] == ["rod.vtu"]
    back = read_mesh(path)
    assert np.array_equal(back.nodes, rm.mesh.nodes)
    assert back.cells[0].cell_type is CellType.HEX27
    assert np.array_equal(back.cells[0].connectivity, rm.mesh.cells[0].connectivity)
    for name, ids in rm.mesh.node_sets.items():
        assert np.array_equal(back.node_set(name), ids)
    raw = meshio.read(path)
    assert np.array_equal(raw.point_data["u"], u)
    assert np.array_equal(raw.cell_data["id"][0], np.arange(rm.mesh.n_cells))


def _gmsh_box(path, order: int = 1, extra_groups: bool = False, version: float = 4.1) -> None:
    """Mesh the box [0, 2] x [0, 1] x [0, 0.5] with tets; physical surface 'top' (z = 0.5);
    extra_groups: also 'top2' (the same face again), 'side' (y = 0: overlaps nothing),
    'empty' (no entity) and a second physical volume 'body2' over the same volume."""
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("box")
        vol = gmsh.model.occ.addBox(0, 0, 0, 2, 1, 0.5)
        gmsh.model.occ.synchronize()
        top = [
            tag
            for dim, tag in gmsh.model.getEntities(2)
            if abs(gmsh.model.occ.getCenterOfMass(dim, tag)[2] - 0.5) < 1e-9
        ]
        gmsh.model.addPhysicalGroup(2, top, name="top")
        gmsh.model.addPhysicalGroup(3, [vol], name="body")
        if extra_groups:
            side = [
                tag
                for dim, tag in gmsh.model.getEntities(2)
                if abs(gmsh.model.occ.getCenterOfMass(dim, tag)[1]) < 1e-9
            ]
            gmsh.model.addPhysicalGroup(2, top, name="top2")
            gmsh.model.addPhysicalGroup(2, side, name="side")
            gmsh.model.addPhysicalGroup(2, [], name="empty")
            gmsh.model.addPhysicalGroup(3, [vol], name="body2")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.25)
        gmsh.option.setNumber("Mesh.MshFileVersion", version)
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(order)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


@pytest.mark.parametrize(("order", "cell_type"), [(1, CellType.TET4), (2, CellType.TET10)])
def test_gmsh_tets_with_named_surface(tmp_path, order, cell_type):
    """A gmsh box mesh gives tetra (tetra10) cells and a facet set 'top' whose facets lie on
    z = 0.5 with outward (+z) normals, covering the face area 2 x 1 to 1e-12; its nodes form a
    node set; the volume is 1 to 1e-12 (straight-sided cells, exact quadrature)."""
    path = tmp_path / "box.msh"
    _gmsh_box(path, order)
    mesh = read_mesh(path)
    assert [b.cell_type for b in mesh.cells] == [cell_type]
    assert mesh_volume(mesh) == pytest.approx(1.0, rel=1e-12)
    top = mesh.facet_set("top")
    assert len(top.quads) == 0 and len(top.tris) > 0
    p = mesh.nodes[top.tris]
    assert np.allclose(p[:, :, 2], 0.5)
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert np.all(n[:, 2] > 0)
    assert 0.5 * n[:, 2].sum() == pytest.approx(2.0, rel=1e-12)
    assert np.array_equal(mesh.node_set("top"), top.nodes)
    used = np.unique(np.concatenate([b.connectivity.ravel() for b in mesh.cells]))
    assert np.array_equal(used, np.arange(mesh.n_nodes))


def test_missing_file_raises(tmp_path):
    """A file that does not exist: one-line MeshError naming the file."""
    with pytest.raises(MeshError, match="does not exist") as info:
        read_mesh(tmp_path / "nope.msh")
    assert "\n" not in str(info.value)


def test_surface_only_file_raises(tmp_path):
    """A file with only triangles has no volume cells: MeshError saying so."""
    path = tmp_path / "tri.vtu"
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
    meshio.write(path, meshio.Mesh(pts, [("triangle", np.array([[0, 1, 2]]))]))
    with pytest.raises(MeshError, match="no volume cells"):
        read_mesh(path)


def test_unreadable_and_unsupported_raise(tmp_path):
    """Garbage content and an unsupported volume type (pyramid) give one-line MeshErrors."""
    bad = tmp_path / "bad.vtu"
    bad.write_text("not a mesh\n")
    with pytest.raises(MeshError, match="cannot read") as info:
        read_mesh(bad)
    assert "\n" not in str(info.value)
    pyr = tmp_path / "pyr.vtu"
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 1]], dtype=float)
    meshio.write(pyr, meshio.Mesh(pts, [("pyramid", np.array([[0, 1, 2, 3, 4]]))]))
    with pytest.raises(MeshError, match="unsupported cell type 'pyramid'"):
        read_mesh(pyr)


def test_unused_nodes_dropped_and_inverted_cell_rejected(tmp_path):
    """Nodes used by no volume cell are dropped (ids renumbered); an inverted tet is rejected
    by the quality check on reading."""
    pts = np.array([[9, 9, 9], [0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    path = tmp_path / "tet.vtu"
    meshio.write(path, meshio.Mesh(pts, [("tetra", np.array([[1, 2, 3, 4]]))]))
    with pytest.warns(MeshWarning):
        mesh = read_mesh(path, node_sets={"apex": [4]})
    assert np.array_equal(mesh.nodes, pts[1:])
    assert mesh.cells[0].connectivity.tolist() == [[0, 1, 2, 3]]
    assert mesh.node_set("apex").tolist() == [3]
    meshio.write(path, meshio.Mesh(pts[1:], [("tetra", np.array([[0, 2, 1, 3]]))]))
    with pytest.raises(MeshError, match="tetra element 1 .*is inverted"):
        read_mesh(path)


def _tiny_target():
    """The tiny study case's target rod (tests/data/tiny_impact.toml, body b2): hexahedron27."""
    from pathlib import Path

    from flexmvm.scenarios import load_scenario

    sc = load_scenario(Path(__file__).parent / "data" / "tiny_impact.toml")
    return rod_mesh(sc.body("b2").rod.spec()).mesh


def test_duplicated_cell_refused(tmp_path):
    """The issue's case: the tiny case's target rod written with one hexahedron27 twice (which
    raised the peak contact force by 10.6 %) is refused in one line naming the file and the
    cell; without the copy the same file reads back with every cell once."""
    mesh = _tiny_target()
    conn = mesh.cells[0].connectivity
    path = tmp_path / "target.vtu"
    meshio.write(path, meshio.Mesh(mesh.nodes, [("hexahedron27", np.vstack([conn, conn[3:4]]))]))
    with pytest.raises(
        MeshError,
        match=r"target.vtu.*hexahedron27 element 4 is written 2 times "
        r"\(also element \d+; no physical group;",
    ) as info:
        read_mesh(path)
    assert "\n" not in str(info.value)
    meshio.write(path, meshio.Mesh(mesh.nodes, [("hexahedron27", conn)]))
    assert read_mesh(path).n_cells == len(conn)


def test_duplicated_cell_in_another_order_refused(tmp_path):
    """Two tets on the same four nodes in different orders (both positive: an even permutation)
    cannot be told apart: refused, naming both orders."""
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    path = tmp_path / "two.vtu"
    meshio.write(path, meshio.Mesh(pts, [("tetra", np.array([[0, 1, 2, 3], [1, 2, 0, 3]]))]))
    with pytest.raises(
        MeshError, match="elements 1 and 2 have the same nodes in a different order"
    ):
        read_mesh(path)


def test_folded_cells_refused(tmp_path):
    """Two valid tets on the same side of their shared face overlap (a folded mesh): refused;
    the same two tets on opposite sides read, with a skin of 6 outward triangles."""
    pts = np.array(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.2, 0.2, 0.5], [0, 0, -1]], dtype=float
    )
    path = tmp_path / "fold.vtu"
    meshio.write(path, meshio.Mesh(pts[:5], [("tetra", np.array([[0, 1, 2, 3], [0, 1, 2, 4]]))]))
    with pytest.raises(MeshError, match="cells 1 and 2 .* lie on the same side"):
        read_mesh(path)
    meshio.write(
        path, meshio.Mesh(pts[[0, 1, 2, 3, 5]], [("tetra", np.array([[0, 1, 2, 3], [0, 2, 1, 4]]))])
    )
    mesh = read_mesh(path)
    skin = mesh.facet_set("surface")
    assert len(skin.tris) == 6 and len(skin.quads) == 0
    p = mesh.nodes[skin.tris]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert np.all(np.einsum("ij,ij->i", n, p.mean(axis=1) - mesh.nodes.mean(axis=0)) > 0)


def test_unused_nodes_stated(tmp_path):
    """A node used by no cell is dropped and a MeshWarning states how many and which."""
    pts = np.array([[9, 9, 9], [0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    path = tmp_path / "tet.vtu"
    meshio.write(path, meshio.Mesh(pts, [("tetra", np.array([[1, 2, 3, 4]]))]))
    with pytest.warns(
        MeshWarning,
        match=r"1 node\(s\) used by no volume cell dropped "
        r"\(file ids 0\)",
    ):
        read_mesh(path)
    meshio.write(path, meshio.Mesh(pts[1:], [("tetra", np.array([[0, 1, 2, 3]]))]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_mesh(path)


def _box_facets(mesh):
    """Boundary facets of the box mesh by plane: {(axis, value): (n_facets, area [m^2])}."""
    p = mesh.nodes[mesh.facet_set("surface").tris]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    out = {}
    for axis, hi in ((0, 2.0), (1, 1.0), (2, 0.5)):
        for value, sign in ((0.0, -1), (hi, 1)):
            on = np.all(np.isclose(p[:, :, axis], value), axis=1)
            assert np.all(sign * n[on, axis] > 0)  # outward
            out[axis, value] = (int(on.sum()), 0.5 * float(np.abs(n[on, axis]).sum()))
    return out


@pytest.mark.parametrize("version", [4.1, 2.2])
def test_gmsh_overlapping_groups_keep_all_members(tmp_path, version):
    """gmsh physical groups sharing entities (MSH 4.1: one element, two tags; MSH 2.2: the
    element written once per group): 'top' and 'top2' both hold the whole top face; the two
    physical volumes over one volume do not double a cell (volume 1 m^3 to 1e-12, every cell
    once); 'side' (y = 0) is its own face."""
    path = tmp_path / "box.msh"
    _gmsh_box(path, extra_groups=True, version=version)
    mesh = read_mesh(path)
    assert mesh_volume(mesh) == pytest.approx(1.0, rel=1e-12)
    keys = np.sort(mesh.cells[0].connectivity, axis=1)
    assert len(np.unique(keys, axis=0)) == len(keys)
    top, top2 = mesh.facet_set("top"), mesh.facet_set("top2")
    assert np.array_equal(top.tris, top2.tris)
    p = mesh.nodes[top.tris]
    assert 0.5 * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])[:, 2].sum() == pytest.approx(2.0)
    assert np.allclose(mesh.nodes[mesh.node_set("side"), 1], 0.0)
    assert np.array_equal(mesh.node_set("body"), np.arange(mesh.n_nodes))
    assert np.array_equal(mesh.node_set("body2"), np.arange(mesh.n_nodes))


def test_gmsh_empty_group_is_empty_not_unknown(tmp_path):
    """A physical group with no entity: asking for it says 'empty', a name never defined
    says 'unknown'."""
    path = tmp_path / "box.msh"
    _gmsh_box(path, extra_groups=True)
    mesh = read_mesh(path)
    with pytest.raises(MeshError, match="surface 'empty' is empty"):
        mesh.facet_set("empty")
    with pytest.raises(MeshError, match="node set 'empty' is empty"):
        mesh.node_set("empty")
    with pytest.raises(MeshError, match="unknown surface 'nothing'"):
        mesh.facet_set("nothing")


@pytest.mark.parametrize("order", [1, 2])
def test_surface_set_is_the_boundary(tmp_path, order):
    """The facet set 'surface' is the whole skin of the box: on each of its six faces the
    facets are outward and cover the face's area (to 1e-12), 'top' is the part on z = 0.5, and
    node set 'surface' is every node on the boundary (tet10 mid-side nodes included: each
    6-node face is 4 linear sub-triangles, 4 times the facets of the tet4 mesh's count per
    face)."""
    path = tmp_path / "box.msh"
    _gmsh_box(path, order)
    mesh = read_mesh(path)
    faces = _box_facets(mesh)
    assert sum(n for n, _ in faces.values()) == mesh.facet_set("surface").n_facets
    areas = {
        (0, 0.0): 0.5,
        (0, 2.0): 0.5,
        (1, 0.0): 1.0,
        (1, 1.0): 1.0,
        (2, 0.0): 2.0,
        (2, 0.5): 2.0,
    }
    for key, area in areas.items():
        assert faces[key][1] == pytest.approx(area, rel=1e-12)
    assert faces[2, 0.5][0] == mesh.facet_set("top").n_facets
    x = mesh.nodes
    on_box = np.any(np.isclose(x, 0.0) | np.isclose(x, [2.0, 1.0, 0.5]), axis=1)
    assert np.array_equal(mesh.node_set("surface"), np.flatnonzero(on_box))
    assert np.array_equal(mesh.node_set("top"), np.flatnonzero(np.isclose(x[:, 2], 0.5)))
    if order == 2:
        corners = np.unique(mesh.cells[0].connectivity[:, :4])
        assert not np.all(np.isin(mesh.node_set("top"), corners))  # mid-side nodes are in


def test_rod_skin_is_its_three_surfaces(tmp_path):
    """A rod mesh (hexahedron27) read back from .vtu passes every integrity check and its
    skin 'surface' is its end_a, end_b and side surfaces together: the rod's facet sets split
    each hexahedron27 face into 4 quads through its midside nodes, and read_mesh splits the
    skin's faces the same way (mesh/subfacets.py): the same sub-quads, in the same winding
    (outward). The rod mesh itself has the skin too: facet set and node set 'surface', the
    three together."""
    rm = rod_mesh(RodSpec(length_m=0.2, end_a="hemisphere"))
    path = tmp_path / "rod.vtu"
    write_mesh(path, rm.mesh)
    back = read_mesh(path)
    parts = np.unique(
        np.concatenate([rm.mesh.facet_set(s).nodes for s in ("end_a", "end_b", "side")])
    )
    assert np.all(np.isin(back.facet_set("surface").nodes, parts))
    assert np.array_equal(rm.mesh.facet_set("surface").nodes, parts)
    assert np.array_equal(
        rm.mesh.node_set("surface"),
        np.unique(np.concatenate([rm.mesh.node_set(s) for s in ("end_a", "end_b", "side")])),
    )
    assert (
        back.facet_set("surface").n_facets
        == rm.mesh.facet_set("surface").n_facets
        == sum(rm.mesh.facet_set(s).n_facets for s in ("end_a", "end_b", "side"))
    )
    assert np.array_equal(back.node_set("surface"), parts)

    def cyclic(quads):  # each quad from its smallest node id: same winding, same rows
        start = np.argmin(quads, axis=1)
        rolled = np.array([np.roll(q, -k) for q, k in zip(quads, start)])
        return rolled[np.lexsort(rolled.T[::-1])]

    assert np.array_equal(
        cyclic(back.facet_set("surface").quads), cyclic(rm.mesh.facet_set("surface").quads)
    )


def test_abaqus_sets_by_name(tmp_path):
    """Other meshio formats: an Abaqus .inp's element sets of triangles become facet sets
    (oriented outward: 'slope' is the face x + y + z = 1 of the upper tet, normal +(1, 1, 1)),
    overlapping sets keep every member ('both' holds 'slope' too), a set of volume cells
    ('lower') the node set of its nodes, an NSET ('apex') a node set."""
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    none = np.zeros(0, dtype=int)
    m = meshio.Mesh(
        pts,
        [
            ("tetra", np.array([[0, 1, 2, 3], [0, 2, 1, 4]])),
            ("triangle", np.array([[1, 3, 2], [0, 3, 1]])),
        ],
        cell_sets={
            "slope": [none, np.array([0])],
            "both": [none, np.array([0, 1])],
            "lower": [np.array([1]), none],
        },
        point_sets={"apex": np.array([3])},
    )
    path = tmp_path / "two.inp"
    meshio.write(path, m)
    mesh = read_mesh(path)
    slope = mesh.nodes[mesh.facet_set("slope").tris[0]]
    assert np.cross(slope[1] - slope[0], slope[2] - slope[0]) @ np.ones(3) > 0
    assert mesh.facet_set("both").n_facets == 2
    assert mesh.node_set("lower").tolist() == [0, 1, 2, 4]
    assert mesh.node_set("apex").tolist() == [3]
    assert mesh.facet_set("surface").n_facets == 6


@pytest.mark.parametrize(("tags", "kept"), [((1, 2), True), ((1, 1), False)])
def test_copies_in_two_physical_volumes_kept_once(tmp_path, tags, kept):
    """MSH 2.2 writes an element once per physical volume it is in: two copies of a tet with
    different physical tags are one element in two groups (kept once, volume 1/6, each group's
    node set has its nodes); two copies with the same tag are a true duplicate, refused."""
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    conn = np.array([[0, 1, 2, 3], [0, 1, 2, 3]])
    m = meshio.Mesh(
        pts,
        [("tetra", conn)],
        cell_data={"gmsh:physical": [np.array(tags)], "gmsh:geometrical": [np.array([1, 1])]},
        field_data={"a": np.array([1, 3]), "b": np.array([2, 3])},
    )
    path = tmp_path / "two.msh"
    meshio.write(path, m, file_format="gmsh22", binary=False)
    if not kept:
        with pytest.raises(
            MeshError, match="tetra element 1 is written 2 times .*both in physical group 1"
        ):
            read_mesh(path)
        return
    mesh = read_mesh(path)
    assert mesh.n_cells == 1
    assert mesh_volume(mesh) == pytest.approx(1 / 6, rel=1e-14)
    assert mesh.node_set("a").tolist() == mesh.node_set("b").tolist() == [0, 1, 2, 3]
