"""Symbolic analysis of a sparse symmetric positive definite matrix for its supernodal
L D L^T (Davis, "Direct Methods for Sparse Linear Systems", SIAM 2006, ch. 4): the
elimination tree (Liu's algorithm), its postorder, the column counts of L (row subtrees,
Gilbert, Ng and Peyton 1994), the fundamental supernodes, relaxed amalgamation (Ashcraft and
Grimes 1989; CHOLMOD's default limits) and every supernode's row structure. One analysis
serves every matrix of its pattern (fe.solvers.cholesky factors them).
"""

from __future__ import annotations

import numba
import numpy as np
import scipy.sparse as sp

from flexmvm.fe.solvers.ldl import split_halves, stored_entries
from flexmvm.fe.solvers.ordering import mmd_order

#: Relaxed amalgamation (CHOLMOD's defaults, cholmod_super.c): a child supernode is merged
#: into its parent when the merged one is w columns wide with a fraction z of explicit zeros
#: and w <= 4, or w <= 16 and z < 0.8, or w <= 48 and z < 0.1, or z < 0.05.
RELAX_WIDTH = (4, 16, 48)
RELAX_ZEROS = (0.8, 0.1, 0.05)


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
        delta[j] = 1 if first[j] == -1 else 0  # a leaf of the tree
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
                continue  # j is not a leaf of row i's subtree
            maxfirst[i] = first[j]
            jprev = prevleaf[i]
            prevleaf[i] = j
            delta[j] += 1
            if jprev != -1:  # subtract at the least common ancestor
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
    width = np.empty(ns, np.int64)  # of the group starting at s (s and what merged into it)
    first_count = np.empty(ns, np.int64)
    entries = np.empty(ns, np.float64)
    zeros = np.empty(ns, np.float64)
    merged = np.zeros(ns, np.bool_)  # s + 1's group was merged into s
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
            ok = (
                ww <= relax_width[0]
                or (ww <= relax_width[1] and frac < relax_zeros[0])
                or (ww <= relax_width[2] and frac < relax_zeros[1])
                or frac < relax_zeros[2]
            )
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
        rows[base : base + size].sort()
    return r_off, rows, sn_parent, child_ptr, child_idx


class SymbolicFactor:
    """The ordering and supernodal structure of L for one sparsity pattern (reusable for
    any matrix of that pattern: numeric factorizations with other values)."""

    def __init__(self, a: sp.spmatrix, order: np.ndarray | None = None):
        """a: SPD sparse matrix (its full symmetric pattern is used); order: elimination
        order (default mmd_order(a))."""
        a = symmetric_csc(a)
        n = a.shape[0]
        p0 = mmd_order(a) if order is None else np.asarray(order, np.int64)
        Ap = a.indptr.astype(np.int64)
        Ai = a.indices
        pinv0 = np.empty(n, np.int64)
        pinv0[p0] = np.arange(n)
        parent0 = _etree(Ap, Ai, p0, pinv0)
        post = _postorder(parent0)
        p = p0[post]  # postordered: same fill, supernodes contiguous
        pinv = np.empty(n, np.int64)
        pinv[p] = np.arange(n)
        parent = _relabel(parent0, post)
        counts = _column_counts(Ap, Ai, p, pinv, parent)
        starts, sn_count = _supernodes(
            parent, counts, np.asarray(RELAX_WIDTH, np.int64), np.asarray(RELAX_ZEROS, np.float64)
        )
        r_off, rows, sn_parent, child_ptr, child_idx = _structure(
            Ap, Ai, p, pinv, parent, starts, sn_count
        )
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
        a = symmetric_csc(a)
        Ap, Ai = self._pattern
        return (
            a.shape == (self.n, self.n)
            and a.nnz == Ai.size
            and np.array_equal(a.indptr, Ap)
            and np.array_equal(a.indices, Ai)
        )

    @property
    def nnz(self) -> int:
        """Entries of L stored (diagonal and amalgamation zeros included)."""
        return stored_entries(self.starts, self.r_off)


def _relabel(parent0: np.ndarray, post: np.ndarray) -> np.ndarray:
    """The elimination tree in postorder labels: parent[k] of the node post[k]."""
    where = np.empty_like(post)
    where[post] = np.arange(post.size)
    up = parent0[post]
    return np.where(up >= 0, where[np.maximum(up, 0)], -1).astype(np.int64)


def symmetric_csc(a: sp.spmatrix) -> sp.csc_matrix:
    """a as CSC; of a symmetric CSR matrix its transpose (the same matrix, no copy)."""
    if sp.issparse(a) and a.format == "csr":
        return a.T
    return sp.csc_matrix(a)


__all__ = ["RELAX_WIDTH", "RELAX_ZEROS", "SymbolicFactor", "symmetric_csc"]
