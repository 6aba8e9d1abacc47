"""The one seam through which this package solves with a sparse SPD matrix: spd_solver(a)
returns x = solve(b). Which factorization stands behind it is a policy of its size and of a
setting, FLEXMVM_CHOLESKY:

- "supernodal" (default): from CHOLESKY_MIN_N rows the supernodal L D L^T of
  fe.solvers.cholesky, solved by fe.solvers.ldl; below, SuperLU with the symmetric ordering
  SPD_LU (fe.solvers.superlu);
- "cholmod": CHOLMOD's Cholesky (fe.solvers.cholmod; optional, ``flexmvm[cholmod]``) from
  CHOLESKY_MIN_N rows; below, SuperLU as by default.

Either way SuperLU's LU is taken when the Cholesky refuses a (a pivot not positive, or the
check of its solve fails), so a symmetric indefinite or unsymmetric matrix still solves.
"""

from __future__ import annotations

import enum
import os
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager

import scipy.sparse as sp

from flexmvm.errors import SolverError
from flexmvm.fe.solvers.superlu import Solve, superlu_spd
from flexmvm.threads import worker_threads

#: Environment variable: the Cholesky behind spd_solver (CholeskyBackend's values).
ENV_CHOLESKY = "FLEXMVM_CHOLESKY"

#: From this many rows spd_solver factors with a Cholesky (0.6 s for a seed rod's K_ii,
#: 24,972 DOFs, against 1.1 s for SuperLU's LU and 0.5 s more to solve it as L D L^T); below,
#: SuperLU (milliseconds, less than loading fe.solvers.cholesky's kernels in a fresh process,
#: ~0.2 s).
CHOLESKY_MIN_N = 2000


class CholeskyBackend(enum.Enum):
    """The Cholesky factorization behind spd_solver (module docstring)."""

    SUPERNODAL = "supernodal"  #: fe.solvers.cholesky + fe.solvers.ldl: the default
    CHOLMOD = "cholmod"  #: SuiteSparse's CHOLMOD through cholespy: optional


def cholesky_backend() -> CholeskyBackend:
    """The backend set by FLEXMVM_CHOLESKY (default SUPERNODAL). Raises SolverError for an
    unknown value."""
    value = os.environ.get(ENV_CHOLESKY, "").strip().lower()
    if not value:
        return CholeskyBackend.SUPERNODAL
    try:
        return CholeskyBackend(value)
    except ValueError:
        known = ", ".join(b.value for b in CholeskyBackend)
        raise SolverError(f"{ENV_CHOLESKY} must be one of {known}, got {value!r}") from None


@contextmanager
def solver_pool() -> Iterator[ThreadPoolExecutor | None]:
    """A one-worker thread pool for the second elimination-tree half of an LDL^T solve
    (spd_solver), or None when FLEXMVM_THREADS allows one thread only (flexmvm.threads)."""
    if worker_threads() < 2:
        yield None
        return
    with ThreadPoolExecutor(max_workers=1, thread_name_prefix="flexmvm-ldl") as pool:
        yield pool


def spd_solver(
    a: sp.spmatrix, pool: ThreadPoolExecutor | None = None, backend: CholeskyBackend | None = None
) -> Solve:
    """x = solve(b) for the SPD sparse matrix a (b (n,) or (n, k)): from CHOLESKY_MIN_N rows
    the Cholesky of ``backend`` (default: cholesky_backend(), the FLEXMVM_CHOLESKY setting);
    the supernodal one solves several right-hand sides in one pass over the factor, the two
    elimination-tree halves on two threads with a pool. Below CHOLESKY_MIN_N rows, and where
    the Cholesky refuses a, SuperLU with the symmetric ordering SPD_LU (which fails as
    fe.solvers.superlu.factor does: SolverError). Raises SolverError for CHOLMOD when
    cholespy is not installed (a setting asked for it: no silent fallback)."""
    if backend is None:
        backend = cholesky_backend()
    if backend is CholeskyBackend.CHOLMOD:
        from flexmvm.fe.solvers import cholmod

        if not cholmod.available():
            raise SolverError(
                f"{ENV_CHOLESKY}=cholmod needs the {cholmod.PACKAGE} package "
                "(pip install flexmvm[cholmod])"
            )
    if a.shape[0] < CHOLESKY_MIN_N:
        return superlu_spd(a).solve
    try:
        if backend is CholeskyBackend.CHOLMOD:
            from flexmvm.fe.solvers.cholmod import CholmodFactor

            return CholmodFactor(a).solve
        from flexmvm.fe.solvers.cholesky import cholesky_ldl

        return cholesky_ldl(a, pool).solve
    except SolverError:
        return superlu_spd(a).solve


__all__ = [
    "CHOLESKY_MIN_N",
    "ENV_CHOLESKY",
    "CholeskyBackend",
    "cholesky_backend",
    "solver_pool",
    "spd_solver",
]
