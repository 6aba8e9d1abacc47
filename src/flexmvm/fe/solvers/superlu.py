"""SuperLU (scipy.sparse.linalg.splu) with this package's policy for SPD matrices.

Every matrix this package factors as SPD (K_ii, K - sigma M with sigma <= 0,
M + theta^2 h^2 K) takes SPD_LU: SuperLU's minimum-degree ordering of A^T + A and no
pivoting off the diagonal. SuperLU's default (COLAMD, partial pivoting) orders for an
unsymmetric A, and its fill on our meshes is erratic: 108 million factor entries (28 s)
against 22 million (1.2 s) for K_ii of the seed rod with the 3-4 selection retained.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from flexmvm.errors import SolverError

#: x = solve(b) for b (n,) or (n, k): what every factorization of this subpackage returns.
Solve = Callable[[np.ndarray], np.ndarray]

#: SuperLU options for symmetric positive definite matrices (module docstring).
SPD_LU = {
    "permc_spec": "MMD_AT_PLUS_A",
    "diag_pivot_thresh": 0.0,
    "options": {"SymmetricMode": True},
}


def factor(a: sp.spmatrix, spd: bool = True) -> Solve:
    """Sparse LU of a square matrix; returns x = solve(b) for b (n,) or (n, k).

    spd: the matrix is symmetric positive definite (symmetric ordering, diagonal pivots,
    SPD_LU); False: SuperLU's general defaults.
    Raises SolverError if the matrix is singular or holds NaN/inf.
    """
    return _superlu(a, SPD_LU if spd else {}).solve


def superlu_spd(a: sp.spmatrix):
    """SuperLU's factor object of the SPD matrix a with the symmetric ordering SPD_LU (below
    fe.solvers.spd.CHOLESKY_MIN_N rows, and where the supernodal Cholesky refuses a). Raises
    SolverError as factor does."""
    return _superlu(a, SPD_LU)


def _superlu(a: sp.spmatrix, options: dict):
    data = a.data if sp.issparse(a) else np.asarray(a)
    if not np.isfinite(data).all():
        raise SolverError(
            f"sparse LU of a {a.shape[0]}x{a.shape[0]} matrix: it holds a "
            "non-finite number (NaN/inf)"
        )
    try:
        return spla.splu(sp.csc_matrix(a), **options)
    except RuntimeError as exc:
        raise SolverError(
            f"sparse LU of a {a.shape[0]}x{a.shape[0]} matrix failed: {exc}"
        ) from None


__all__ = ["SPD_LU", "Solve", "factor", "superlu_spd"]
