"""The 8-node hexahedron (meshio 'hexahedron', VTK_HEXAHEDRON 12): trilinear on [0, 1]^3."""

from __future__ import annotations

from flexmvm.mesh.cells import shapes
from flexmvm.mesh.cells.spec import CellSpec, CellType

#: Corner faces, outward for a valid cell (right-hand rule).
FACES = ((0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (0, 4, 7, 3))
#: Corner edges: bottom ring, top ring, then the four verticals.
EDGES: tuple[tuple[int, int], ...] = (
    (0, 1),
    (1, 2),
    (2, 3),
    (3, 0),
    (4, 5),
    (5, 6),
    (6, 7),
    (7, 4),
)
EDGES += ((0, 4), (1, 5), (2, 6), (3, 7))
#: Abaqus C3D8 faces S1..S6 (mesh/abaqus.py).
ABAQUS_FACES = ((0, 1, 2, 3), (4, 7, 6, 5), (0, 4, 5, 1), (1, 5, 6, 2), (2, 6, 7, 3), (3, 7, 4, 0))

SPEC = CellSpec(
    cell_type=CellType.HEX8,
    vtk_id=12,
    reference_nodes=shapes.HEX27_IJK[:8] / 2.0,
    n_corners=8,
    faces=FACES,
    edges=EDGES,
    shape_gradients=lambda p: shapes.grad_hex(p, shapes.HEX8_CORNERS, 1),
    quadrature=lambda: shapes.gauss_cube(2),
    abaqus_faces=ABAQUS_FACES,
)
