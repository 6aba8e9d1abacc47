"""Supernodal LDL^T solves of a symmetric positive definite matrix.

    A^-1 b = P^T L^-T D^-1 L^-1 P b

with L unit lower triangular, stored by supernodes (runs of columns with one row structure
below their diagonal block; ~1,270 of mean width 20 on a seed rod): a dense triangle and a
dense row-major rectangle per supernode, with the rectangle's row indices once, so a solve
streams 8 bytes per entry of L twice (forward and backward), and several right-hand sides
share one pass over the factor. The kernels release the GIL: two bodies' solves run on two
threads (integrate.moreau_jean), and one body's solve can run its two elimination-tree halves
on two threads (etree_halves; fe.solvers.ordering makes an order that has them). From
BLAS_MIN_COLUMNS right-hand sides each supernode's block goes through BLAS-3 (dtrsm, dgemm;
fe.solvers.blas): a Craig-Bampton build's constraint columns in one block.

The factor comes from fe.solvers.cholesky, packed in this layout as it is made. Sparse-direct
background: Davis, "Direct Methods for Sparse
Linear Systems" (SIAM 2006), ch. 4 and 9 (supernodes, elimination trees).
"""

from __future__ import annotations

import numba
import numpy as np
import scipy.sparse as sp

from flexmvm.errors import SolverError
from flexmvm.fe.solvers.blas import dgemm, dtrsm

#: A factor is accepted when the backward error of its solve of a random right-hand side,
#: ||A x - b|| / (||A|| ||x|| + ||b||) (max norms), is at most this; stable solves give ~1e-16.
BACKWARD_RTOL = 1e-12


_FAST = {"reassoc", "contract"}  # lets LLVM vectorise the dot products (round-off only)


@numba.njit(nogil=True, cache=True)
def _permute_in(perm, b, y):  # pragma: no cover - compiled
    """y = P b: (P b)[perm[i]] = b[i]; b, y (n, k)."""
    n, k = b.shape
    for i in range(n):
        pi = perm[i]
        for c in range(k):
            y[pi, c] = b[i, c]


@numba.njit(nogil=True, cache=True)
def _permute_out(perm, y, out):  # pragma: no cover - compiled
    n, k = y.shape
    for i in range(n):
        pi = perm[i]
        for c in range(k):
            out[i, c] = y[pi, c]


@numba.njit(nogil=True, cache=True)
def _widest(starts):  # pragma: no cover - compiled
    wmax = 1
    for s in range(starts.shape[0] - 1):
        wmax = max(wmax, starts[s + 1] - starts[s])
    return wmax


@numba.njit(nogil=True, cache=True, fastmath=_FAST)
def _forward(sns, starts, t_off, b_off, r_off, tri, rect, rows, y):  # pragma: no cover
    """L z = y in place over the supernodes sns (ascending: children before parents), y
    (n, k). A supernode updates only its own rows and its etree ancestors'."""
    k = y.shape[1]
    ys = np.empty((k, _widest(starts)))
    for j in range(sns.shape[0]):
        s = sns[j]
        c0 = starts[s]
        w = starts[s + 1] - c0
        T = tri[t_off[s] : t_off[s + 1]]
        for a in range(w):
            for c in range(k):
                acc = y[c0 + a, c]
                for a2 in range(a):
                    acc -= T[a * w + a2] * ys[c, a2]
                ys[c, a] = acc
        for a in range(w):
            for c in range(k):
                y[c0 + a, c] = ys[c, a]
        B = rect[b_off[s] : b_off[s + 1]]
        r0 = r_off[s]
        for i in range(r_off[s + 1] - r0):
            ri = rows[r0 + i]
            for c in range(k):
                acc = 0.0
                for a in range(w):
                    acc += B[i * w + a] * ys[c, a]
                y[ri, c] -= acc


@numba.njit(nogil=True, cache=True)
def _diagonal(d, y):  # pragma: no cover - compiled
    """y = D^-1 y."""
    n, k = y.shape
    for i in range(n):
        di = 1.0 / d[i]
        for c in range(k):
            y[i, c] *= di


