"""A point of a body located in its tetrahedral elements: the element's nodes and their shape
function values there, so that a field is interpolated at the point as the FE model does.

For a tet with corners x0..x3 the barycentric coordinates l = (l0, l1, l2, l3) of p solve
[x1 - x0, x2 - x0, x3 - x0] (l1, l2, l3) = p - x0, l0 = 1 - l1 - l2 - l3 (exact for straight
edges; a tet10 with curved edges is taken by its corners). Shape functions (Zienkiewicz and
Taylor, The Finite Element Method, vol. 1, ch. 6): tet4 N_i = l_i; tet10, meshio/VTK order
(corners 0-3, then edges 01, 12, 02, 03, 13, 23), N_i = l_i (2 l_i - 1) at a corner and
N_ij = 4 l_i l_j on an edge. They sum to 1, so a rigid motion is carried exactly. A point on
the skin belongs to its face's element (l_i >= -INSIDE_TOL).
"""

from __future__ import annotations

import numpy as np

from flexmvm.mesh.mesh import CellType, Mesh

#: A point counts as inside a tet when every barycentric coordinate is at least -INSIDE_TOL
#: (a point on a face or given at rounded coordinates)
INSIDE_TOL = 1e-6
#: Tets tried, nearest centroids first
CANDIDATES = 32


def _barycentric(corners: np.ndarray, p: np.ndarray) -> np.ndarray:
    """(k, 4) barycentric coordinates of p in the k tets with corners (k, 4, 3)."""
    J = np.transpose(corners[:, 1:] - corners[:, :1], (0, 2, 1))  # (k, 3, 3), columns x_i - x0
    ok = np.abs(np.linalg.det(J)) > 0
    lam = np.full((len(corners), 4), -np.inf)
    if ok.any():
        rhs = (p - corners[ok, 0])[:, :, None]
        l123 = np.linalg.solve(J[ok], rhs)[:, :, 0]
        lam[ok] = np.column_stack([1.0 - l123.sum(axis=1), l123])
    return lam


def _shape(cell_type: CellType, lam: np.ndarray) -> np.ndarray:
    """Shape function values at barycentric coordinates lam (4,), in the cell's node order."""
    mids = cell_type.spec.edge_nodes  # (corner, corner, mid-side node), in node order
    if not mids:
        return lam.copy()
    corner = lam * (2.0 * lam - 1.0)
    edge = [4.0 * lam[i] * lam[j] for i, j, _ in mids]
    return np.concatenate([corner, edge])


def tet_weights(mesh: Mesh, point) -> tuple[np.ndarray, np.ndarray] | None:
    """(node ids, weights) of ``point`` [m] (3,) in the tet4/tet10 element that holds it
    (module doc), or None when no tetrahedral element of the mesh does."""
    p = np.asarray(point, dtype=float)
    best = None
    for block in mesh.cells:
        if block.cell_type.spec.n_corners != 4:  # not a tetrahedron
            continue
        conn = block.connectivity
        corners = mesh.nodes[conn[:, :4]]
        centre = corners.mean(axis=1)
        near = np.argsort(np.linalg.norm(centre - p, axis=1))[:CANDIDATES]
        lam = _barycentric(corners[near], p)
        worst = lam.min(axis=1)
        k = int(np.argmax(worst))
        if worst[k] >= -INSIDE_TOL and (best is None or worst[k] > best[0]):
            cell = near[k]
            best = (worst[k], conn[cell], _shape(block.cell_type, np.maximum(lam[k], 0.0)))
    if best is None:
        return None
    _, nodes, w = best
    return np.asarray(nodes, dtype=np.int64), w / w.sum()
