"""Shape-function gradients and weights at the integration points of every cell: the same
scikit-fem elements, isoparametric maps and Gauss rules as the stiffness of assembly.py, for
the stages that integrate a nonlinear stress (plasticity/).

For each cell block: node ids (ne, nloc) in skfem local order, N (ne, nloc, nqp), grad N
(ne, nloc, 3, nqp) [1/m] and dx = |det J| w (ne, nqp) [m^3]; sum_e sum_q B^T D_el B dx is
assembly.py's K.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.fe.assembly import block_basis, shape_arrays
from flexmvm.mesh.mesh import CellType, Mesh


@dataclass(frozen=True)
class BlockPoints:
    """Integration points of one cell block: cell_type, nodes (ne, nloc) node ids, values
    N (ne, nloc, nqp), grad (ne, nloc, 3, nqp) [1/m], dx (ne, nqp) [m^3]."""

    cell_type: CellType
    nodes: np.ndarray
    values: np.ndarray
    grad: np.ndarray
    dx: np.ndarray

    @property
    def n_points(self) -> int:
        return self.dx.size

    def coordinates(self, nodes_xyz: np.ndarray) -> np.ndarray:
        """Positions (ne * nqp, 3) [m] of the points, cell-major, from node positions (n, 3)."""
        xyz = np.einsum("eaq,eai->eqi", self.values, nodes_xyz[self.nodes])
        return xyz.reshape(-1, 3)


def integration_points(mesh: Mesh) -> tuple[BlockPoints, ...]:
    """The integration points of every non-empty cell block of ``mesh`` (module doc).
    Raises MeshError as assembly.assemble does (unmappable cell type, non-conforming mesh)."""
    out = []
    for block in mesh.cells:
        if len(block.connectivity) == 0:
            continue
        basis, dof_to_node = block_basis(mesh.nodes, block)
        nodes = dof_to_node[basis.element_dofs.T]
        values, grad, dx = shape_arrays(basis, slice(None))
        out.append(BlockPoints(block.cell_type, nodes, values, np.ascontiguousarray(grad), dx))
    return tuple(out)
