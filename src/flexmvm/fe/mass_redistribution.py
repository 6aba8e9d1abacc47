"""Mass redistribution on the contact boundary (Khenous, Laborde and Renard 2008; Hager,
Hueeber and Wohlmuth 2008): the nodes that carry contact get no mass, so an implicit scheme
without numerical damping (Moreau-Jean at theta = 1/2) does not make them ring from step to
step: a massless contact node has no velocity of its own to jump at an impact, its motion is
the quasi-static response of the body under the contact impulse.

The mass taken from the contact nodes (their rows and columns of the scalar consistent mass
matrix) is put on the diagonal of their neighbours (the nodes coupled to them in M), so that
the body keeps its mass, its first moment (centre of mass) and its second moment X^T M X
(inertia tensor) exactly: Khenous et al.'s conditions. The diagonal d >= 0 is the lumped
share of each neighbour (its coupling row sums, and the contact node's row sum spread over its
neighbours by |M_ij|), then every node off the boundary gets the least change of its diagonal,
relative to its own lumped mass, that restores the 10 moments (the inward move of the
boundary's mass shifts the centre of mass by ~ its mass x half an element). The redistributed matrix is positive semi-definite (a contact node has zero mass);
with the stiffness of a supported body, M + theta^2 h^2 K stays positive definite.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from flexmvm.errors import InputError

#: Largest moment correction on a node's diagonal, relative to its lumped mass: small enough
#: that the consistent matrix stays positive definite off the boundary.
MAX_RELATIVE_CHANGE = 1e-2


def moments(M_scalar: sp.spmatrix, X: np.ndarray) -> np.ndarray:
    """(10,) mass, first moments (3) and second moments xx, yy, zz, xy, xz, yz of a scalar
    mass matrix (n, n) [kg] on nodes X (n, 3) [m]: 1^T M 1, X^T M 1, X^T M X."""
    M = sp.csr_matrix(M_scalar)
    m1, MX = np.asarray(M.sum(axis=1)).ravel(), M @ X
    J = X.T @ MX
    return np.array([m1.sum(), *(X.T @ m1), J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2]])


def _moment_rows(X: np.ndarray) -> np.ndarray:
    """(10, k): the moments of unit masses at the nodes X (k, 3) (one column per node)."""
    x, y, z = X.T
    return np.vstack([np.ones(len(X)), x, y, z, x * x, y * y, z * z, x * y, x * z, y * z])


def redistribute_mass(M_scalar: sp.spmatrix, X: np.ndarray, nodes) -> sp.csr_matrix:
    """The scalar mass matrix (n, n) with no mass on ``nodes`` (their rows and columns zero)
    and the same mass, first and second moments, the difference on the diagonal of the nodes
    coupled to them and a moment correction on every node (module doc). InputError if a node
    is outside the mesh, or if the correction would exceed MAX_RELATIVE_CHANGE."""
    M = sp.csr_matrix(M_scalar, dtype=float)
    n = M.shape[0]
    B = np.unique(np.asarray(nodes, dtype=np.int64))
    if B.size == 0:
        return M
    if B[0] < 0 or B[-1] >= n:
        raise InputError(
            f"mass redistribution: node {int(B[-1] if B[-1] >= n else B[0])} is "
            f"outside the mesh (0..{n - 1})"
        )
    on_b = np.zeros(n, bool)
    on_b[B] = True
    keep = sp.diags((~on_b).astype(float))
    M_kept = sp.csr_matrix(keep @ M @ keep)
    removed = M - M_kept
    target = moments(removed, X)
    # neighbours: coupled to a boundary node, not on the boundary
    coupling = sp.csr_matrix(abs(M[B]))
    nb = np.unique(coupling.indices)
    nb = nb[~on_b[nb]]
    if nb.size < 10:
        raise InputError(
            f"mass redistribution: the {B.size} contact nodes have {nb.size} "
            "neighbours off the contact surface; at least 10 are needed to keep "
            "the mass and its moments"
        )
    # each neighbour takes its coupling to the boundary, plus the boundary rows' own sums
    # spread over their neighbours by |M_ij|
    rows_b = np.asarray(removed[B].sum(axis=1)).ravel()  # (|B|,) boundary row sums
    C = coupling[:, nb]  # (|B|, |nb|)
    share = sp.diags(1.0 / np.maximum(np.asarray(C.sum(axis=1)).ravel(), 1e-300)) @ C
    d = np.zeros(n)
    d[nb] = np.asarray(removed[nb][:, B].sum(axis=1)).ravel() + share.T @ rows_b
    # That moves the boundary's mass inwards: the centre of mass and the inertia shift by
    # ~ (mass of the boundary layer) x (half an element). The least change of every node's
    # diagonal relative to its own lumped mass restores the 10 moments exactly.
    free = np.flatnonzero(~on_b)
    lumped = np.asarray(M_kept.sum(axis=1)).ravel()[free]
    A = _moment_rows(X[free])
    y = np.linalg.lstsq((A * lumped) @ A.T, target - A @ d[free], rcond=None)[0]
    change = lumped * (A.T @ y)
    worst = float(np.abs(change / lumped).max())
    if worst > MAX_RELATIVE_CHANGE:
        share = float(target[0] / max(lumped.sum() + target[0], 1e-300))
        raise InputError(
            f"mass redistribution: keeping the moments needs a change of "
            f"{worst:.2g} of a node's mass (at most {MAX_RELATIVE_CHANGE:g}): the "
            f"{B.size} contact nodes carry {100 * share:.2g} % of the body's mass; "
            "expected a contact surface the size of the contact (a patch about "
            "the expected contact point, e.g. a gmsh physical group) or "
            "redistribute_mass = false"
        )
    d[free] += change
    out = M_kept + sp.diags(d)
    return sp.csr_matrix(out)
