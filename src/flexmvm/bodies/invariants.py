"""Inertia invariants of a floating-frame body (Shabana, *Dynamics of Multibody Systems*, ch. 5;
Schwertassek & Wallrapp's "standard input data").

With node positions in the body frame s_k = X_k + psi_k q, a consistent scalar mass matrix M_s
(n x n; the vector mass is kron(M_s, I3)) and the direction-wise basis blocks P_a = psi[a::3]
(n x nq, a = x, y, z), every configuration-dependent inertia term of the equations of motion is a
contraction of the constants below with q and q_dot: no loop over nodes in the time loop.

    m          = 1^T M_s 1                      total mass
    S0[a]      = 1^T M_s X_a                    first moment of the undeformed body (3,)
    S1[a]      = 1^T M_s P_a                    (3, nq)
    G0[a, b]   = X_a^T M_s X_b                  (3, 3)
    G1[a][b]   = X_a^T M_s P_b                  (nq,)
    G2[a][b]   = P_a^T M_s P_b                  (nq, nq), dense for reduced bases, sparse for full FE

G2[b][a] = G2[a][b]^T, and M_qq = psi^T M psi = sum_a G2[a][a].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp


@dataclass(frozen=True)
class InertiaInvariants:
    """Constant inertia data of one body (see module docstring for the definitions)."""

    mass: float
    S0: np.ndarray
    S1: np.ndarray
    G0: np.ndarray
    G1: tuple[tuple[np.ndarray, ...], ...]
    G2: tuple[tuple[np.ndarray | sp.spmatrix, ...], ...]
    M_qq: np.ndarray | sp.spmatrix
    # sparse bases only: M_s and P_a^T, so that the nine G2[b][a] q come from one M_s product
    Ms: sp.csr_matrix | None = None
    PT: tuple[sp.csr_matrix, ...] | None = None

    @property
    def nq(self) -> int:
        return self.S1.shape[1]


def direction_blocks(psi: np.ndarray | sp.spmatrix) -> list:
    """P_a = psi[a::3, :] for a = 0, 1, 2: (n, nq) each; csr if psi is sparse."""
    if sp.issparse(psi):
        psi = sp.csr_matrix(psi)
        return [psi[a::3, :].tocsr() for a in range(3)]
    return [np.ascontiguousarray(psi[a::3, :]) for a in range(3)]


def inertia_invariants(X: np.ndarray, M_scalar: sp.spmatrix, psi) -> InertiaInvariants:
    """Compute the invariants of (X (n,3) [m], M_scalar (n,n) [kg], psi (3n, nq)).

    Sparse psi (full FE) gives sparse G2 blocks; dense psi gives dense ones.
    """
    X = np.asarray(X, dtype=float)
    Ms = sp.csr_matrix(M_scalar)
    msum = np.asarray(Ms.sum(axis=1)).ravel()
    P = direction_blocks(psi)
    nq = P[0].shape[1]
    MsX = Ms @ X
    S0 = msum @ X
    S1 = np.vstack([np.asarray(P[a].T @ msum).ravel() for a in range(3)]).reshape(3, nq)
    G0 = X.T @ MsX
    G0 = 0.5 * (G0 + G0.T)
    G1 = tuple(tuple(np.asarray(P[b].T @ MsX[:, a]).ravel() for b in range(3)) for a in range(3))
    MsP = [Ms @ P[b] for b in range(3)]
    G2 = tuple(tuple(_product(P[a], MsP[b]) for b in range(3)) for a in range(3))
    M_qq = G2[0][0] + G2[1][1] + G2[2][2]
    M_qq = 0.5 * (M_qq + M_qq.T)
    if sp.issparse(M_qq):
        M_qq = sp.csr_matrix(M_qq)
    extra = {}
    if sp.issparse(psi):
        extra = {"Ms": Ms, "PT": tuple(sp.csr_matrix(P[a].T) for a in range(3))}
    return InertiaInvariants(float(msum.sum()), S0, S1, G0, G1, G2, M_qq, **extra)


def _product(Pa, MsPb):
    out = Pa.T @ MsPb
    return sp.csr_matrix(out) if sp.issparse(out) else np.asarray(out)
