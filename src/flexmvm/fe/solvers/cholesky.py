"""Supernodal multifrontal L D L^T factorization of a sparse symmetric positive definite matrix.

SuperLU (scipy) factors an SPD matrix as a general LU: both triangles, in its supernode-panel
kernels (for the seed rod's K_ii: 24,972 DOFs, 10.5 M entries in L, 6.1 GFlop of Cholesky
arithmetic), and fe.solvers.ldl would then copy its L out to solve with L D L^T (timings:
docs/notes/2026-11-27-comment-measurements.md). This module computes that L D L^T itself,
in fe.solvers.ldl's packed supernodal layout, with the dense work of every supernode in
LAPACK/BLAS (dpotrf, dtrsm, dsyrk: BLAS-3):

1. Ordering: SuperLU's minimum degree of A^T + A (fe.solvers.ordering.mmd_order).
2. Symbolic analysis: fe.solvers.symbolic (elimination tree, column counts, supernodes).
3. Numeric factorization, multifrontal (Duff and Reid 1983; Liu, SIAM Review 34, 1992): per
   supernode, in postorder, a dense front assembled from A's columns and the children's update
   matrices (extend-add), its pivot block factored (dpotrf), the rows below solved (dtrsm) and
   the update matrix formed (dsyrk), then packed as unit-triangular blocks and D.

The kernels call the BLAS/LAPACK that scipy ships, through fe.solvers.blas.
"""

from __future__ import annotations

import numba
import numpy as np
import scipy.sparse as sp
from numba.typed import List
from threadpoolctl import threadpool_limits

from flexmvm.errors import SolverError
from flexmvm.fe.solvers import ldl
from flexmvm.fe.solvers.blas import dpotrf, dsyrk, dtrsm
from flexmvm.fe.solvers.ordering import mmd_order
from flexmvm.fe.solvers.symbolic import SymbolicFactor, symmetric_csc


@numba.njit(cache=True)
def _no_fronts(ns):  # pragma: no cover - compiled
    """A list of ns empty fronts (a front is kept there until its parent has used it)."""
    fronts = List()
    for _ in range(ns):
        fronts.append(np.empty(0))
    return fronts


@numba.njit(nogil=True, cache=True)
def _front_from_a(s, pos, Ap, Ai, Ax, p, pinv, starts, r_off, rows):  # pragma: no cover
    """Supernode s's front F (m x m, column-major, lower part; m = w + r: its w columns and
    r rows below) with A's entries of its columns scattered in; pos maps a row of the
    elimination order to its place in the front. Returns F."""
    c0 = starts[s]
    w = starts[s + 1] - c0
    base = r_off[s]
    r = r_off[s + 1] - base
    m = w + r
    F = np.zeros(m * m)
    for a in range(w):
        pos[c0 + a] = a
    for i in range(r):
        pos[rows[base + i]] = w + i
    for a in range(w):
        j = c0 + a
        col = p[j]
        for q in range(Ap[col], Ap[col + 1]):
            i = pinv[Ai[q]]
            if i >= j:
                F[pos[i] + a * m] += Ax[q]
    return F


@numba.njit(nogil=True, cache=True)
def _extend_add(
    F, m, s, pos, starts, r_off, rows, child_ptr, child_idx, fronts, other
):  # pragma: no cover
    """Add the update matrices of supernode s's children into its front F (m x m): a child's
    front from fronts, else from other (the other etree half's list); both released after
    use."""
    for t in range(child_ptr[s], child_ptr[s + 1]):
        c = child_idx[t]
        Fc = fronts[c]
        if Fc.shape[0] == 0:
            Fc = other[c]
            other[c] = np.empty(0)
        wc = starts[c + 1] - starts[c]
        cb0 = r_off[c]
        rc = r_off[c + 1] - cb0
        mc = wc + rc
        for b in range(rc):
            jb = pos[rows[cb0 + b]] * m
            src = (wc + b) * mc + wc
            for a in range(b, rc):
                F[pos[rows[cb0 + a]] + jb] += Fc[src + a]
        fronts[c] = np.empty(0)


@numba.njit(nogil=True, cache=True)
def _factor_front(F, w, m, r, ch, iv, dv):  # pragma: no cover - compiled
    """Dense Cholesky of front F's pivot block (dpotrf), the rows below solved against it
    (dtrsm) and the update matrix F_22 - L_21 L_21^T formed (dsyrk), in place. ch: the
    characters 'L', 'R', 'T', 'N'; iv, dv: work for the integer and double arguments.
    Returns LAPACK's info (0, or the 1-based column of a pivot that was not positive)."""
    iv[0], iv[1], iv[2], iv[3] = w, m, r, 0
    dpotrf(ch[0:].ctypes, iv[0:].ctypes, F.ctypes, iv[1:].ctypes, iv[3:].ctypes)
    if iv[3] != 0 or r == 0:
        return iv[3]
    below = F[w:]
    dtrsm(
        ch[1:].ctypes,
        ch[0:].ctypes,
        ch[2:].ctypes,
        ch[3:].ctypes,
        iv[2:].ctypes,
        iv[0:].ctypes,
        dv[0:].ctypes,
        F.ctypes,
        iv[1:].ctypes,
        below.ctypes,
        iv[1:].ctypes,
    )
    update = F[w + w * m :]
    dsyrk(
        ch[0:].ctypes,
        ch[3:].ctypes,
        iv[2:].ctypes,
        iv[0:].ctypes,
        dv[1:].ctypes,
        below.ctypes,
        iv[1:].ctypes,
        dv[0:].ctypes,
        update.ctypes,
        iv[1:].ctypes,
    )
    return 0