@numba.njit(nogil=True, cache=True, fastmath=_FAST)
def _backward(sns, starts, t_off, b_off, r_off, tri, rect, rows, y):  # pragma: no cover
    """L^T x = y in place over the supernodes sns, taken in descending order (parents
    before children); a supernode writes only its own rows and reads its ancestors'."""
    k = y.shape[1]
    ys = np.empty((k, _widest(starts)))
    for j in range(sns.shape[0] - 1, -1, -1):
        s = sns[j]
        c0 = starts[s]
        w = starts[s + 1] - c0
        for a in range(w):
            for c in range(k):
                ys[c, a] = y[c0 + a, c]
        B = rect[b_off[s] : b_off[s + 1]]
        r0 = r_off[s]
        for i in range(r_off[s + 1] - r0):
            ri = rows[r0 + i]
            for c in range(k):
                yr = y[ri, c]
                if yr != 0.0:
                    for a in range(w):
                        ys[c, a] -= B[i * w + a] * yr
        T = tri[t_off[s] : t_off[s + 1]]
        for a in range(w - 1, -1, -1):
            for c in range(k):
                xa = ys[c, a]
                for a2 in range(a):
                    ys[c, a2] -= T[a * w + a2] * xa
        for a in range(w):
            for c in range(k):
                y[c0 + a, c] = ys[c, a]


#: From this many right-hand sides a solve takes the supernodes' blocks through BLAS-3 (dtrsm,
#: dgemm: _forward_blas, _backward_blas) instead of the loops above. Seed K_ii, two threads,
#: ms per column (loops / BLAS): 8 columns 3.95 / 3.68, 32 3.66 / 1.71, 513 3.11 / 1.03.
BLAS_MIN_COLUMNS = 8


@numba.njit(nogil=True, cache=True)
def _widest_below(r_off):  # pragma: no cover - compiled
    rmax = 1
    for s in range(r_off.shape[0] - 1):
        rmax = max(rmax, r_off[s + 1] - r_off[s])
    return rmax


@numba.njit(nogil=True, cache=True)
def _forward_blas(sns, starts, t_off, b_off, r_off, tri, rect, rows, y):  # pragma: no cover
    """_forward with each supernode's block through BLAS: the w x k rows of y (row-major,
    i.e. their transpose column-major) solved against the unit triangle (dtrsm; the
    row-major triangle is its transpose column-major), the rows below updated by one dgemm."""
    k = y.shape[1]
    flat = y.reshape(y.size)  # a view: y is C-contiguous
    z = np.empty(_widest_below(r_off) * k)
    ch = np.empty(4, np.uint8)
    ch[0], ch[1], ch[2], ch[3] = 82, 85, 78, 84  # 'R', 'U', 'N', 'T'
    iv = np.empty(3, np.int32)  # k, w, r
    dv = np.empty(2)
    dv[0], dv[1] = 1.0, 0.0
    for j in range(sns.shape[0]):
        s = sns[j]
        c0 = starts[s]
        w = starts[s + 1] - c0
        r0 = r_off[s]
        r = r_off[s + 1] - r0
        iv[0], iv[1], iv[2] = k, w, r
        block = flat[c0 * k :]
        T = tri[t_off[s] :]
        dtrsm(
            ch[0:].ctypes,
            ch[1:].ctypes,
            ch[2:].ctypes,
            ch[1:].ctypes,
            iv[0:].ctypes,
            iv[1:].ctypes,
            dv[0:].ctypes,
            T.ctypes,
            iv[1:].ctypes,
            block.ctypes,
            iv[0:].ctypes,
        )
        if r > 0:
            B = rect[b_off[s] :]
            dgemm(
                ch[2:].ctypes,
                ch[2:].ctypes,
                iv[0:].ctypes,
                iv[2:].ctypes,
                iv[1:].ctypes,
                dv[0:].ctypes,
                block.ctypes,
                iv[0:].ctypes,
                B.ctypes,
                iv[1:].ctypes,
                dv[1:].ctypes,
                z.ctypes,
                iv[0:].ctypes,
            )
            for i in range(r):
                ri = rows[r0 + i]
                for c in range(k):
                    y[ri, c] -= z[i * k + c]


