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
from flexmvm.mesh.mesh import CellType, Mesh

#: Relative Jacobian below which a cell counts as degenerate (det / size**3).
DEGENERATE_RELATIVE_DET = 1e-12

_HEX8_CORNERS = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
)

#: meshio/VTK hexahedron27 node k sits at parametric point HEX27_IJK[k] / 2: 8 corners,
#: 12 edge mid-nodes, face centres of x=0, x=1, y=0, y=1, z=0, z=1, then the cell centre.
HEX27_IJK = np.vstack(
    [
        2 * _HEX8_CORNERS,
        [[1, 0, 0], [2, 1, 0], [1, 2, 0], [0, 1, 0], [1, 0, 2], [2, 1, 2], [1, 2, 2], [0, 1, 2]],
        [[0, 0, 1], [2, 0, 1], [2, 2, 1], [0, 2, 1]],
        [[0, 1, 1], [2, 1, 1], [1, 0, 1], [1, 2, 1], [1, 1, 0], [1, 1, 2], [1, 1, 1]],
    ]
).astype(np.int64)

_TET_CORNERS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
_TET10_EDGES = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]])
_WEDGE_CORNERS = np.array(
    [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1]], dtype=float
)
_BARY_GRAD = np.array([[-1.0, -1.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


def _lagrange_1d(x: np.ndarray, order: int) -> tuple[np.ndarray, np.ndarray]:
    """1D Lagrange basis on [0, 1] (nodes 0, 1 or 0, 1/2, 1): values and derivatives (n, order+1)."""
    if order == 1:
        return np.stack([1 - x, x], axis=1), np.stack([-np.ones_like(x), np.ones_like(x)], axis=1)
    val = np.stack([(1 - x) * (1 - 2 * x), 4 * x * (1 - x), x * (2 * x - 1)], axis=1)
    der = np.stack([4 * x - 3, 4 - 8 * x, 4 * x - 1], axis=1)
    return val, der


def _grad_hex(pts: np.ndarray, ijk: np.ndarray, order: int) -> np.ndarray:
    """Gradients (n_pts, n_nodes, 3) of a tensor-product hexahedron basis at pts (n_pts, 3)."""
    v, d = zip(*(_lagrange_1d(pts[:, k], order) for k in range(3)))
    i, j, k = ijk.T
    return np.stack(
        [
            d[0][:, i] * v[1][:, j] * v[2][:, k],
            v[0][:, i] * d[1][:, j] * v[2][:, k],
            v[0][:, i] * v[1][:, j] * d[2][:, k],
        ],
        axis=2,
    )


def _grad_tet4(pts: np.ndarray) -> np.ndarray:
    return np.broadcast_to(_BARY_GRAD, (len(pts), 4, 3)).copy()


def _grad_tet10(pts: np.ndarray) -> np.ndarray:
    lam = np.column_stack([1 - pts.sum(axis=1), pts])
    g = np.empty((len(pts), 10, 3))
    g[:, :4] = (4 * lam - 1)[:, :, None] * _BARY_GRAD[None]
    a, b = _TET10_EDGES.T
    g[:, 4:] = 4 * (lam[:, b, None] * _BARY_GRAD[a] + lam[:, a, None] * _BARY_GRAD[b])
    return g


def _grad_wedge6(pts: np.ndarray) -> np.ndarray:
    r, s, t = pts.T
    tri = np.stack([1 - r - s, r, s], axis=1)
    dtri = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])
    g = np.empty((len(pts), 6, 3))
    for lo, fac, dfac in ((0, 1 - t, -1.0), (3, t, 1.0)):
        g[:, lo : lo + 3, :2] = fac[:, None, None] * dtri[None]
        g[:, lo : lo + 3, 2] = dfac * tri
    return g


_GRADIENTS: dict[CellType, Callable[[np.ndarray], np.ndarray]] = {
    CellType.HEX8: lambda p: _grad_hex(p, _HEX8_CORNERS, 1),
    CellType.HEX27: lambda p: _grad_hex(p, HEX27_IJK, 2),
    CellType.TET4: _grad_tet4,
    CellType.TET10: _grad_tet10,
    CellType.WEDGE6: _grad_wedge6,
}


def _gauss_cube(n: int) -> tuple[np.ndarray, np.ndarray]:
    x, w = np.polynomial.legendre.leggauss(n)
    x, w = (x + 1) / 2, w / 2
    g = np.stack(np.meshgrid(x, x, x, indexing="ij"), axis=-1).reshape(-1, 3)
    wg = (w[:, None, None] * w[None, :, None] * w[None, None, :]).ravel()
    return g, wg


def _keast_tet() -> tuple[np.ndarray, np.ndarray]:
    """Degree-3 5-point rule on the unit tetrahedron (Keast 1986); weights sum to 1/6."""
    a, b = 1 / 2, 1 / 6
    pts = [[0.25, 0.25, 0.25], [b, b, b], [a, b, b], [b, a, b], [b, b, a]]
    return np.array(pts), np.array([-2 / 15] + [3 / 40] * 4)


def _wedge_rule() -> tuple[np.ndarray, np.ndarray]:
    """Triangle degree-2 (3 points) x 2-point Gauss: exact for the wedge6 Jacobian."""
    tri = np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]])
    x, w = np.polynomial.legendre.leggauss(2)
    t, wt = (x + 1) / 2, w / 2
    pts = np.array([[r, s, tt] for tt in t for r, s in tri])
    return pts, np.repeat(wt, 3) / 6


def quadrature(cell_type: CellType) -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 3) and weights (n,) integrating the cell's Jacobian determinant exactly.

    Gauss 2x2x2 (hexahedron), 3x3x3 (hexahedron27), Keast degree 3 (tetra, tetra10; the tetra10
    Jacobian is cubic), triangle 3-point x Gauss 2 (wedge).
    """
    if cell_type is CellType.HEX8:
        return _gauss_cube(2)
    if cell_type is CellType.HEX27:
        return _gauss_cube(3)
    if cell_type is CellType.WEDGE6:
        return _wedge_rule()
    return _keast_tet()


def _reference_nodes(cell_type: CellType) -> np.ndarray:
    """Parametric coordinates (n_corners, 3) of the corner nodes."""
    if cell_type in (CellType.HEX8, CellType.HEX27):
        return _HEX8_CORNERS.astype(float)
    if cell_type is CellType.WEDGE6:
        return _WEDGE_CORNERS
    return _TET_CORNERS


def shape_gradients(cell_type: CellType, points: np.ndarray) -> np.ndarray:
    """Parametric gradients dN_a/dxi_j of the shape functions, shape (n_pts, n_nodes, 3)."""
    return _GRADIENTS[cell_type](np.atleast_2d(np.asarray(points, dtype=float)))


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
    ref = _reference_nodes(cell_type)
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