@numba.njit(nogil=True, cache=True)
def _pack_front(F, w, m, r, c0, t0, b0, tri, rect, d):  # pragma: no cover - compiled
    """The factored front F's columns in fe.solvers.ldl's packed layout: L = L_c D^(1/2)
    (L_c the Cholesky factor) as unit lower triangle tri, rows below rect, pivots d."""
    for a in range(w):
        piv = F[a + a * m]
        d[c0 + a] = piv * piv
        inv = 1.0 / piv
        for a2 in range(a + 1, w):
            tri[t0 + a2 * w + a] = F[a2 + a * m] * inv
        for i in range(r):
            rect[b0 + i * w + a] = F[w + i + a * m] * inv


@numba.njit(nogil=True, cache=True)
def _numeric(
    sns,
    Ap,
    Ai,
    Ax,
    p,
    pinv,
    starts,
    r_off,
    rows,
    child_ptr,
    child_idx,
    sn_parent,
    t_off,
    b_off,
    tri,
    rect,
    d,
    fronts,
    other,
):  # pragma: no cover - compiled
    """Multifrontal L D L^T of a[p][:, p] over the supernodes sns (ascending: children
    first) into fe.solvers.ldl's packed layout (tri: unit lower triangles, row-major; rect: the rows
    below, row-major; d). A supernode's front is left in fronts for its parent; a child's is
    taken from fronts, else from other (the list of the other etree half, whose subtrees a
    top supernode also has as children). Returns -1, or the column at which a pivot was not
    positive (the matrix is not positive definite)."""
    pos = np.empty(p.shape[0], np.int64)
    ch = np.empty(4, np.uint8)
    ch[0], ch[1], ch[2], ch[3] = 76, 82, 84, 78  # 'L', 'R', 'T', 'N'
    iv = np.empty(4, np.int32)  # w, m, r, info
    dv = np.empty(2)
    dv[0], dv[1] = 1.0, -1.0
    for k in range(sns.shape[0]):
        s = sns[k]
        c0 = starts[s]
        w = starts[s + 1] - c0
        r = r_off[s + 1] - r_off[s]
        m = w + r
        F = _front_from_a(s, pos, Ap, Ai, Ax, p, pinv, starts, r_off, rows)
        _extend_add(F, m, s, pos, starts, r_off, rows, child_ptr, child_idx, fronts, other)
        info = _factor_front(F, w, m, r, ch, iv, dv)
        if info != 0:
            return c0 + info - 1
        _pack_front(F, w, m, r, c0, t_off[s], b_off[s], tri, rect, d)
        if sn_parent[s] != -1:
            fronts[s] = F
    return -1


def numeric_factor(symbolic: SymbolicFactor, a: sp.spmatrix, pool=None):
    """The packed L D L^T of a (the pattern `symbolic` was made for): (tri, rect, d). With a
    pool, the two elimination-tree halves (fe.solvers.ldl.etree_halves) are factored on two threads
    (the same arithmetic as on one: bit for bit), then the top of the tree.
    Raises SolverError when a pivot is not positive (a is not positive definite)."""
    a = symmetric_csc(a)
    if not symbolic.matches(a):
        raise SolverError(
            "Cholesky factor: the matrix has another sparsity pattern than its symbolic analysis"
        )
    if not np.isfinite(a.data).all():
        raise SolverError(
            f"Cholesky factor of a {symbolic.n}x{symbolic.n} matrix: it holds "
            "a non-finite number (NaN/inf)"
        )
    tri = np.zeros(symbolic.t_off[-1])
    rect = np.empty(symbolic.b_off[-1])
    d = np.empty(symbolic.n)
    ns = symbolic.starts.shape[0] - 1
    mine, theirs = _no_fronts(ns), _no_fronts(ns)
    args = (
        symbolic._pattern[0],
        symbolic._pattern[1],
        np.asarray(a.data, np.float64),
        symbolic.order,
        symbolic.inverse,
        symbolic.starts,
        symbolic.r_off,
        symbolic.rows,
        symbolic.child_ptr,
        symbolic.child_idx,
        symbolic.sn_parent,
        symbolic.t_off,
        symbolic.b_off,
        tri,
        rect,
        d,
    )
    # one BLAS thread: a threaded dsyrk rounds differently from a serial one, and the same
    # matrix must give the same factor (and modes) whatever the caller's BLAS setting
    with threadpool_limits(limits=1, user_api="blas"):
        if pool is None or symbolic.halves is None:
            bad = _numeric(np.arange(ns, dtype=np.int64), *args, mine, theirs)
        else:
            first, second, top = symbolic.halves
            job = pool.submit(_numeric, second, *args, theirs, mine)
            bad = _numeric(first, *args, mine, theirs)
            bad_second = job.result()
            bad = bad if bad >= 0 else bad_second
            if bad < 0:
                bad = _numeric(top, *args, mine, theirs)
    if bad >= 0:
        raise SolverError(
            f"Cholesky factor of a {symbolic.n}x{symbolic.n} matrix: pivot "
            f"{bad} of its elimination order is not positive (the matrix is not "
            "positive definite)"
        )
    return tri, rect, d