@numba.njit(nogil=True, cache=True)
def _backward_blas(sns, starts, t_off, b_off, r_off, tri, rect, rows, y):  # pragma: no cover
    """_backward with each supernode's block through BLAS: the rows below gathered, one
    dgemm into the block, then the transposed unit triangle solved (dtrsm)."""
    k = y.shape[1]
    flat = y.reshape(y.size)  # a view: y is C-contiguous
    g = np.empty(_widest_below(r_off) * k)
    ch = np.empty(4, np.uint8)
    ch[0], ch[1], ch[2], ch[3] = 82, 85, 78, 84  # 'R', 'U', 'N', 'T'
    iv = np.empty(3, np.int32)  # k, w, r
    dv = np.empty(2)
    dv[0], dv[1] = 1.0, -1.0
    for j in range(sns.shape[0] - 1, -1, -1):
        s = sns[j]
        c0 = starts[s]
        w = starts[s + 1] - c0
        r0 = r_off[s]
        r = r_off[s + 1] - r0
        iv[0], iv[1], iv[2] = k, w, r
        block = flat[c0 * k :]
        if r > 0:
            for i in range(r):
                ri = rows[r0 + i]
                for c in range(k):
                    g[i * k + c] = y[ri, c]
            B = rect[b_off[s] :]
            dgemm(
                ch[2:].ctypes,
                ch[3:].ctypes,
                iv[0:].ctypes,
                iv[1:].ctypes,
                iv[2:].ctypes,
                dv[1:].ctypes,
                g.ctypes,
                iv[0:].ctypes,
                B.ctypes,
                iv[1:].ctypes,
                dv[0:].ctypes,
                block.ctypes,
                iv[0:].ctypes,
            )
        T = tri[t_off[s] :]
        dtrsm(
            ch[0:].ctypes,
            ch[1:].ctypes,
            ch[3:].ctypes,
            ch[1:].ctypes,
            iv[0:].ctypes,
            iv[1:].ctypes,
            dv[0:].ctypes,
            T.ctypes,
            iv[1:].ctypes,
            block.ctypes,
            iv[0:].ctypes,
        )


@numba.njit(nogil=True, cache=True)
def _merge(y, y2, own2, top, top0):  # pragma: no cover - compiled
    """After the two subtree halves' forward passes (the first in y, the second in y2, both
    from the same y): y takes the second half's rows and the second's updates of the top
    rows, y[top] += y2[top] - top0 (top0: the top rows before either pass)."""
    k = y.shape[1]
    for j in range(own2.shape[0]):
        i = own2[j]
        for c in range(k):
            y[i, c] = y2[i, c]
    for j in range(top.shape[0]):
        i = top[j]
        for c in range(k):
            y[i, c] += y2[i, c] - top0[j, c]


