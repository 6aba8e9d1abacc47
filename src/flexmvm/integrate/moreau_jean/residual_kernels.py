"""The elementwise ends of a body's Moreau-Jean residual in compiled kernels (issue 49 item 3).

moreau_jean._residual forms, per body and Newton iterate, v_m = theta v+ + (1 - theta) v- and
dv = v+ - v- before the momentum terms, and after them F += applied, the momentum scale
max(|M dv|, h |F|, |M v_m|) and R = M dv - h F: ~12 numpy calls of a few us each on arrays
of 6 + nq, per body and iterate. Here two calls, with the same elementwise operations in the
same order (no fused multiply-add: numba compiles without fastmath here), so the results are
numpy's bit for bit (tests/test_compiled_step.py).
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def iterate_velocities(v, vp, th):  # pragma: no cover - compiled
    """(v_m, dv): v_m = th vp + (1 - th) v and dv = vp - v, as numpy evaluates them."""
    n = v.shape[0]
    vm = np.empty(n)
    dv = np.empty(n)
    c = 1.0 - th
    for i in range(n):
        vm[i] = th * vp[i] + c * v[i]
        dv[i] = vp[i] - v[i]
    return vm, dv


@numba.njit(cache=True, nogil=True)
def _abs_max(x):  # pragma: no cover - compiled
    """np.abs(x).max(): NaN if x holds one (numpy's max propagates it)."""
    out = 0.0 if x.shape[0] else np.nan
    for i in range(x.shape[0]):
        a = abs(x[i])
        if np.isnan(a):
            return np.nan
        if a > out:  # noqa: PLR1730 - the comparison spelled out (NaN order, as Python's max)
            out = a
    return out


@numba.njit(cache=True, nogil=True)
def residual_and_scale(inertia, F, momentum, applied, h):  # pragma: no cover - compiled
    """(R, scale): F += applied (in place; an empty applied: none), R = inertia - h F and
    scale = max(|inertia|.max(), h |F|.max(), |momentum|.max()) with Python's max over the
    three (a later value replaces an earlier one only if greater: NaN as in numpy's path)."""
    n = F.shape[0]
    if applied.shape[0]:
        for i in range(n):
            F[i] += applied[i]
    R = np.empty(n)
    for i in range(n):
        R[i] = inertia[i] - h * F[i]
    scale = _abs_max(inertia)
    for x in (h * _abs_max(F), _abs_max(momentum)):
        if x > scale:  # noqa: PLR1730 - Python's max(a, b, c) spelled out (its NaN order)
            scale = x
    return R, scale
