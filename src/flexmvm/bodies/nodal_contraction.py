"""The G2 contractions of a basis that selects nodal DOFs (full FE), in compact form.

A full-FE body's basis psi (3n, nq) has one entry 1.0 per column: coordinate k is component
c_k of node n_k's displacement (the floating frame's reference condition removes a few). Then
P_a = psi[a::3] (bodies.invariants) maps q to the n-vector of a-components, and the contraction
L(x)[a, b] = G2[b][a] x = P_b^T M_s P_a x (bodies.body.FlexibleBody.contractions) is

    L(x)[a, b, k] = y_a[n_k] if c_k = b else 0,        y_a = M_s P_a x,

so the three n-vectors Y(x) = (y_0, y_1, y_2) (3, n) hold all of it: 3 n numbers instead of
the 9 nq of L (the seed rods: 0.2 MB instead of 1.9 MB), one product of the scalar mass M_s
with three columns, and no scatter into nine blocks. Likewise G1[a][b][k] = (M_s X)[n_k, a]
if c_k = b (bodies.invariants._sparse_terms), so C = G1 + L(q) (FlexibleBody.inertia_terms) is
C[a][b][k] = Cq[a, n_k] if c_k = b, with Cq = (M_s X)^T + Y(q).

The integrator (integrate.moreau_jean) carries Y(q) and Y(q_dot) of such bodies instead of L;
bodies.momentum.momentum_terms_nodal takes them. FlexibleBody.carried_contractions,
contraction_trace, inertia_terms and rotational_coupling accept either form.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numba
import numpy as np
import scipy.sparse as sp


# fastmath without "reassoc": with it LLVM vectorises the row sums with gathers of U[j], which
# the development machine's cores run slowly (a call ~1.7x slower; the results differ by
# round-off only: docs/notes/2026-11-27-comment-measurements.md)
@numba.njit(nogil=True, cache=True, fastmath={"contract"})
def _compact(indptr, indices, data, node, comp, x, U, Y):  # pragma: no cover - compiled
    """Y[a] = M_s U[:, a], U[n_k, c_k] = x_k (U zeroed here), M_s given as csr arrays."""
    U[:] = 0.0
    for k in range(x.shape[0]):
        U[node[k], comp[k]] = x[k]
    for i in range(indptr.shape[0] - 1):
        a0 = a1 = a2 = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            m = data[p]
            j = indices[p]
            a0 += m * U[j, 0]
            a1 += m * U[j, 1]
            a2 += m * U[j, 2]
        Y[0, i] = a0
        Y[1, i] = a1
        Y[2, i] = a2


@numba.njit(nogil=True, cache=True)
def _gather(Y, node, comp, out):  # pragma: no cover - compiled
    """out[k] = Y[comp[k], node[k]]."""
    for k in range(node.shape[0]):
        out[k] = Y[comp[k], node[k]]


@numba.njit(nogil=True, cache=True)
def _antisymmetric(Cq, node, comp, out):  # pragma: no cover - compiled
    """out[:, k] = [C[a][b][k] - C[b][a][k]] over cyclic (c, a, b): with c_k = comp[k],
    c1, c2 = c_k + 1, c_k + 2 (mod 3): out[c1, k] = Cq[c2, n_k], out[c2, k] = -Cq[c1, n_k],
    out[c_k, k] = 0."""
    for k in range(node.shape[0]):
        c = comp[k]
        n = node[k]
        c1 = (c + 1) % 3
        c2 = (c + 2) % 3
        out[c, k] = 0.0
        out[c1, k] = Cq[c2, n]
        out[c2, k] = -Cq[c1, n]


@dataclass(frozen=True)
class NodalContraction:
    """The compact contraction of a DOF-selecting basis: `__call__(x)` -> Y(x) (3, n)."""

    node: np.ndarray  # (nq,) node of each coordinate
    comp: np.ndarray  # (nq,) component (0, 1, 2) of each coordinate
    Ms: sp.csr_matrix  # (n, n) scalar mass [kg]
    MsX: np.ndarray  # (n, 3) M_s X [kg m]

    @classmethod
    def of(cls, psi, Ms: sp.csr_matrix | None, X: np.ndarray) -> NodalContraction | None:
        """The contraction of psi if it selects nodal DOFs (one 1.0 per column, each DOF at
        most once) and M_s is known, else None."""
        if Ms is None or not sp.issparse(psi) or psi.shape[1] == 0:
            return None
        pc = sp.csc_matrix(psi)
        pc.sum_duplicates()
        if (
            pc.nnz != pc.shape[1]
            or np.any(np.diff(pc.indptr) != 1)
            or np.any(pc.data != 1.0)
            or np.unique(pc.indices).size != pc.nnz
        ):
            return None
        dof = pc.indices.astype(np.int64)
        Ms = sp.csr_matrix(Ms)
        Ms.sort_indices()
        return cls(dof // 3, dof % 3, Ms, np.ascontiguousarray(Ms @ X, dtype=float))

    @property
    def n_nodes(self) -> int:
        return self.Ms.shape[0]

    @functools.cached_property
    def dof(self) -> np.ndarray:
        """(nq,) the DOF 3 n_k + c_k each coordinate selects."""
        return 3 * self.node + self.comp

    def __call__(self, x: np.ndarray) -> np.ndarray:
        Y = np.empty((3, self.n_nodes))
        U = np.empty((self.n_nodes, 3))
        _compact(
            self.Ms.indptr,
            self.Ms.indices,
            self.Ms.data,
            self.node,
            self.comp,
            np.ascontiguousarray(x, dtype=float),
            U,
            Y,
        )
        return Y

    def expand(self, Y: np.ndarray) -> np.ndarray:
        """L (3, 3, nq) of Y."""
        nq = self.node.shape[0]
        L = np.zeros((3, 3, nq))
        k = np.arange(nq)
        for a in range(3):
            L[a, self.comp, k] = Y[a, self.node]
        return L

    def trace(self, Y: np.ndarray) -> np.ndarray:
        """L[0, 0] + L[1, 1] + L[2, 2] = M_qq x (M_qq = sum_a G2[a][a])."""
        out = np.empty(self.node.shape[0])
        _gather(Y, self.node, self.comp, out)
        return out

    def first_moment_matrix(self, Y: np.ndarray) -> np.ndarray:
        """Cq = (M_s X)^T + Y (3, n) for Y = Y(q): C[a][b][k] = Cq[a, n_k] if c_k = b."""
        return self.MsX.T + Y

    def antisymmetric(self, Cq: np.ndarray) -> np.ndarray:
        """[C[a][b] - C[b][a]] over cyclic (c, a, b), (3, nq), for C given by Cq."""
        out = np.empty((3, self.node.shape[0]))
        _antisymmetric(np.ascontiguousarray(Cq), self.node, self.comp, out)
        return out

    def scattered(self, q: np.ndarray) -> np.ndarray:
        """Q (n, 3), Q[n_k, c_k] = q_k (the displacement field of q)."""
        Q = np.zeros((self.n_nodes, 3))
        Q[self.node, self.comp] = q
        return Q
