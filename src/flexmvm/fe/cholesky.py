"""Supernodal multifrontal L D L^T factorization of a sparse symmetric positive definite matrix.

SuperLU (scipy) factors an SPD matrix as a general LU: both triangles, in its supernode-panel
kernels, 1.14 s for the seed rod's K_ii (24,972 DOFs, 10.5 M entries in L, 6.1 GFlop of
Cholesky arithmetic), and fe.ldl then copies its L out (0.5 s) to solve with L D L^T. This
module computes that L D L^T itself, in fe.ldl's packed supernodal layout, with the dense work
of every supernode in LAPACK/BLAS (dpotrf, dtrsm, dsyrk: BLAS-3):

1. Ordering: SuperLU's minimum degree of A^T + A (fe.modes.SPD_LU), taken from an incomplete
   factorization that drops every entry (spilu: the same permutation as splu's, 0.2 s instead
   of a whole factorization).
2. Symbolic analysis (Davis, "Direct Methods for Sparse Linear Systems", SIAM 2006, ch. 4):
   the elimination tree (Liu's algorithm), its postorder, the column counts of L (row
   subtrees, Gilbert, Ng and Peyton 1994), the fundamental supernodes, relaxed amalgamation
   (Ashcraft and Grimes 1989; CHOLMOD's default limits) and every supernode's row structure.
3. Numeric factorization, multifrontal (Duff and Reid 1983; Liu, SIAM Review 34, 1992): per
   supernode, in postorder, a dense front assembled from A's columns and the children's update
   matrices (extend-add), its pivot block factored (dpotrf), the rows below solved (dtrsm) and
   the update matrix formed (dsyrk), then packed as unit-triangular blocks and D.

The kernels call the BLAS/LAPACK that scipy ships, through fe.blas.
"""

from __future__ import annotations

import numba
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numba.typed import List
from threadpoolctl import threadpool_limits

from flexmvm.errors import SolverError
from flexmvm.fe.blas import dpotrf, dsyrk, dtrsm

#: Relaxed amalgamation (CHOLMOD's defaults, cholmod_super.c): a child supernode is merged
#: into its parent when the merged one is w columns wide with a fraction z of explicit zeros
#: and w <= 4, or w <= 16 and z < 0.8, or w <= 48 and z < 0.1, or z < 0.05.
RELAX_WIDTH = (4, 16, 48)
RELAX_ZEROS = (0.8, 0.1, 0.05)


def mmd_order(a: sp.spmatrix) -> np.ndarray:
    """Elimination order p of the SPD matrix a (a[p][:, p] has little fill): SuperLU's
    minimum degree of A^T + A, read off an incomplete factorization that drops every entry
    (the permutation is computed before any numeric work: the same as splu's with
    fe.modes.SPD_LU)."""
    from flexmvm.fe.modes import SPD_LU
    a = sp.csc_matrix(a)
    try:
        ilu = spla.spilu(a, drop_tol=np.inf, fill_factor=1.0, **SPD_LU)
    except RuntimeError:
        # a zero pivot of the dropped factor (a singular a): the ordering depends on the
        # pattern only, so order a diagonally dominant matrix of a's pattern instead
        dominant = a.copy()
        dominant.data[:] = 1.0
        dominant = sp.csc_matrix(dominant + sp.diags(np.diff(dominant.indptr) + 1.0))
        ilu = spla.spilu(dominant, drop_tol=np.inf, fill_factor=1.0, **SPD_LU)
    perm_c = np.asarray(ilu.perm_c, np.int64)
    order = np.empty_like(perm_c)
    order[perm_c] = np.arange(perm_c.size)      # perm_c[i]: position of column i
    return order


