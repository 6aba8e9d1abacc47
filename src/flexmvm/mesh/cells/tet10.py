"""The 10-node tetrahedron (meshio 'tetra10', VTK_QUADRATIC_TETRA 24): quadratic on the unit
simplex; corners 0-3, then mid-edge nodes of edges 01, 12, 20, 03, 13, 23."""

from __future__ import annotations

import numpy as np

from flexmvm.mesh.cells import shapes, tet4
from flexmvm.mesh.cells.spec import CellSpec, CellType

SPEC = CellSpec(
    cell_type=CellType.TET10,
    vtk_id=24,
    reference_nodes=np.vstack(
        [shapes.TET_CORNERS, shapes.TET_CORNERS[np.array(shapes.TET_EDGES)].mean(axis=1)]
    ),
    n_corners=4,
    faces=tet4.FACES,
    edges=shapes.TET_EDGES,
    shape_gradients=shapes.grad_tet10,
    # Keast degree 3: the tetra10 Jacobian is cubic
    quadrature=shapes.keast_tet,
    abaqus_faces=tet4.ABAQUS_FACES,  # C3D10: the corners of C3D4's
    edge_nodes=tuple((a, b, 4 + k) for k, (a, b) in enumerate(shapes.TET_EDGES)),
)
