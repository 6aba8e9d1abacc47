"""The 4-node tetrahedron (meshio 'tetra', VTK_TETRA 10): linear on the unit simplex."""

from __future__ import annotations

from flexmvm.mesh.cells import shapes
from flexmvm.mesh.cells.spec import CellSpec, CellType

#: Corner faces, outward for a valid cell (right-hand rule).
FACES = ((0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2))
#: Abaqus C3D4 faces S1..S4 (mesh/abaqus.py).
ABAQUS_FACES = ((0, 1, 2), (0, 3, 1), (1, 3, 2), (2, 3, 0))

SPEC = CellSpec(
    cell_type=CellType.TET4,
    vtk_id=10,
    reference_nodes=shapes.TET_CORNERS,
    n_corners=4,
    faces=FACES,
    edges=shapes.TET_EDGES,
    shape_gradients=shapes.grad_tet4,
    quadrature=shapes.keast_tet,
    abaqus_faces=ABAQUS_FACES,
)
