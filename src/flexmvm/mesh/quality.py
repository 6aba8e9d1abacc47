"""Mesh quality: Jacobian checks and volume by Gauss quadrature.

Reference cells use parametric coordinates in [0, 1] (hexahedra), the unit simplex (tetrahedra)
and triangle x [0, 1] (wedges); node order is meshio's (VTK for hexahedron, hexahedron27,
tetra, tetra10; gmsh's prism for wedge, i.e. the normal of triangle (0, 1, 2) by the right-hand
rule points towards triangle (3, 4, 5)). With these conventions a valid cell has a positive
Jacobian determinant det(dx/dxi) everywhere.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from flexmvm.errors import MeshError
from flexmvm.mesh.cells.shapes import HEX27_IJK  # noqa: F401  (hexahedron27 node k at HEX27_IJK[k] / 2; rod.py)
from flexmvm.mesh.mesh import CellType, Mesh

#: Relative Jacobian below which a cell counts as degenerate (det / size**3).
DEGENERATE_RELATIVE_DET = 1e-12


def quadrature(cell_type: CellType) -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 3) and weights (n,) integrating the cell's Jacobian determinant exactly
    (the cell type's rule, mesh/cells: Gauss 2x2x2 hexahedron, 3x3x3 hexahedron27, Keast
    degree 3 tetra and tetra10, triangle 3-point x Gauss 2 wedge)."""
    return cell_type.spec.quadrature()


def shape_gradients(cell_type: CellType, points: np.ndarray) -> np.ndarray:
    """Parametric gradients dN_a/dxi_j of the shape functions, shape (n_pts, n_nodes, 3)."""
    return cell_type.spec.shape_gradients(np.atleast_2d(np.asarray(points, dtype=float)))


def jacobian_determinants(
    nodes: np.ndarray, connectivity: np.ndarray, cell_type: CellType, points: np.ndarray
) -> np.ndarray:
    """det(dx/dxi) of every cell at parametric points: (n_cells, n_pts) [m^3 per unit xi^3]."""
    grads = shape_gradients(cell_type, points)
    out = np.empty((len(connectivity), len(grads)))
    chunk = 20000
    for lo in range(0, len(connectivity), chunk):
        x = nodes[connectivity[lo : lo + chunk]]
        jac = np.einsum("cni,pnj->cpij", x, grads)
        out[lo : lo + chunk] = np.linalg.det(jac)
    return out


def _check_points(cell_type: CellType) -> np.ndarray:
    ref = cell_type.spec.corners
    return np.vstack([ref, ref.mean(axis=0, keepdims=True), quadrature(cell_type)[0]])


def check_quality(mesh: Mesh, cell_name: Callable[[int, int], str] | None = None) -> None:
    """Raise MeshError for the first inverted or degenerate cell of the mesh.

    The Jacobian determinant of the isoparametric map is evaluated at the corner nodes, the
    centroid and the quadrature points of every cell. A cell fails if det <= 0 (inverted) or
    det < 1e-12 * size**3 (degenerate), size [m] = largest bounding-box extent of its nodes.
    Raises MeshError naming the cell type, the cell index within its block (or
    ``cell_name(block index, cell index)``, e.g. the file's element number) and the defect.
    """
    for k, block in enumerate(mesh.cells):
        conn = block.connectivity
        if len(conn) == 0:
            continue
        pts = _check_points(block.cell_type)
        det = jacobian_determinants(mesh.nodes, conn, block.cell_type, pts)
        x = mesh.nodes[conn]
        size = np.max(x.max(axis=1) - x.min(axis=1), axis=1)
        rel = det / np.maximum(size, np.finfo(float).tiny)[:, None] ** 3
        bad_cells = np.flatnonzero(np.any(rel < DEGENERATE_RELATIVE_DET, axis=1))
        if bad_cells.size:
            c = int(bad_cells[0])
            p = int(np.argmin(rel[c]))
            what = "inverted" if rel[c, p] < -DEGENERATE_RELATIVE_DET else "degenerate"
            name = f"{block.cell_type.value} cell {c}" if cell_name is None else cell_name(k, c)
            raise MeshError(
                f"{name} is {what}: Jacobian determinant "
                f"{det[c, p]:.3e} (relative {rel[c, p]:.1e}, expected > {DEGENERATE_RELATIVE_DET:g}) "
                f"at parametric point {tuple(np.round(pts[p], 3).tolist())}; "
                f"{len(bad_cells)} bad cell(s) in the block"
            )


def cell_volumes(mesh: Mesh) -> list[np.ndarray]:
    """Volume [m^3] of every cell, one array per cell block, by exact Gauss quadrature."""
    out = []
    for block in mesh.cells:
        pts, w = quadrature(block.cell_type)
        out.append(jacobian_determinants(mesh.nodes, block.connectivity, block.cell_type, pts) @ w)
    return out


def mesh_volume(mesh: Mesh) -> float:
    """Total volume [m^3] of the isoparametric geometry (exact quadrature of det J)."""
    return float(sum(v.sum() for v in cell_volumes(mesh)))
