"""Solves with small dense factors straight through LAPACK (dpotrs, dgetrs).

scipy.linalg.cho_solve and lu_solve call the same routines but pass every call through
argument checks and array-API wrappers: ~45 us against ~5 us for the 6 x 6 frame Schur
complements and the reduced bodies' W that a step solves with a dozen times. Same routine,
same arguments: the results are bit for bit those of scipy's functions.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import dgetrs, dpotrs

from flexmvm.errors import SolverError


def cho_solve(cho: tuple[np.ndarray, bool], b: np.ndarray) -> np.ndarray:
    """x = A^-1 b for cho = scipy.linalg.cho_factor(A) (b (n,) or (n, k))."""
    c, lower = cho
    x, info = dpotrs(c, b, lower=int(lower))
    if info:
        raise SolverError(f"dpotrs: illegal argument {-info}")
    return x


def lu_solve(lu_piv: tuple[np.ndarray, np.ndarray], b: np.ndarray) -> np.ndarray:
    """x = A^-1 b for lu_piv = scipy.linalg.lu_factor(A) (b (n,) or (n, k))."""
    lu, piv = lu_piv
    x, info = dgetrs(lu, piv, b)
    if info:
        raise SolverError(f"dgetrs: illegal argument {-info}")
    return x
