"""Quadratic faces of mesh files in contact (mesh/subfacets.py, read through mesh/io.py).

A gmsh box of tetra10 and one of hexahedron27 (straight-sided cells): the facet set of a
physical surface and the skin ``surface`` are linear sub-facets through every face node,
outward, tiling the face (areas to 1e-12: straight-sided sub-facets tile it exactly), each
sub-facet's nodes where the split puts them (a mid-side node at the middle of its parent edge,
to 1e-12 of the box size), and the node set of a surface group holds every node on that face.
About 1 s.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexmvm.mesh import CellType, read_mesh

gmsh = pytest.importorskip("gmsh")

LX, LY, LZ = 2.0, 1.0, 0.5


def _box(path, hexes: bool) -> None:
    """The box [0, LX] x [0, LY] x [0, LZ], second order; physical surface 'top' (z = LZ).
    hexes: a 4 x 2 x 2 transfinite grid of hexahedron27, else tetra10 of size 0.25."""
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("box")
        vol = gmsh.model.occ.addBox(0, 0, 0, LX, LY, LZ)
        gmsh.model.occ.synchronize()
        top = [
            t
            for d, t in gmsh.model.getEntities(2)
            if abs(gmsh.model.occ.getCenterOfMass(d, t)[2] - LZ) < 1e-9
        ]
        gmsh.model.addPhysicalGroup(2, top, name="top")
        gmsh.model.addPhysicalGroup(3, [vol], name="body")
        if hexes:
            for _, c in gmsh.model.getEntities(1):
                lo = gmsh.model.getBoundingBox(1, c)
                span = max(lo[3] - lo[0], lo[4] - lo[1], lo[5] - lo[2])
                gmsh.model.mesh.setTransfiniteCurve(c, 1 + round(span / 0.25))
            for _, s in gmsh.model.getEntities(2):
                gmsh.model.mesh.setTransfiniteSurface(s)
                gmsh.model.mesh.setRecombine(2, s)
            gmsh.model.mesh.setTransfiniteVolume(vol)
        else:
            gmsh.option.setNumber("Mesh.MeshSizeMax", 0.25)
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


def _area_normals(x: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """Area-weighted right-hand normals (n, 3) of triangles, or of quads by their diagonals."""
    p = x[facets]
    if facets.shape[1] == 3:
        return 0.5 * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return 0.5 * np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])


@pytest.mark.parametrize(("hexes", "cell_type"), [(False, CellType.TET10), (True, CellType.HEX27)])
def test_quadratic_faces_are_linear_subfacets_through_all_nodes(tmp_path, hexes, cell_type):
    path = tmp_path / "box.msh"
    _box(path, hexes)
    mesh = read_mesh(path)
    assert [b.cell_type for b in mesh.cells] == [cell_type]
    x = mesh.nodes
    top = mesh.facet_set("top")
    facets = top.quads if hexes else top.tris
    assert len(facets) and (len(top.tris) if hexes else len(top.quads)) == 0
    # on the face, outward (+z), tiling it
    assert np.allclose(x[facets, 2], LZ)
    n = _area_normals(x, facets)
    assert np.all(n[:, 2] > 0)
    assert n[:, 2].sum() == pytest.approx(LX * LY, rel=1e-12)
    # every node on the face is a contact node: the node set and the facets' nodes
    on_top = np.flatnonzero(np.isclose(x[:, 2], LZ))
    assert np.array_equal(top.nodes, on_top)
    assert np.array_equal(mesh.node_set("top"), on_top)
    corners = np.unique(mesh.cells[0].connectivity[:, : 8 if hexes else 4])
    assert np.setdiff1d(on_top, corners).size > 0.5 * on_top.size  # mid-side nodes: most
    # the split: grids of 0.125 (half the element) for hexes; for tets, sub-triangles of a
    # 6-node face have three sub-triangles with one parent corner each and one inner one,
    # whose nodes are all mid-side nodes at the middle of the outer sub-triangles' edges
    if hexes:
        h = np.ptp(x[facets], axis=1)
        assert np.allclose(np.sort(h[:, :2], axis=1), [0.125, 0.125], atol=1e-12)
    else:
        sub = facets.reshape(-1, 4, 3)
        for k in range(3):
            assert np.all(np.isin(sub[:, k], corners).sum(axis=1) == 1)
        assert not np.any(np.isin(sub[:, 3], corners))
        a, b, c = sub[:, 0, 0], sub[:, 1, 1], sub[:, 2, 2]
        for (i, j), mid in (((a, b), sub[:, 0, 1]), ((b, c), sub[:, 1, 2]), ((c, a), sub[:, 0, 2])):
            assert np.allclose(x[mid], 0.5 * (x[i] + x[j]), atol=1e-12 * LX)
    # the skin: the same split on every face, outward, the box's area
    skin = mesh.facet_set("surface")
    sf = skin.quads if hexes else skin.tris
    ns = _area_normals(x, sf)
    centre = np.array([LX, LY, LZ]) / 2
    assert np.all(np.einsum("ij,ij->i", ns, x[sf].mean(axis=1) - centre) > 0)
    assert np.abs(ns).sum() == pytest.approx(2 * (LX * LY + LX * LZ + LY * LZ), rel=1e-12)
    on_box = np.any(np.isclose(x, 0.0) | np.isclose(x, [LX, LY, LZ]), axis=1)
    assert np.array_equal(mesh.node_set("surface"), np.flatnonzero(on_box))
