"""Supernodal LDL^T solves with SuperLU's factor of a symmetric positive definite matrix.

For an SPD matrix A factored by SuperLU with a symmetric ordering and diagonal pivots
(fe.modes.SPD_LU: perm_r = perm_c = p, no pivoting), P A P^T = L U with U = D L^T up to
round-off (measured 1.5e-16 of max |U| on the b2 rod's W = M + (theta h)^2 K), so

    A^-1 b = P^T L^-T D^-1 L^-1 P b

needs only L and D. L is stored by supernodes (runs of columns with one row structure below
their diagonal block; 1,912 of mean width 13 on that 25,041-DOF rod): a dense triangle and a
dense row-major rectangle per supernode, with the rectangle's row indices once, so a
solve streams 8 bytes per entry of L twice (forward and backward) instead of SuperLU's L and U
with their indices, and several right-hand sides share one pass over the factor (SuperLU's
solve costs k times one solve for k right-hand sides). The kernels release the GIL: two
bodies' solves run on two threads (integrate.moreau_jean). Sparse-direct background: Davis,
"Direct Methods for Sparse Linear Systems" (SIAM 2006), ch. 4 and 9 (supernodes).
"""

from __future__ import annotations

import numba
import numpy as np
import scipy.sparse as sp

from flexmvm.errors import SolverError
from flexmvm.fe.modes import superlu_spd

#: A factor is accepted when its solve of a random right-hand side agrees with SuperLU's to
#: this (relative, max norm); the two differ by round-off only (measured ~1e-15).
CHECK_RTOL = 1e-10


@numba.njit(nogil=True, cache=True)
def _supernodes(Lp, Li, n):  # pragma: no cover - compiled
    """Start columns of the fundamental supernodes of the unit lower triangular L (CSC,
    sorted, diagonal stored): column j + 1 joins column j's supernode when the rows of
    column j below its diagonal are j + 1 followed by those of column j + 1."""
    starts = np.empty(n + 1, np.int64)
    starts[0] = 0
    ns = 1
    for j in range(n - 1):
        a0 = Lp[j] + 1            # skip the diagonal
        b0 = Lp[j + 1] + 1
        la = Lp[j + 1] - a0
        lb = Lp[j + 2] - b0
        same = la == lb + 1 and la > 0 and Li[a0] == j + 1
        if same:
            for t in range(lb):
                if Li[a0 + 1 + t] != Li[b0 + t]:
                    same = False
                    break
        if not same:
            starts[ns] = j + 1
            ns += 1
    starts[ns] = n
    return starts[: ns + 1]


@numba.njit(cache=True)
def _pack(Lp, Li, Lx, starts):  # pragma: no cover - compiled
    """Dense blocks of every supernode: the w x w unit lower triangle (row-major, strictly
    lower part used) and the r x w rectangle below it (row-major), in one value array."""
    ns = starts.shape[0] - 1
    t_off = np.empty(ns + 1, np.int64)
    b_off = np.empty(ns + 1, np.int64)
    r_off = np.empty(ns + 1, np.int64)
    t_off[0] = b_off[0] = r_off[0] = 0
    tv = 0
    bv = 0
    rv = 0
    for s in range(ns):
        c0 = starts[s]
        w = starts[s + 1] - c0
        r = (Lp[c0 + 1] - Lp[c0]) - w    # rows below the triangle (column c0 holds them all)
        tv += w * w
        bv += r * w
        rv += r
        t_off[s + 1] = tv
        b_off[s + 1] = bv
        r_off[s + 1] = rv
    tri = np.zeros(tv)
    rect = np.empty(bv)
    rows = np.empty(rv, np.int32)
    for s in range(ns):
        c0 = starts[s]
        w = starts[s + 1] - c0
        r = r_off[s + 1] - r_off[s]
        p0 = Lp[c0] + w
        for i in range(r):
            rows[r_off[s] + i] = Li[p0 + i]
        for a in range(w):
            col = c0 + a
            p = Lp[col] + 1            # below the diagonal: rows c0 + a + 1 .. c0 + w - 1, then R
            for a2 in range(a + 1, w):
                tri[t_off[s] + a2 * w + a] = Lx[p]
                p += 1
            for i in range(r):
                rect[b_off[s] + i * w + a] = Lx[p]
                p += 1
    return t_off, b_off, r_off, tri, rect, rows


