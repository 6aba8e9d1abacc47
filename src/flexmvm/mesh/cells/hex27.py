"""The 27-node hexahedron (meshio 'hexahedron27', VTK_TRIQUADRATIC_HEXAHEDRON 29):
triquadratic on [0, 1]^3; node k at shapes.HEX27_IJK[k] / 2 (8 corners, 12 mid-edge nodes,
face centres of x=0, x=1, y=0, y=1, z=0, z=1, then the cell centre)."""

from __future__ import annotations

from flexmvm.mesh.cells import hex8, shapes
from flexmvm.mesh.cells.spec import CellSpec, CellType

#: Mid-edge nodes: (corner, corner, mid-side node), meshio/VTK order (nodes 8..19).
EDGE_NODES = (
    (0, 1, 8),
    (1, 2, 9),
    (2, 3, 10),
    (3, 0, 11),
    (4, 5, 12),
    (5, 6, 13),
    (6, 7, 14),
    (7, 4, 15),
    (0, 4, 16),
    (1, 5, 17),
    (2, 6, 18),
    (3, 7, 19),
)
#: Face-centre nodes: (the face's four corners, centre node), VTK order.
FACE_NODES = (
    ((0, 3, 7, 4), 20),
    ((1, 2, 6, 5), 21),
    ((0, 1, 5, 4), 22),
    ((3, 2, 6, 7), 23),
    ((0, 1, 2, 3), 24),
    ((4, 5, 6, 7), 25),
)

SPEC = CellSpec(
    cell_type=CellType.HEX27,
    vtk_id=29,
    reference_nodes=shapes.HEX27_IJK / 2.0,
    n_corners=8,
    faces=hex8.FACES,
    edges=hex8.EDGES,
    shape_gradients=lambda p: shapes.grad_hex(p, shapes.HEX27_IJK, 2),
    quadrature=lambda: shapes.gauss_cube(3),
    edge_nodes=EDGE_NODES,
    face_nodes=FACE_NODES,
)
