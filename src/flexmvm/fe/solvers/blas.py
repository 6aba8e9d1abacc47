"""BLAS and LAPACK routines for numba kernels: the ones scipy ships (scipy.linalg.cython_blas,
cython_lapack), bound by symbol name so that numba's disk cache keeps the kernels that call
them (a raw function address would differ in every process).

Every argument is a pointer (Fortran calling convention): pass ``array.ctypes`` of a
one-element uint8 array for a character, of an int32 array for an integer, of a float64 array
for a scalar or matrix (column-major, leading dimension given).
"""

from __future__ import annotations

from llvmlite import binding as _llvm
from numba import types
from numba.extending import get_cython_function_address

_ROUTINES = {
    "dpotrf": ("scipy.linalg.cython_lapack", 5),
    "dtrsm": ("scipy.linalg.cython_blas", 11),
    "dsyrk": ("scipy.linalg.cython_blas", 10),
    "dgemm": ("scipy.linalg.cython_blas", 13),
}


def _bind(name: str):
    module, n_args = _ROUTINES[name]
    symbol = f"flexmvm_{name}"
    _llvm.add_symbol(symbol, get_cython_function_address(module, name))
    return types.ExternalFunction(symbol, types.void(*[types.voidptr] * n_args))


#: (uplo, n, a, lda, info): Cholesky factor of a.
dpotrf = _bind("dpotrf")
#: (side, uplo, transa, diag, m, n, alpha, a, lda, b, ldb): b := alpha op(a)^-1 b or b op(a)^-1.
dtrsm = _bind("dtrsm")
#: (uplo, trans, n, k, alpha, a, lda, beta, c, ldc): c := alpha a a^T + beta c (or a^T a).
dsyrk = _bind("dsyrk")
#: (transa, transb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc): c := alpha op(a) op(b) + beta c.
dgemm = _bind("dgemm")

__all__ = ["dgemm", "dpotrf", "dsyrk", "dtrsm"]
