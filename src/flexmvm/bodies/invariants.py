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

Cost: a dense psi (3n, nq) is viewed as the (n, 3 nq) array [P_x, P_y, P_z] (no copy), so
M_s P comes from one sparse product and the six blocks G2[a][b], b >= a, from three matrix
products; G2[b][a] is the transpose. A sparse psi takes the same route with sparse products.
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
    """Compute the invariants of (X (n,3) [m], M_scalar (n,n) [kg], psi (3n, nq) [-]).

    Sparse psi (full FE) gives sparse (csr) G2 blocks and M_qq and sets Ms, PT; dense psi
    gives dense ones. Units: mass [kg], S [kg m], G0 [kg m^2], G1 [kg m], G2 [kg].
    """
    X = np.asarray(X, dtype=float)
    Ms = sp.csr_matrix(M_scalar)
    msum = np.asarray(Ms.sum(axis=1)).ravel()
    MsX = Ms @ X
    S0 = msum @ X
    G0 = X.T @ MsX
    G0 = 0.5 * (G0 + G0.T)
    if sp.issparse(psi):
        S1, G1, G2, extra = _sparse_terms(Ms, msum, MsX, sp.csr_matrix(psi))
    else:
        S1, G1, G2 = _dense_terms(Ms, msum, MsX, np.asarray(psi, dtype=float))
        extra = {}
    M_qq = G2[0][0] + G2[1][1] + G2[2][2]
    M_qq = 0.5 * (M_qq + M_qq.T)
    if sp.issparse(M_qq):
        M_qq = sp.csr_matrix(M_qq)
    return InertiaInvariants(float(msum.sum()), S0, S1, G0, G1, G2, M_qq, **extra)


def _dense_terms(Ms: sp.csr_matrix, msum: np.ndarray, MsX: np.ndarray, psi: np.ndarray):
    """S1 (3, nq), G1 and G2 (nested 3 x 3 tuples) of a dense psi (3n, nq).

    psi is viewed as P = [P_x, P_y, P_z] (n, 3 nq); M_s P is one sparse product and the block
    row a of G2 (b >= a) one matrix product P_a^T (M_s P)[:, a nq:].
    """
    n, nq = Ms.shape[0], psi.shape[1]
    P = np.ascontiguousarray(psi).reshape(n, 3 * nq)
    S1 = (msum @ P).reshape(3, nq)
    G1x = (MsX.T @ P).reshape(3, 3, nq)  # G1x[a, b] = X_a^T M_s P_b
    G1 = tuple(tuple(G1x[a, b].copy() for b in range(3)) for a in range(3))
    MsP = Ms @ P
    G2: list[list] = [[None] * 3 for _ in range(3)]
    for a in range(3):
        row = P[:, a * nq : (a + 1) * nq].T @ MsP[:, a * nq :]
        for b in range(a, 3):
            G2[a][b] = np.ascontiguousarray(row[:, (b - a) * nq : (b - a + 1) * nq])
            if b > a:
                G2[b][a] = np.ascontiguousarray(G2[a][b].T)
    return S1, G1, tuple(tuple(r) for r in G2)


def _sparse_terms(Ms: sp.csr_matrix, msum: np.ndarray, MsX: np.ndarray, psi: sp.csr_matrix):
    """S1 (3, nq), G1, G2 (csr blocks) and the extra fields {Ms, PT} of a sparse psi (3n, nq)."""
    P = direction_blocks(psi)
    PT = tuple(sp.csr_matrix(P[a].T) for a in range(3))
    nq = psi.shape[1]
    S1 = np.vstack([PT[a] @ msum for a in range(3)]).reshape(3, nq)
    G1 = tuple(tuple(np.asarray(PT[b] @ MsX[:, a]).ravel() for b in range(3)) for a in range(3))
    MsP = [sp.csr_matrix(Ms @ P[b]) for b in range(3)]
    G2: list[list] = [[None] * 3 for _ in range(3)]
    for a in range(3):
        for b in range(a, 3):
            G2[a][b] = sp.csr_matrix(PT[a] @ MsP[b])
            if b > a:
                G2[b][a] = sp.csr_matrix(G2[a][b].T)
    return S1, G1, tuple(tuple(r) for r in G2), {"Ms": Ms, "PT": PT}


def leading_columns(inv: InertiaInvariants, m: int) -> InertiaInvariants:
    """The invariants of the basis psi[:, :m] (dense bases only): every q-indexed array cut to
    its first m entries, exactly what inertia_invariants gives for the cut basis up to round-off.
    """
    if inv.Ms is not None:
        raise ValueError("leading_columns: sparse (full FE) invariants cannot be cut")
    if not 0 <= m <= inv.nq:
        raise ValueError(f"leading_columns: m = {m} outside 0..{inv.nq}")
    G1 = tuple(tuple(g[:m].copy() for g in row) for row in inv.G1)
    G2 = tuple(tuple(np.ascontiguousarray(g[:m, :m]) for g in row) for row in inv.G2)
    return InertiaInvariants(
        inv.mass,
        inv.S0,
        np.ascontiguousarray(inv.S1[:, :m]),
        inv.G0,
        G1,
        G2,
        np.ascontiguousarray(inv.M_qq[:m, :m]),
    )