def cholesky_ldl(a: sp.spmatrix, pool=None, symbolic: SymbolicFactor | None = None):
    """fe.solvers.ldl.SupernodalLDL of the SPD sparse matrix a factored here (module docstring):
    `solve(b)` for b (n,) or (n, k); with a pool the factor and the solves take the two
    elimination-tree halves on two threads. a is symmetric: of a CSR matrix, its transpose
    (CSC, no copy) is factored. symbolic: the analysis of a's pattern, when already made
    (default: made here; one of another pattern is remade with its order). With a pool, the
    compiled kernels are loaded on its thread while SuperLU orders a (~0.2 s in a fresh
    process, hidden).
    Raises SolverError when a is not positive definite or the check of the solve fails."""
    csc = symmetric_csc(a)
    if symbolic is None:
        warm = pool.submit(warm_kernels) if pool is not None and not _WARM else None
        order = mmd_order(csc)
        if warm is not None:
            warm.result()
        symbolic = SymbolicFactor(csc, order)
    elif not symbolic.matches(csc):
        symbolic = SymbolicFactor(csc, symbolic.given_order)
    tri, rect, d = numeric_factor(symbolic, csc, pool)
    factor = (
        symbolic.starts,
        symbolic.t_off,
        symbolic.b_off,
        symbolic.r_off,
        tri,
        rect,
        symbolic.rows,
    )
    return ldl.SupernodalLDL(symbolic.inverse, factor, d, symbolic.halves, pool, a=a)


def ldl_factor(a: sp.spmatrix, pool=None):
    """x = solve(b) for the SPD sparse matrix a (b (n,) or (n, k)): cholesky_ldl with SuperLU's
    minimum-degree ordering. Raises SolverError when a is not positive definite."""
    return cholesky_ldl(a, pool).solve


def packed_entries(symbolic: SymbolicFactor) -> int:
    """Numbers numeric_factor's packed factor holds: tri (a w x w square per supernode of
    width w), rect and d."""
    return int(symbolic.t_off[-1] + symbolic.b_off[-1]) + symbolic.n


def held_entries(symbolic: SymbolicFactor) -> int:
    """The most numbers (8 bytes each) numeric_factor holds at once for a matrix of the
    pattern ``symbolic`` was made for: the packed factor (packed_entries) and the fronts
    alive at the worst moment. A supernode's front is an
    m x m square (m: its columns and the rows below them), made when the supernode is
    factored and kept until its parent has added it in; with two etree halves on two threads
    their worst moments are taken as coinciding (a bound: the run's own order is not known).
    On a 263,685-DOF plate in the integrator's order the fronts' peak was about the packed
    factor's size (419 M against 422 M numbers)."""
    width = np.diff(symbolic.starts)
    m = width + np.diff(symbolic.r_off)
    size = m.astype(np.float64) ** 2
    parent = symbolic.sn_parent
    has_parent = parent >= 0
    children = np.bincount(parent[has_parent], weights=size[has_parent], minlength=size.size)
    delta = np.where(has_parent, size, 0.0) - children  # alive after s minus before

    def walk(sns: np.ndarray, live: float) -> tuple[float, float]:
        if not sns.size:
            return live, live
        before = live + np.concatenate([[0.0], np.cumsum(delta[sns])[:-1]])
        return float((before + size[sns]).max()), float(live + delta[sns].sum())

    if symbolic.halves is None:
        peak, _ = walk(np.arange(size.size), 0.0)
    else:
        first, second, top = symbolic.halves
        peak1, live1 = walk(np.asarray(first), 0.0)
        peak2, live2 = walk(np.asarray(second), 0.0)
        peak_top, _ = walk(np.asarray(top), live1 + live2)
        peak = max(peak1 + peak2, peak_top)
    return packed_entries(symbolic) + int(peak)


_WARM = False  # the kernels are loaded in this process (warm_kernels ran)


def warm_kernels() -> None:
    """Load (or compile, the first time) every kernel of a factor and of a split solve, once
    per process: one factor and solve of a small diagonal matrix (its forest of an
    elimination tree splits)."""
    global _WARM
    n = ldl.SPLIT_MIN_N
    eye = sp.identity(n, format="csc")
    cholesky_ldl(eye, symbolic=SymbolicFactor(eye, np.arange(n))).solve(np.ones(n))
    _WARM = True


__all__ = [
    "cholesky_ldl",
    "held_entries",
    "ldl_factor",
    "numeric_factor",
    "packed_entries",
    "warm_kernels",
]
