"""Shape-function gradients and exact quadrature rules of the reference cells (mesh/cells).

Reference cells: [0, 1]^3 hexahedra (tensor-product Lagrange), the unit simplex, and the
triangle x [0, 1] wedge. Each rule integrates its cell's Jacobian determinant exactly.
"""

from __future__ import annotations

import numpy as np

#: meshio/VTK hexahedron8 corners on [0, 1]^3
HEX8_CORNERS = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
)

#: meshio/VTK hexahedron27 node k sits at parametric point HEX27_IJK[k] / 2: 8 corners,
#: 12 edge mid-nodes, face centres of x=0, x=1, y=0, y=1, z=0, z=1, then the cell centre.
HEX27_IJK = np.vstack(
    [
        2 * HEX8_CORNERS,
        [[1, 0, 0], [2, 1, 0], [1, 2, 0], [0, 1, 0], [1, 0, 2], [2, 1, 2], [1, 2, 2], [0, 1, 2]],
        [[0, 0, 1], [2, 0, 1], [2, 2, 1], [0, 2, 1]],
        [[0, 1, 1], [2, 1, 1], [1, 0, 1], [1, 2, 1], [1, 1, 0], [1, 1, 2], [1, 1, 1]],
    ]
).astype(np.int64)

TET_CORNERS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
#: meshio/VTK tetra corner edges; tetra10 mid-edge nodes 4..9 in this order
TET_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))
WEDGE_CORNERS = np.array(
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


def grad_hex(pts: np.ndarray, ijk: np.ndarray, order: int) -> np.ndarray:
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


def grad_tet4(pts: np.ndarray) -> np.ndarray:
    return np.broadcast_to(_BARY_GRAD, (len(pts), 4, 3)).copy()


def grad_tet10(pts: np.ndarray) -> np.ndarray:
    lam = np.column_stack([1 - pts.sum(axis=1), pts])
    g = np.empty((len(pts), 10, 3))
    g[:, :4] = (4 * lam - 1)[:, :, None] * _BARY_GRAD[None]
    a, b = np.array(TET_EDGES).T
    g[:, 4:] = 4 * (lam[:, b, None] * _BARY_GRAD[a] + lam[:, a, None] * _BARY_GRAD[b])
    return g


def grad_wedge6(pts: np.ndarray) -> np.ndarray:
    r, s, t = pts.T
    tri = np.stack([1 - r - s, r, s], axis=1)
    dtri = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])
    g = np.empty((len(pts), 6, 3))
    for lo, fac, dfac in ((0, 1 - t, -1.0), (3, t, 1.0)):
        g[:, lo : lo + 3, :2] = fac[:, None, None] * dtri[None]
        g[:, lo : lo + 3, 2] = dfac * tri
    return g


def gauss_cube(n: int) -> tuple[np.ndarray, np.ndarray]:
    """n x n x n Gauss-Legendre rule on [0, 1]^3."""
    x, w = np.polynomial.legendre.leggauss(n)
    x, w = (x + 1) / 2, w / 2
    g = np.stack(np.meshgrid(x, x, x, indexing="ij"), axis=-1).reshape(-1, 3)
    wg = (w[:, None, None] * w[None, :, None] * w[None, None, :]).ravel()
    return g, wg


def keast_tet() -> tuple[np.ndarray, np.ndarray]:
    """Degree-3 5-point rule on the unit tetrahedron (Keast 1986); weights sum to 1/6."""
    a, b = 1 / 2, 1 / 6
    pts = [[0.25, 0.25, 0.25], [b, b, b], [a, b, b], [b, a, b], [b, b, a]]
    return np.array(pts), np.array([-2 / 15] + [3 / 40] * 4)


def wedge_rule() -> tuple[np.ndarray, np.ndarray]:
    """Triangle degree-2 (3 points) x 2-point Gauss: exact for the wedge6 Jacobian."""
    tri = np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]])
    x, w = np.polynomial.legendre.leggauss(2)
    t, wt = (x + 1) / 2, w / 2
    pts = np.array([[r, s, tt] for tt in t for r, s in tri])
    return pts, np.repeat(wt, 3) / 6