@numba.njit(cache=True)
def _etree(Ap, Ai, p, pinv):  # pragma: no cover - compiled
    """Elimination tree of the symmetric a[p][:, p] (parent[j] = -1 for a root); Ap, Ai the
    full pattern of a (CSC), p the order and pinv its inverse (Liu; Davis 2006, 4.1)."""
    n = p.shape[0]
    parent = np.full(n, -1, np.int64)
    ancestor = np.full(n, -1, np.int64)
    for k in range(n):
        col = p[k]
        for q in range(Ap[col], Ap[col + 1]):
            i = pinv[Ai[q]]
            while i != -1 and i < k:
                inext = ancestor[i]
                ancestor[i] = k
                if inext == -1:
                    parent[i] = k
                i = inext
    return parent


@numba.njit(cache=True)
def _postorder(parent):  # pragma: no cover - compiled
    """A postorder of the forest parent (Davis 2006, 4.3): post[k] is the k-th node."""
    n = parent.shape[0]
    head = np.full(n, -1, np.int64)
    nxt = np.empty(n, np.int64)
    stack = np.empty(n, np.int64)
    post = np.empty(n, np.int64)
    for j in range(n - 1, -1, -1):
        if parent[j] != -1:
            nxt[j] = head[parent[j]]
            head[parent[j]] = j
    k = 0
    for j in range(n):
        if parent[j] != -1:
            continue
        top = 0
        stack[0] = j
        while top >= 0:
            node = stack[top]
            child = head[node]
            if child == -1:
                top -= 1
                post[k] = node
                k += 1
            else:
                head[node] = nxt[child]
                top += 1
                stack[top] = child
    return post


@numba.njit(cache=True)
def _column_counts(Ap, Ai, p, pinv, parent):  # pragma: no cover - compiled
    """Entries of every column of L (diagonal included) for a[p][:, p] whose elimination tree
    parent is postordered (children before parents): row subtrees and least common ancestors
    (Gilbert, Ng and Peyton 1994; Davis 2006, 4.5, cs_counts)."""
    n = p.shape[0]
    first = np.full(n, -1, np.int64)
    maxfirst = np.full(n, -1, np.int64)
    prevleaf = np.full(n, -1, np.int64)
    ancestor = np.arange(n)
    delta = np.zeros(n, np.int64)
    for k in range(n):
        j = k
        delta[j] = 1 if first[j] == -1 else 0      # a leaf of the tree
        while j != -1 and first[j] == -1:
            first[j] = k
            j = parent[j]
    for j in range(n):
        if parent[j] != -1:
            delta[parent[j]] -= 1
        col = p[j]
        for q in range(Ap[col], Ap[col + 1]):
            i = pinv[Ai[q]]
            if i <= j or first[j] <= maxfirst[i]:
                continue                            # j is not a leaf of row i's subtree
            maxfirst[i] = first[j]
            jprev = prevleaf[i]
            prevleaf[i] = j
            delta[j] += 1
            if jprev != -1:                         # subtract at the least common ancestor
                lca = jprev
                while lca != ancestor[lca]:
                    lca = ancestor[lca]
                s = jprev
                while s != lca:
                    up = ancestor[s]
                    ancestor[s] = lca
                    s = up
                delta[lca] -= 1
        if parent[j] != -1:
            ancestor[j] = parent[j]
    for j in range(n):
        if parent[j] != -1:
            delta[parent[j]] += delta[j]
    return delta