@numba.njit(nogil=True, cache=True)
def _ldl_solve(starts, t_off, b_off, r_off, tri, rect, rows, d, perm, b, out):  # pragma: no cover
    """out = A^-1 b for b, out (n, k) C-ordered (P A P^T = L D L^T, (P b)[perm[i]] = b[i])."""
    n, k = b.shape
    ns = starts.shape[0] - 1
    y = np.empty((n, k))
    for i in range(n):
        pi = perm[i]
        for c in range(k):
            y[pi, c] = b[i, c]
    wmax = 0
    for s in range(ns):
        wmax = max(wmax, starts[s + 1] - starts[s])
    ys = np.empty((k, wmax))
    # forward: L z = P b
    for s in range(ns):
        c0 = starts[s]
        w = starts[s + 1] - c0
        T = tri[t_off[s]: t_off[s + 1]]
        for a in range(w):
            for c in range(k):
                acc = y[c0 + a, c]
                for a2 in range(a):
                    acc -= T[a * w + a2] * ys[c, a2]
                ys[c, a] = acc
        for a in range(w):
            for c in range(k):
                y[c0 + a, c] = ys[c, a]
        B = rect[b_off[s]: b_off[s + 1]]
        r0 = r_off[s]
        for i in range(r_off[s + 1] - r0):
            ri = rows[r0 + i]
            for c in range(k):
                acc = 0.0
                for a in range(w):
                    acc += B[i * w + a] * ys[c, a]
                y[ri, c] -= acc
    # D^-1
    for i in range(n):
        di = 1.0 / d[i]
        for c in range(k):
            y[i, c] *= di
    # backward: L^T x = D^-1 z
    for s in range(ns - 1, -1, -1):
        c0 = starts[s]
        w = starts[s + 1] - c0
        for a in range(w):
            for c in range(k):
                ys[c, a] = y[c0 + a, c]
        B = rect[b_off[s]: b_off[s + 1]]
        r0 = r_off[s]
        for i in range(r_off[s + 1] - r0):
            ri = rows[r0 + i]
            for c in range(k):
                yr = y[ri, c]
                if yr != 0.0:
                    for a in range(w):
                        ys[c, a] -= B[i * w + a] * yr
        T = tri[t_off[s]: t_off[s + 1]]
        for a in range(w - 1, -1, -1):
            for c in range(k):
                xa = ys[c, a]
                for a2 in range(a):
                    ys[c, a2] -= T[a * w + a2] * xa
        for a in range(w):
            for c in range(k):
                y[c0 + a, c] = ys[c, a]
    for i in range(n):
        pi = perm[i]
        for c in range(k):
            out[i, c] = y[pi, c]


class SupernodalLDL:
    """x = A^-1 b from SuperLU's factor of an SPD matrix (see the module docstring).

    `solve(b)` for b (n,) or (n, k); the kernel holds no GIL."""

    def __init__(self, lu):
        n = lu.shape[0]
        perm = np.asarray(lu.perm_r, np.int64)
        if not np.array_equal(perm, np.asarray(lu.perm_c)):
            raise SolverError("LDL^T solve needs a symmetric ordering (perm_r = perm_c)")
        L = sp.csc_matrix(lu.L)
        L.sort_indices()
        Lp = L.indptr.astype(np.int64)
        Li = L.indices.astype(np.int32)
        if np.any(Li[Lp[:-1]] != np.arange(n)):
            raise SolverError("LDL^T solve: SuperLU's L has a missing diagonal entry")
        starts = _supernodes(Lp, Li, n)
        self.n = n
        self.n_supernodes = starts.shape[0] - 1
        self.nnz = L.nnz
        t_off, b_off, r_off, tri, rect, rows = _pack(Lp, Li, L.data, starts)
        d = np.asarray(lu.U.diagonal(), float)
        self._data = (starts, t_off, b_off, r_off, tri, rect, rows, d, perm)
        rhs = np.random.default_rng(0).standard_normal(n)
        ref = lu.solve(rhs)
        err = np.abs(self.solve(rhs) - ref).max() / max(np.abs(ref).max(), 1e-300)
        if not err <= CHECK_RTOL:
            raise SolverError(f"LDL^T solve disagrees with SuperLU's LU by {err:.1e} "
                              "(the matrix is not symmetric positive definite?)")

    def solve(self, b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, float)
        one = b.ndim == 1
        b2 = np.ascontiguousarray(b.reshape(self.n, -1))
        out = np.empty_like(b2)
        _ldl_solve(*self._data, b2, out)
        return out[:, 0] if one else out

    __call__ = solve


def ldl_factor(a: sp.spmatrix):
    """x = solve(b) for the SPD sparse matrix a (b (n,) or (n, k)): SuperLU's factor with
    the symmetric ordering of fe.modes.SPD_LU, solved as L D L^T by SupernodalLDL.
    Raises SolverError as fe.modes.factor does."""
    return SupernodalLDL(superlu_spd(a)).solve
