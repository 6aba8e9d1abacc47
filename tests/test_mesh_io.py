"""meshio reading/writing (flexmvm.mesh.io)."""

import meshio
import numpy as np
import pytest

from flexmvm.errors import MeshError
from flexmvm.mesh import CellType, RodSpec, mesh_volume, read_mesh, rod_mesh, write_mesh

gmsh = pytest.importorskip("gmsh")


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


def _gmsh_box(path, order: int = 1) -> None:
    """Mesh the box [0, 2] x [0, 1] x [0, 0.5] with tets; physical surface 'top' (z = 0.5)."""
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
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.25)
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
    mesh = read_mesh(path, node_sets={"apex": [4]})
    assert np.array_equal(mesh.nodes, pts[1:])
    assert mesh.cells[0].connectivity.tolist() == [[0, 1, 2, 3]]
    assert mesh.node_set("apex").tolist() == [3]
    meshio.write(path, meshio.Mesh(pts, [("tetra", np.array([[1, 3, 2, 4]]))]))
    with pytest.raises(MeshError, match="tetra cell 0 is inverted"):
        read_mesh(path)
