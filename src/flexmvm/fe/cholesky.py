"""Former path of the supernodal Cholesky, kept for the modules that import it from here; its
parts now live in fe.solvers: cholesky (the numeric factor), symbolic (SymbolicFactor),
ordering (mmd_order). New code imports those."""

from flexmvm.fe.solvers.cholesky import cholesky_ldl, ldl_factor, numeric_factor, warm_kernels
from flexmvm.fe.solvers.ordering import mmd_order
from flexmvm.fe.solvers.symbolic import RELAX_WIDTH, RELAX_ZEROS, SymbolicFactor

__all__ = [
    "RELAX_WIDTH",
    "RELAX_ZEROS",
    "SymbolicFactor",
    "cholesky_ldl",
    "ldl_factor",
    "mmd_order",
    "numeric_factor",
    "warm_kernels",
]