@numba.njit(cache=True)
def _supernodes(parent, counts, relax_width, relax_zeros):  # pragma: no cover - compiled
    """Start columns of the relaxed supernodes of a postordered elimination tree with column
    counts `counts`: fundamental supernodes (column j + 1 is j's parent and j's structure is
    its own plus j + 1's), then a child merged into the supernode right after it when that
    is its parent and the merge keeps within the amalgamation limits. Returns (starts,
    count of each supernode's first column: its width plus its rows below)."""
    n = parent.shape[0]
    fs = np.empty(n + 1, np.int64)
    ns = 0
    for j in range(n):
        if j == 0 or not (parent[j - 1] == j and counts[j - 1] == counts[j] + 1):
            fs[ns] = j
            ns += 1
    fs[ns] = n
    col_sn = np.empty(n, np.int64)
    for s in range(ns):
        for j in range(fs[s], fs[s + 1]):
            col_sn[j] = s
    width = np.empty(ns, np.int64)     # of the group starting at s (s and what merged into it)
    first_count = np.empty(ns, np.int64)
    entries = np.empty(ns, np.float64)
    zeros = np.empty(ns, np.float64)
    merged = np.zeros(ns, np.bool_)    # s + 1's group was merged into s
    for s in range(ns - 1, -1, -1):
        w = fs[s + 1] - fs[s]
        c = counts[fs[s]]
        own = w * c - w * (w - 1) / 2.0
        width[s], first_count[s], entries[s], zeros[s] = w, c, own, 0.0
        last = fs[s + 1] - 1
        if s + 1 < ns and parent[last] == fs[s + 1]:
            ww = w + width[s + 1]
            cc = w + first_count[s + 1]
            tot = ww * cc - ww * (ww - 1) / 2.0
            z = tot - own - (entries[s + 1] - zeros[s + 1])
            frac = z / tot
            ok = (ww <= relax_width[0] or (ww <= relax_width[1] and frac < relax_zeros[0])
                  or (ww <= relax_width[2] and frac < relax_zeros[1]) or frac < relax_zeros[2])
            if ok:
                merged[s] = True
                width[s], first_count[s], entries[s], zeros[s] = ww, cc, tot, z
    starts = np.empty(ns + 1, np.int64)
    sn_count = np.empty(ns, np.int64)
    m = 0
    s = 0
    while s < ns:
        starts[m] = fs[s]
        sn_count[m] = first_count[s]
        m += 1
        t = s
        while merged[t]:
            t += 1
        s = t + 1
    starts[m] = n
    return starts[: m + 1], sn_count[:m]


@numba.njit(cache=True, inline="always")
def _add_row(i, s, c1, mark, rows, base, cnt, size):  # pragma: no cover - compiled
    """Row i joins supernode s's structure (below its last column c1 - 1, once); the count."""
    if i >= c1 and mark[i] != s:
        if cnt == size:
            raise ValueError("supernode row structure exceeds its column count")
        mark[i] = s
        rows[base + cnt] = i
        cnt += 1
    return cnt


@numba.njit(cache=True)
def _structure(Ap, Ai, p, pinv, parent, starts, sn_count):  # pragma: no cover - compiled
    """Row structure below every supernode (sorted), its parent supernode and the children
    lists (CSR): rows = A's rows in its columns below it, with its children's rows below it.
    Returns (r_off, rows, sn_parent, child_ptr, child_idx)."""
    n = p.shape[0]
    ns = starts.shape[0] - 1
    col_sn = np.empty(n, np.int64)
    r_off = np.zeros(ns + 1, np.int64)
    for s in range(ns):
        for j in range(starts[s], starts[s + 1]):
            col_sn[j] = s
        r_off[s + 1] = r_off[s] + sn_count[s] - (starts[s + 1] - starts[s])
    sn_parent = np.full(ns, -1, np.int64)
    n_children = np.zeros(ns + 1, np.int64)
    for s in range(ns):
        up = parent[starts[s + 1] - 1]
        if up != -1:
            sn_parent[s] = col_sn[up]
            n_children[col_sn[up] + 1] += 1
    child_ptr = np.cumsum(n_children)
    child_idx = np.empty(child_ptr[ns], np.int64)
    fill = child_ptr[:ns].copy()
    for s in range(ns):
        if sn_parent[s] != -1:
            child_idx[fill[sn_parent[s]]] = s
            fill[sn_parent[s]] += 1
    rows = np.empty(r_off[ns], np.int32)
    mark = np.full(n, -1, np.int64)
    for s in range(ns):
        c1 = starts[s + 1]
        base = r_off[s]
        size = r_off[s + 1] - base
        cnt = 0
        for j in range(starts[s], c1):
            col = p[j]
            for q in range(Ap[col], Ap[col + 1]):
                cnt = _add_row(pinv[Ai[q]], s, c1, mark, rows, base, cnt, size)
        for t in range(child_ptr[s], child_ptr[s + 1]):
            c = child_idx[t]
            for q in range(r_off[c], r_off[c + 1]):
                cnt = _add_row(rows[q], s, c1, mark, rows, base, cnt, size)
        if cnt != size:
            raise ValueError("supernode row structure differs from its column count")
        rows[base: base + size].sort()
    return r_off, rows, sn_parent, child_ptr, child_idx


