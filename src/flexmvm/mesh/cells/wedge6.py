"""The 6-node wedge (meshio 'wedge', VTK_WEDGE 13): linear triangle x [0, 1]. VTK numbers the
triangles the other way round (meshio -> VTK node order 0, 2, 1, 3, 5, 4)."""

from __future__ import annotations

from flexmvm.mesh.cells import shapes
from flexmvm.mesh.cells.spec import CellSpec, CellType

SPEC = CellSpec(
    cell_type=CellType.WEDGE6,
    vtk_id=13,
    reference_nodes=shapes.WEDGE_CORNERS,
    n_corners=6,
    faces=((0, 2, 1), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (0, 3, 5, 2)),
    edges=((0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5)),
    shape_gradients=shapes.grad_wedge6,
    quadrature=shapes.wedge_rule,
    vtk_order=(0, 2, 1, 3, 5, 4),
    abaqus_faces=((0, 1, 2), (3, 5, 4), (0, 3, 4, 1), (1, 4, 5, 2), (2, 5, 3, 0)),  # C3D6
)
