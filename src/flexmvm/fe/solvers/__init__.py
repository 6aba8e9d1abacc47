"""Sparse direct solvers of the FE stage, one room for all of them:

- superlu: SuperLU with the SPD policy SPD_LU (factor, superlu_spd) and the Solve type;
- ordering: fill-reducing orders (SuperLU's minimum degree, one-level dissection);
- symbolic: elimination tree, column counts and supernodes of a pattern (SymbolicFactor);
- cholesky: the supernodal multifrontal L D L^T (cholesky_ldl, ldl_factor);
- ldl: its packed layout and solves (SupernodalLDL), optionally on two threads;
- blas: the BLAS/LAPACK routines those kernels call;
- cholmod: CHOLMOD's Cholesky, an optional backend (flexmvm[cholmod]);
- spd: spd_solver, the seam that picks one of them for an SPD matrix (FLEXMVM_CHOLESKY).

Imports point one way: superlu, blas <- ldl <- ordering <- symbolic <- cholesky <- spd.
"""

from flexmvm.fe.solvers.spd import (
    CHOLESKY_MIN_N,
    ENV_CHOLESKY,
    CholeskyBackend,
    cholesky_backend,
    solver_pool,
    spd_solver,
)
from flexmvm.fe.solvers.superlu import SPD_LU, Solve, factor, superlu_spd

__all__ = [
    "CHOLESKY_MIN_N",
    "ENV_CHOLESKY",
    "SPD_LU",
    "CholeskyBackend",
    "Solve",
    "cholesky_backend",
    "factor",
    "solver_pool",
    "spd_solver",
    "superlu_spd",
]