@numba.njit(cache=True)
def _no_fronts(ns):  # pragma: no cover - compiled
    """A list of ns empty fronts (a front is kept there until its parent has used it)."""
    fronts = List()
    for _ in range(ns):
        fronts.append(np.empty(0))
    return fronts


@numba.njit(nogil=True, cache=True)
def _numeric(sns, Ap, Ai, Ax, p, pinv, starts, r_off, rows, child_ptr, child_idx, sn_parent,
             t_off, b_off, tri, rect, d, fronts, other):  # pragma: no cover - compiled
    """Multifrontal L D L^T of a[p][:, p] over the supernodes sns (ascending: children
    first) into fe.ldl's packed layout (tri: unit lower triangles, row-major; rect: the rows
    below, row-major; d). A supernode's front is left in fronts for its parent; a child's is
    taken from fronts, else from other (the list of the other etree half, whose subtrees a
    top supernode also has as children). Returns -1, or the column at which a pivot was not
    positive (the matrix is not positive definite)."""
    n = p.shape[0]
    pos = np.empty(n, np.int64)
    ch = np.empty(4, np.uint8)
    ch[0], ch[1], ch[2], ch[3] = 76, 82, 84, 78            # 'L', 'R', 'T', 'N'
    iv = np.empty(4, np.int32)                             # w, m, r, info
    dv = np.empty(2)
    dv[0], dv[1] = 1.0, -1.0
    for k in range(sns.shape[0]):
        s = sns[k]
        c0 = starts[s]
        w = starts[s + 1] - c0
        base = r_off[s]
        r = r_off[s + 1] - base
        m = w + r
        F = np.zeros(m * m)                                # column-major front, lower part
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
        for t in range(child_ptr[s], child_ptr[s + 1]):    # extend-add
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
        iv[0], iv[1], iv[2], iv[3] = w, m, r, 0
        dpotrf(ch[0:].ctypes, iv[0:].ctypes, F.ctypes, iv[1:].ctypes, iv[3:].ctypes)
        if iv[3] != 0:
            return c0 + iv[3] - 1
        if r > 0:
            below = F[w:]
            dtrsm(ch[1:].ctypes, ch[0:].ctypes, ch[2:].ctypes, ch[3:].ctypes, iv[2:].ctypes,
                   iv[0:].ctypes, dv[0:].ctypes, F.ctypes, iv[1:].ctypes, below.ctypes,
                   iv[1:].ctypes)
            update = F[w + w * m:]
            dsyrk(ch[0:].ctypes, ch[3:].ctypes, iv[2:].ctypes, iv[0:].ctypes, dv[1:].ctypes,
                   below.ctypes, iv[1:].ctypes, dv[0:].ctypes, update.ctypes, iv[1:].ctypes)
        t0 = t_off[s]
        b0 = b_off[s]
        for a in range(w):
            piv = F[a + a * m]
            d[c0 + a] = piv * piv
            inv = 1.0 / piv
            for a2 in range(a + 1, w):
                tri[t0 + a2 * w + a] = F[a2 + a * m] * inv
            for i in range(r):
                rect[b0 + i * w + a] = F[w + i + a * m] * inv
        if sn_parent[s] != -1:
            fronts[s] = F
    return -1


