"""Fill-reducing orderings: SuperLU's minimum degree (mmd_order), and one with two independent
halves, for solves on two threads (dissection_order).

SuperLU's minimum degree (mmd_order) orders a rod's W = M + (theta h)^2 K with little
fill, but where its elimination tree branches is up to the mesh: on the seed's aluminium rod
it splits into two subtrees of ~45 % of the factor each, on the brass rod with the
hemispherical end it ends in a chain of 37 cross-section supernodes holding 56 % of it, which
one thread must take alone (fe.solvers.ldl.etree_halves).

One level of nested dissection fixes the tree's top: a level set of a breadth-first search
from a pseudo-peripheral vertex separates the graph (every edge joins equal or adjacent levels;
George and Liu, "Computer Solution of Large Sparse Positive Definite Systems", 1981, ch. 4
and 7); the level at which half the vertices have been reached is taken as the separator and
ordered last. The two sides are ordered by SuperLU's minimum degree of the pattern with the
separator made a clique (so the vertices next to it are eliminated late, as constrained
minimum degree would; Liu 1989), in one ordering of the whole. On the seed's rods (25,767
and 25,041 DOFs): factor entries +0.4 % and -0.5 % of plain minimum degree, two halves of ~47 %
each, so a solve runs on two threads (timings: docs/notes/2026-11-27-comment-measurements.md).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse import csgraph

from flexmvm.fe.solvers import ldl
from flexmvm.fe.solvers.superlu import SPD_LU

#: The separator is used when it holds at most this fraction of the vertices (a larger one
#: is not a rod-like body's cross-section: the dissection would add fill for little).
MAX_SEPARATOR_FRACTION = 0.1


def mmd_order(a: sp.spmatrix) -> np.ndarray:
    """Elimination order p of the SPD matrix a (a[p][:, p] has little fill): SuperLU's
    minimum degree of A^T + A, read off an incomplete factorization that drops every entry
    (the permutation is computed before any numeric work: the same as splu's with
    fe.solvers.superlu.SPD_LU)."""
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
    order[perm_c] = np.arange(perm_c.size)  # perm_c[i]: position of column i
    return order


def _ones(a: sp.spmatrix) -> sp.csr_matrix:
    """The sparsity pattern of a as a CSR matrix of ones."""
    pattern = sp.csr_matrix(a, dtype=float, copy=True)
    pattern.data[:] = 1.0
    return pattern


def _levels(pattern: sp.csr_matrix, root: int) -> np.ndarray:
    """Breadth-first level of every vertex from root (-1: not reached)."""
    d = csgraph.shortest_path(pattern, unweighted=True, indices=root, directed=False)
    return np.where(np.isfinite(d), d, -1).astype(np.int64)


def dissection_order(a: sp.spmatrix) -> np.ndarray | None:
    """Elimination order p (a permutation of range(n): a[p][:, p] is factored in natural
    order) of the symmetric matrix a, with a one-level separator last (module docstring);
    None when the graph of a is disconnected or has no separator of at most
    MAX_SEPARATOR_FRACTION of its vertices."""
    n = a.shape[0]
    if n < 3:
        return None
    pattern = _ones(a)
    level = _levels(pattern, 0)
    if np.any(level < 0):
        return None
    level = _levels(pattern, int(np.argmax(level)))  # from a pseudo-peripheral vertex
    mid = int(np.searchsorted(np.cumsum(np.bincount(level)), n / 2))
    sep = np.flatnonzero(level == mid)
    if not (0 < mid < level.max()) or len(sep) > MAX_SEPARATOR_FRACTION * n:
        return None
    # minimum degree of the pattern with the separator a clique (values: a diagonally
    # dominant SPD matrix of that pattern, for SuperLU's ordering only)
    k = len(sep)
    clique = sp.csr_matrix((np.ones(k * k), (np.repeat(sep, k), np.tile(sep, k))), shape=a.shape)
    aug = ((pattern + pattern.T + clique) != 0).astype(float)
    aug = sp.csc_matrix(aug + sp.diags(np.asarray(aug.sum(axis=1)).ravel() + 1.0))
    order = mmd_order(aug)
    last = np.zeros(n, bool)
    last[sep] = True
    return np.concatenate([order[~last[order]], sep]).astype(np.int64)


def elimination_order(a: sp.spmatrix) -> np.ndarray | None:
    """The order the integrator factors a sparse iteration matrix a with: dissection_order
    from SPLIT_MIN_N rows (fe.solvers.ldl: solves in two halves), else None (SuperLU's minimum
    degree)."""
    return dissection_order(a) if a.shape[0] >= ldl.SPLIT_MIN_N else None


def iteration_pattern(
    M_qq: sp.spmatrix, k_hat: sp.spmatrix, c_hat: sp.spmatrix | None = None
) -> sp.csr_matrix:
    """The sparsity pattern (ones) of W = M_qq + theta h C + (theta h)^2 K, the same for
    every step size."""
    parts = [M_qq, k_hat] + ([c_hat] if c_hat is not None else [])
    return _ones(sum(abs(sp.csr_matrix(p)) for p in parts))