def etree_halves(starts, r_off, rows, min_gain: float):
    """The supernodes split for a solve on two threads: two sets of whole etree subtrees of
    about equal work (L entries) and the top of the tree above them, or None when that
    split would gain less than min_gain (ideal, work / (top + larger half)).

    Columns of L depend only on their etree descendants, so two disjoint sets of subtrees are
    eliminated independently and the supernodes above them after (subtree-to-subcube
    mapping: George, Liu and Ng 1989; Davis 2006, ch. 4 and 9). The minimum-degree ordering
    of a rod's W leaves ~11 % of the work at the top and two halves of ~44 % (25,041 DOFs)."""
    ns = starts.shape[0] - 1
    width = np.diff(starts)
    below = np.diff(r_off)
    work = width * (width + 1) / 2.0 + width * below
    col_sn = np.repeat(np.arange(ns), width)
    parent = np.full(ns, -1, np.int64)
    for sn in np.flatnonzero(below):
        parent[sn] = col_sn[rows[r_off[sn] : r_off[sn + 1]].min()]
    subtree = work.copy()
    children: list[list[int]] = [[] for _ in range(ns)]
    for s in range(ns):  # parents come after their children
        if parent[s] >= 0:
            subtree[parent[s]] += subtree[s]
            children[parent[s]].append(s)
    total = float(work.sum())

    def bins(frontier):  # largest subtree first, to the lighter half
        loads, half = [0.0, 0.0], {}
        for s in sorted(frontier, key=lambda s: -subtree[s]):
            h = int(np.argmin(loads))
            loads[h] += subtree[s]
            half[s] = h
        return loads, half

    # expand the heaviest subtree (its root goes to the top) while that may help; keep the
    # frontier with the least work on the critical path, top + larger half
    frontier = [int(s) for s in np.flatnonzero(parent < 0)]
    top: list[int] = []
    best: tuple[float, list[int], dict[int, int]] = (np.inf, [], {})
    for _ in range(min(ns, 400)):
        loads, half = bins(frontier)
        path = total - sum(loads) + max(loads)
        if path < best[0] and min(loads) > 0.0:
            best = (path, list(top), half)
        heaviest = max(frontier, key=lambda s: subtree[s])
        # the path is at least (total + top) / 2, and the top only grows
        if not children[heaviest] or total + (total - sum(loads)) >= 2.0 * best[0]:
            break
        frontier.remove(heaviest)
        top.append(heaviest)
        frontier += children[heaviest]
    path, top, half = best
    if not half or total / path < min_gain:
        return None
    label = np.full(ns, -1, np.int64)
    for s, h in half.items():
        label[s] = h
    label[top] = 2
    for s in range(ns - 1, -1, -1):
        if label[s] < 0:
            label[s] = label[parent[s]]
    return tuple(np.flatnonzero(label == h).astype(np.int64) for h in range(3))


@numba.njit(cache=True)
def _abs_row_sums(indptr, index, data, n, by_rows):  # pragma: no cover - compiled
    """sum_j |a_ij| for every row i of a CSR (by_rows) or CSC matrix."""
    out = np.zeros(n)
    for k in range(indptr.shape[0] - 1):
        for q in range(indptr[k], indptr[k + 1]):
            out[k if by_rows else index[q]] += abs(data[q])
    return out


def _inf_norm(a) -> float:
    """max_i sum_j |a_ij| in one pass (scipy.sparse.linalg.norm(a, inf) of a CSC matrix
    builds abs(a) and a product: docs/notes/2026-11-27-comment-measurements.md)."""
    a = sp.csr_matrix(a) if not sp.issparse(a) or a.format not in ("csr", "csc") else a
    sums = _abs_row_sums(
        a.indptr, a.indices, np.asarray(a.data, float), a.shape[0], a.format == "csr"
    )
    return float(sums.max()) if sums.size else 0.0


def backward_error(a, solve) -> float:
    """||a x - b|| / (||a|| ||x|| + ||b||) (max norms) of x = solve(b) for a random b (seeded):
    ~1e-16 for a stable solve of a's factor, whatever a's conditioning; of order one when the
    factor is not a's (of an unsymmetric a, only one triangle was factored)."""
    rhs = np.random.default_rng(0).standard_normal(a.shape[0])
    x = solve(rhs)
    scale = _inf_norm(a) * np.abs(x).max() + np.abs(rhs).max()
    return float(np.abs(a @ x - rhs).max() / max(scale, 1e-300))


#: A solve is split over two threads (SupernodalLDL.pool) when the etree split gains at least
#: this (ideal: work / (top + larger half)) on a matrix of at least SPLIT_MIN_N rows; below,
#: handing half a solve to another thread costs more than it saves.
SPLIT_MIN_GAIN = 1.3
SPLIT_MIN_N = 4000


def split_halves(starts, r_off, rows):
    """etree_halves of a factor of at least SPLIT_MIN_N rows that gains SPLIT_MIN_GAIN, else
    None: the split a factorization (fe.solvers.cholesky) and the solves take on two threads."""
    if starts[-1] < SPLIT_MIN_N:
        return None
    return etree_halves(starts, r_off, rows, SPLIT_MIN_GAIN)


