"""CHOLMOD's sparse Cholesky (SuiteSparse; Chen, Davis, Hager and Rajamanickam, ACM TOMS 35,
2008), an optional backend of spd_solver (fe.solvers.spd), through the ``cholespy`` package
(``pip install flexmvm[cholmod]``): a supernodal L L^T with its own fill-reducing ordering
(AMD or METIS), solving several right-hand sides at once.

It is not the default: its ordering is not SuperLU's, so its factor and the modes built on
it differ from the default's in the last bits, and a stored result (keyed by the package
source, not by this setting) would no longer be reproduced bit for bit.
"""

from __future__ import annotations

import importlib.util

import numpy as np
import scipy.sparse as sp

from flexmvm.errors import SolverError
from flexmvm.fe.solvers.ldl import BACKWARD_RTOL, backward_error

#: The package that binds CHOLMOD.
PACKAGE = "cholespy"


def available() -> bool:
    """Whether the CHOLMOD binding (PACKAGE) is installed."""
    return importlib.util.find_spec(PACKAGE) is not None


class CholmodFactor:
    """x = A^-1 b by CHOLMOD's Cholesky factor of the SPD sparse matrix a (n, n): ``solve(b)``
    for b (n,) or (n, k). Checked as fe.solvers.ldl checks its own factor: a solve's backward
    error at most BACKWARD_RTOL (CHOLMOD reads one triangle of a, so an unsymmetric a
    factors silently and fails there). Raises SolverError when a is not positive definite,
    fails that check, or holds a non-finite number, and when cholespy is not installed."""

    def __init__(self, a: sp.spmatrix):
        if not available():
            raise SolverError(
                f"the CHOLMOD backend needs the {PACKAGE} package (pip install flexmvm[cholmod])"
            )
        from cholespy import CholeskySolverD, MatrixType

        csc = sp.csc_matrix(a)
        self.n = csc.shape[0]
        if not np.isfinite(csc.data).all():
            raise SolverError(
                f"CHOLMOD factor of a {self.n}x{self.n} matrix: it holds a "
                "non-finite number (NaN/inf)"
            )
        try:
            self._solver = CholeskySolverD(
                self.n,
                csc.indptr.astype(np.int32),
                csc.indices.astype(np.int32),
                np.ascontiguousarray(csc.data, np.float64),
                MatrixType.CSC,
            )
        except (ValueError, RuntimeError) as exc:
            raise SolverError(
                f"CHOLMOD factor of a {self.n}x{self.n} matrix failed: {exc}"
            ) from None
        err = backward_error(csc, self.solve)
        if not err <= BACKWARD_RTOL:
            raise SolverError(
                f"CHOLMOD solve has a backward error of {err:.1e} (the matrix "
                "is not symmetric positive definite?)"
            )

    def solve(self, b: np.ndarray) -> np.ndarray:
        b = np.ascontiguousarray(b, np.float64)
        x = np.empty_like(b)
        self._solver.solve(b, x)
        return x

    __call__ = solve


__all__ = ["PACKAGE", "CholmodFactor", "available"]
