"""Small dense factors and their solves straight through LAPACK (dpotrf, dgetrf, dpotrs,
dgetrs).

scipy.linalg's cho_factor, lu_factor, cho_solve and lu_solve call the same routines but pass
every call through argument checks and array-API wrappers: ~45 us against ~5 us for the 6 x 6
frame Schur complements, the contact Delassus blocks and the reduced bodies' W that a step
factors or solves with a dozen times. Same routine, same arguments (cho_factor leaves the other
triangle as scipy's does): the results are bit for bit those of scipy's functions, and so are
the errors (LinAlgError for a matrix that is not positive definite, ValueError for a
non-finite one).
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.linalg import LinAlgWarning
from scipy.linalg.lapack import dgetrf, dgetrs, dpotrf, dpotrs

from flexmvm.errors import SolverError


def _finite(a) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    if not np.isfinite(a).all():
        raise ValueError("array must not contain infs or NaNs")  # as scipy's check
    return a


def cho_factor(a: np.ndarray, lower: bool = False) -> tuple[np.ndarray, bool]:
    """scipy.linalg.cho_factor(a, lower) (a (n, n) SPD): (c, lower), c holding the factor in
    its lower or upper triangle; LinAlgError when a is not positive definite."""
    c, info = dpotrf(_finite(a), lower=int(lower), clean=0)
    if info > 0:
        raise np.linalg.LinAlgError(
            f"{info}-th leading minor of the array is not positive definite"
        )
    if info < 0:
        raise ValueError(f"dpotrf: illegal argument {-info}")
    return c, lower


def lu_factor(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """scipy.linalg.lu_factor(a) (a (n, n)): (lu, piv); an exactly singular a warns as
    scipy's does (LinAlgWarning)."""
    lu, piv, info = dgetrf(_finite(a))
    if info > 0:
        warnings.warn(
            f"Diagonal number {info} is exactly zero. Singular matrix.", LinAlgWarning, stacklevel=2
        )
    if info < 0:
        raise ValueError(f"dgetrf: illegal argument {-info}")
    return lu, piv


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