def stored_entries(starts, r_off) -> int:
    """Entries of L held by the supernodes (triangles with their diagonals, rectangles)."""
    width = np.diff(starts)
    return int((width * (width + 1) // 2 + width * np.diff(r_off)).sum())


class SupernodalLDL:
    """x = A^-1 b from a supernodal L D L^T of an SPD matrix (see the module docstring).

    `solve(b)` for b (n,) or (n, k); the kernels hold no GIL. With a thread pool (`pool`, a
    concurrent.futures executor with a free worker) a large solve runs its two etree halves
    (etree_halves) on two threads; the arithmetic is the same with or without the pool, so
    the results are identical bit for bit."""

    def __init__(self, perm: np.ndarray, factor: tuple, d: np.ndarray, halves, pool=None, a=None):
        """perm with (P b)[perm[i]] = b[i]; factor = (starts, t_off, b_off, r_off, tri, rect,
        rows), the packed supernodes (fe.solvers.cholesky); d the pivots; halves: split_halves
        of the factor; a (sparse): the matrix, for the check by the backward error of one solve
        (BACKWARD_RTOL). Raises SolverError when the check fails."""
        starts, r_off = factor[0], factor[3]
        self.n = perm.shape[0]
        self.n_supernodes = starts.shape[0] - 1
        self.nnz = stored_entries(starts, r_off)
        self.pool = pool
        self._factor = factor
        self._d, self._perm = np.asarray(d, float), np.asarray(perm, np.int64)
        self._all = np.arange(self.n_supernodes, dtype=np.int64)
        if halves is None:
            self._halves = None
        else:
            first, second, top = halves
            cols = [
                np.concatenate(
                    [np.arange(starts[s], starts[s + 1]) for s in part] + [np.zeros(0, np.int64)]
                )  # the top may be empty
                for part in (second, top)
            ]
            self._halves = (first, second, top, cols[0].astype(np.int64), cols[1].astype(np.int64))
        if a is not None:
            self._check(a)

    def _check(self, a) -> None:
        """SolverError unless a solve of a random right-hand side has a backward error of at
        most BACKWARD_RTOL: independent of the conditioning (a free body's K - sigma M, sigma
        ~1e-9 of its stiffness, is accepted), of order one where the factor is not a's (an
        unsymmetric a, whose lower triangle was factored)."""
        err = backward_error(a, self.solve)
        if not err <= BACKWARD_RTOL:
            raise SolverError(
                f"LDL^T solve has a backward error of {err:.1e} (the matrix "
                "is not symmetric positive definite?)"
            )

    @property
    def split(self) -> bool:
        """Whether solves are taken in two etree halves (on two threads with a pool)."""
        return self._halves is not None

    def solve(self, b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, float)
        one = b.ndim == 1
        b2 = np.ascontiguousarray(b.reshape(self.n, -1))
        L = self._factor
        y = np.empty_like(b2)
        _permute_in(self._perm, b2, y)
        blas = b2.shape[1] >= BLAS_MIN_COLUMNS
        forward = _forward_blas if blas else _forward
        backward = _backward_blas if blas else _backward
        if self._halves is None:
            forward(self._all, *L, y)
            _diagonal(self._d, y)
            backward(self._all, *L, y)
        else:
            first, second, top, own2, top_cols = self._halves
            y2 = y.copy()
            top0 = y[top_cols]
            self._both(forward, first, second, y, y2)
            _merge(y, y2, own2, top_cols, top0)
            forward(top, *L, y)
            _diagonal(self._d, y)
            backward(top, *L, y)
            self._both(backward, first, second, y, y)
        out = np.empty_like(b2)
        _permute_out(self._perm, y, out)
        return out[:, 0] if one else out

    def _both(self, kernel, first, second, y1, y2) -> None:
        """kernel over the first half on y1 and the second on y2, on two threads with a pool."""
        L = self._factor
        if self.pool is None:
            kernel(first, *L, y1)
            kernel(second, *L, y2)
            return
        job = self.pool.submit(kernel, second, *L, y2)
        kernel(first, *L, y1)
        job.result()

    __call__ = solve