class SymbolicFactor:
    """The ordering and supernodal structure of L for one sparsity pattern (reusable for
    any matrix of that pattern: numeric factorizations with other values)."""

    def __init__(self, a: sp.spmatrix, order: np.ndarray | None = None):
        """a: SPD sparse matrix (its full symmetric pattern is used); order: elimination
        order (default mmd_order(a))."""
        from flexmvm.fe.ldl import split_halves
        a = _symmetric_csc(a)
        n = a.shape[0]
        p0 = mmd_order(a) if order is None else np.asarray(order, np.int64)
        Ap = a.indptr.astype(np.int64)
        Ai = a.indices
        pinv0 = np.empty(n, np.int64)
        pinv0[p0] = np.arange(n)
        parent0 = _etree(Ap, Ai, p0, pinv0)
        post = _postorder(parent0)
        p = p0[post]                          # postordered: same fill, supernodes contiguous
        pinv = np.empty(n, np.int64)
        pinv[p] = np.arange(n)
        parent = _relabel(parent0, post)
        counts = _column_counts(Ap, Ai, p, pinv, parent)
        starts, sn_count = _supernodes(parent, counts, np.asarray(RELAX_WIDTH, np.int64),
                                       np.asarray(RELAX_ZEROS, np.float64))
        r_off, rows, sn_parent, child_ptr, child_idx = _structure(Ap, Ai, p, pinv, parent,
                                                                  starts, sn_count)
        width = np.diff(starts)
        below = np.diff(r_off)
        self.n = n
        self.order, self.inverse = p, pinv
        self.column_counts = counts
        self.starts, self.r_off, self.rows = starts, r_off, rows
        self.sn_parent, self.child_ptr, self.child_idx = sn_parent, child_ptr, child_idx
        self.t_off = np.concatenate([[0], np.cumsum(width * width)]).astype(np.int64)
        self.b_off = np.concatenate([[0], np.cumsum(below * width)]).astype(np.int64)
        self._pattern = (Ap, Ai.copy())
        self.given_order = p0
        #: (first, second, top) supernodes for a factor on two threads, or None
        self.halves = split_halves(starts, r_off, rows)

    def matches(self, a: sp.spmatrix) -> bool:
        """Whether a has the sparsity pattern this analysis was made for."""
        a = _symmetric_csc(a)
        Ap, Ai = self._pattern
        return (a.shape == (self.n, self.n) and a.nnz == Ai.size
                and np.array_equal(a.indptr, Ap) and np.array_equal(a.indices, Ai))

    @property
    def nnz(self) -> int:
        """Entries of L stored (diagonal and amalgamation zeros included)."""
        from flexmvm.fe.ldl import stored_entries
        return stored_entries(self.starts, self.r_off)


def _relabel(parent0: np.ndarray, post: np.ndarray) -> np.ndarray:
    """The elimination tree in postorder labels: parent[k] of the node post[k]."""
    where = np.empty_like(post)
    where[post] = np.arange(post.size)
    up = parent0[post]
    return np.where(up >= 0, where[np.maximum(up, 0)], -1).astype(np.int64)


def numeric_factor(symbolic: SymbolicFactor, a: sp.spmatrix, pool=None):
    """The packed L D L^T of a (the pattern `symbolic` was made for): (tri, rect, d). With a
    pool, the two elimination-tree halves (fe.ldl.etree_halves) are factored on two threads
    (the same arithmetic as on one: bit for bit), then the top of the tree.
    Raises SolverError when a pivot is not positive (a is not positive definite)."""
    a = _symmetric_csc(a)
    if not symbolic.matches(a):
        raise SolverError("Cholesky factor: the matrix has another sparsity pattern than "
                          "its symbolic analysis")
    if not np.isfinite(a.data).all():
        raise SolverError(f"Cholesky factor of a {symbolic.n}x{symbolic.n} matrix: it holds "
                          "a non-finite number (NaN/inf)")
    tri = np.zeros(symbolic.t_off[-1])
    rect = np.empty(symbolic.b_off[-1])
    d = np.empty(symbolic.n)
    ns = symbolic.starts.shape[0] - 1
    mine, theirs = _no_fronts(ns), _no_fronts(ns)
    args = (symbolic._pattern[0], symbolic._pattern[1], np.asarray(a.data, np.float64),
            symbolic.order, symbolic.inverse, symbolic.starts, symbolic.r_off, symbolic.rows,
            symbolic.child_ptr, symbolic.child_idx, symbolic.sn_parent, symbolic.t_off,
            symbolic.b_off, tri, rect, d)
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
        raise SolverError(f"Cholesky factor of a {symbolic.n}x{symbolic.n} matrix: pivot "
                          f"{bad} of its elimination order is not positive (the matrix is not "
                          "positive definite)")
    return tri, rect, d


def _symmetric_csc(a: sp.spmatrix) -> sp.csc_matrix:
    """a as CSC; of a symmetric CSR matrix its transpose (the same matrix, no copy)."""
    if sp.issparse(a) and a.format == "csr":
        return a.T
    return sp.csc_matrix(a)


def cholesky_ldl(a: sp.spmatrix, pool=None, symbolic: SymbolicFactor | None = None):
    """fe.ldl.SupernodalLDL of the SPD sparse matrix a factored here (module docstring):
    `solve(b)` for b (n,) or (n, k); with a pool the factor and the solves take the two
    elimination-tree halves on two threads. a is symmetric: of a CSR matrix, its transpose
    (CSC, no copy) is factored. symbolic: the analysis of a's pattern, when already made
    (default: made here; one of another pattern is remade with its order). With a pool, the
    compiled kernels are loaded on its thread while SuperLU orders a (~0.2 s in a fresh
    process, hidden).
    Raises SolverError when a is not positive definite or the check of the solve fails."""
    from flexmvm.fe.ldl import SupernodalLDL
    csc = _symmetric_csc(a)
    if symbolic is None:
        warm = pool.submit(warm_kernels) if pool is not None and not _WARM else None
        order = mmd_order(csc)
        if warm is not None:
            warm.result()
        symbolic = SymbolicFactor(csc, order)
    elif not symbolic.matches(csc):
        symbolic = SymbolicFactor(csc, symbolic.given_order)
    tri, rect, d = numeric_factor(symbolic, csc, pool)
    factor = (symbolic.starts, symbolic.t_off, symbolic.b_off, symbolic.r_off, tri, rect,
              symbolic.rows)
    return SupernodalLDL(symbolic.inverse, factor, d, symbolic.halves, pool, a=a)


def ldl_factor(a: sp.spmatrix, pool=None):
    """x = solve(b) for the SPD sparse matrix a (b (n,) or (n, k)): cholesky_ldl with SuperLU's
    minimum-degree ordering. Raises SolverError when a is not positive definite."""
    return cholesky_ldl(a, pool).solve


_WARM = False   # the kernels are loaded in this process (warm_kernels ran)


def warm_kernels() -> None:
    """Load (or compile, the first time) every kernel of a factor and of a split solve, once
    per process: one factor and solve of a small diagonal matrix (its forest of an
    elimination tree splits)."""
    global _WARM
    from flexmvm.fe.ldl import SPLIT_MIN_N
    n = SPLIT_MIN_N
    eye = sp.identity(n, format="csc")
    cholesky_ldl(eye, symbolic=SymbolicFactor(eye, np.arange(n))).solve(np.ones(n))
    _WARM = True


__all__ = ["RELAX_WIDTH", "RELAX_ZEROS", "SymbolicFactor", "cholesky_ldl", "ldl_factor",
           "mmd_order", "numeric_factor", "warm_kernels"]
