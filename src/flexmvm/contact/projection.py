"""Closest-point projection of one slave node on one facet, compiled (numba).

The numpy implementation in contact.geometry is the specification: the projection here (quad
Newton with the same tolerances, line search, far check and fold test; exact triangle
projection; edge-distance check) reproduces geometry.project_points pair by pair, to
round-off. The search (contact.search) calls it for each candidate facet.

A projection is written as one record (float64, REC_LEN entries, layout REC_*): xi (2),
weights (4), unit normal (3), gap [m], inside (0/1), distance [m]. Tolerances travel in
``params`` (float64 array, see :func:`projection_params`) rather than as module globals, so a
compiled cache never holds stale values.
"""

from __future__ import annotations

import numba
import numpy as np

from flexmvm.contact.geometry import (
    FAR_CHECK_ITER,
    FAR_XI,
    LINE_SEARCH_HALVINGS,
    NEWTON_MAX_ITER,
    NEWTON_TOL,
    XI_BOUND,
)

# status codes returned by the kernels (0 = ok); the caller raises SolverError
DEGENERATE_QUAD, DEGENERATE_TRI, FOLDED_NORMAL = 1, 2, 3
_EPS = np.finfo(float).eps
_SX = np.array([-1.0, 1.0, 1.0, -1.0])
_SY = np.array([-1.0, -1.0, 1.0, 1.0])
# record of one projected pair: xi (2), weights (4), normal (3), gap, inside (0/1), distance
REC_XI, REC_W, REC_N, REC_GAP, REC_IN, REC_DIST, REC_LEN = 0, 2, 6, 9, 10, 11, 12


def projection_params(inside_tol: float = 1e-6) -> np.ndarray:
    """(7,) float64: max Newton iterations, line-search halvings, far-check iteration, far
    |xi|, Newton tolerance, xi bound, inside tolerance (the constants of contact.geometry)."""
    return np.array(
        [
            NEWTON_MAX_ITER,
            LINE_SEARCH_HALVINGS,
            FAR_CHECK_ITER,
            FAR_XI,
            NEWTON_TOL,
            XI_BOUND,
            inside_tol,
        ],
        dtype=np.float64,
    )


@numba.njit(cache=True)
def _quad_coeffs(P, C):
    """Bilinear coefficients C (4, 3): x(xi, eta) = C0 + C1 xi + C2 eta + C3 xi eta."""
    for i in range(3):
        C[0, i] = (P[0, i] + P[1, i] + P[2, i] + P[3, i]) / 4.0
        C[1, i] = (-P[0, i] + P[1, i] + P[2, i] - P[3, i]) / 4.0
        C[2, i] = (-P[0, i] - P[1, i] + P[2, i] + P[3, i]) / 4.0
        C[3, i] = (P[0, i] - P[1, i] + P[2, i] - P[3, i]) / 4.0


@numba.njit(cache=True)
def _residual(xs, C, e, h, r):
    """r = xs - x(e, h) (3,); returns |r|^2."""
    f = 0.0
    for i in range(3):
        r[i] = xs[i] - (C[0, i] + C[1, i] * e + C[2, i] * h + C[3, i] * e * h)
        f += r[i] * r[i]
    return f


@numba.njit(cache=True)
def _newton_direction(C, r, e, h):
    """(a11, a22, det, step_e, step_h, stuck) of one Newton / Gauss-Newton step at (e, h)."""
    a11 = a22 = a12 = rc = F1 = F2 = 0.0
    for i in range(3):
        t1 = C[1, i] + C[3, i] * h
        t2 = C[2, i] + C[3, i] * e
        a11 += t1 * t1
        a22 += t2 * t2
        a12 += t1 * t2
        rc += r[i] * C[3, i]
        F1 += r[i] * t1
        F2 += r[i] * t2
    h12 = a12 - rc
    det = a11 * a22 - h12 * h12
    if det <= 1e-12 * a11 * a22:
        h12 = a12
        det = a11 * a22 - a12 * a12
    stuck = det <= 1e-24 * (a11 + a22) ** 2
    safe = 1.0 if stuck else det
    se = (a22 * F1 - h12 * F2) / safe
    sh = (a11 * F2 - h12 * F1) / safe
    big = max(1.0, max(abs(se), abs(sh)))
    return a11, a22, se / big, sh / big, stuck


@numba.njit(cache=True)
def quad_newton(xs, C, r, params):
    """Local coordinates (e, h) of the closest point of xs (3,) on the bilinear quad with
    coefficients C (4, 3), as geometry._quad_newton for one pair. r (3,) work array.
    Returns (e, h, converged)."""
    max_iter, halvings, far_iter = int(params[0]), int(params[1]), int(params[2])
    far_xi, tol, bound = params[3], params[4], params[5]
    e = h = 0.0
    done = stuck = False
    f_r = _residual(xs, C, e, h, r)
    for it in range(max_iter):
        if it == far_iter and not done and max(abs(e), abs(h)) > far_xi:
            stuck = True
        a11, a22, se, sh, fold = _newton_direction(C, r, e, h)
        stuck = stuck or fold
        if done or stuck:
            se = sh = 0.0
        f0 = f_r
        scale = np.sqrt(f0 / max(min(a11, a22), 1e-300))
        if not stuck and max(abs(se), abs(sh)) <= tol + 64 * _EPS * scale:
            done = True
        for _ in range(halvings):
            te = min(max(e + se, -bound), bound)
            th = min(max(h + sh, -bound), bound)
            f_r = _residual(xs, C, te, th, r)
            worse = f_r > f0 * (1.0 + 1e-9) + 1e-30 and not (done or stuck)
            if worse and max(abs(se), abs(sh)) <= tol:
                done = True
                se = sh = 0.0
                worse = False
            if not worse:
                break
            se *= 0.5
            sh *= 0.5
        e, h = te, th
        if done or stuck:
            break
    return e, h, done


@numba.njit(cache=True)
def _segment_distance(p, a, b):
    """Distance from p to the segment [a, b] (all (3,)); a == b allowed."""
    L2 = 0.0
    pa = 0.0
    for i in range(3):
        L2 += (b[i] - a[i]) ** 2
        pa += (p[i] - a[i]) * (b[i] - a[i])
    t = min(max(pa / (L2 if L2 > 0.0 else 1.0), 0.0), 1.0)
    d = 0.0
    for i in range(3):
        d += (p[i] - a[i] - t * (b[i] - a[i])) ** 2
    return np.sqrt(d)


@numba.njit(cache=True)
def _quad_local(xs, P, C, r, params, rec):
    """Quad part of project_pair: centre-area check, Newton, then xi, weights and the raw
    inside flag (before the edge check) into rec. C (4, 3), r (3,) work. Returns a status."""
    _quad_coeffs(P, C)
    n0 = C[1, 1] * C[2, 2] - C[1, 2] * C[2, 1]
    n1 = C[1, 2] * C[2, 0] - C[1, 0] * C[2, 2]
    n2 = C[1, 0] * C[2, 1] - C[1, 1] * C[2, 0]
    c11 = C[1, 0] ** 2 + C[1, 1] ** 2 + C[1, 2] ** 2
    c22 = C[2, 0] ** 2 + C[2, 1] ** 2 + C[2, 2] ** 2
    if np.sqrt(n0 * n0 + n1 * n1 + n2 * n2) <= 1e-12 * (c11 + c22):
        return DEGENERATE_QUAD
    e, h, conv = quad_newton(xs, C, r, params)
    rec[REC_XI], rec[REC_XI + 1] = e, h
    for a in range(4):
        rec[REC_W + a] = 0.25 * (1.0 + e * _SX[a]) * (1.0 + h * _SY[a])
    rec[REC_IN] = 1.0 if (max(abs(e), abs(h)) <= 1.0 + params[6] and conv) else 0.0
    return 0


@numba.njit(cache=True)
def _quad_tangents(P, e, h, t):
    """Tangents dx/dxi, dx/deta of the quad P (4, 3) at (e, h) into t (2, 3)."""
    for i in range(3):
        t[0, i] = 0.0
        t[1, i] = 0.0
    for a in range(4):
        d1 = 0.25 * _SX[a] * (1.0 + h * _SY[a])
        d2 = 0.25 * _SY[a] * (1.0 + e * _SX[a])
        for i in range(3):
            t[0, i] += d1 * P[a, i]
            t[1, i] += d2 * P[a, i]


@numba.njit(cache=True)
def _tri_local(xs, P, t, params, rec):
    """Exact projection on the triangle P[0..2]; tangents e1, e2 into t (2, 3)."""
    a11 = a22 = a12 = b1 = b2 = 0.0
    for i in range(3):
        t[0, i] = P[1, i] - P[0, i]
        t[1, i] = P[2, i] - P[0, i]
        d = xs[i] - P[0, i]
        a11 += t[0, i] * t[0, i]
        a22 += t[1, i] * t[1, i]
        a12 += t[0, i] * t[1, i]
        b1 += d * t[0, i]
        b2 += d * t[1, i]
    det = a11 * a22 - a12 * a12
    if det <= 1e-24 * a11 * a22:
        return DEGENERATE_TRI
    e = (a22 * b1 - a12 * b2) / det
    h = (a11 * b2 - a12 * b1) / det
    rec[REC_XI], rec[REC_XI + 1] = e, h
    w0 = 1.0 - (e + h)
    rec[REC_W], rec[REC_W + 1], rec[REC_W + 2], rec[REC_W + 3] = w0, e, h, 0.0
    rec[REC_IN] = 1.0 if min(w0, min(e, h)) >= -params[6] else 0.0
    return 0


@numba.njit(cache=True)
def _normal(P, t, quad, rec):
    """Unit normal t1 x t2 / |.| into rec; for a quad projection outside its facet whose
    extended map folds there, the normal at the nearest point of [-1, 1]^2."""
    n0 = t[0, 1] * t[1, 2] - t[0, 2] * t[1, 1]
    n1 = t[0, 2] * t[1, 0] - t[0, 0] * t[1, 2]
    n2 = t[0, 0] * t[1, 1] - t[0, 1] * t[1, 0]
    nl = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    l1 = t[0, 0] ** 2 + t[0, 1] ** 2 + t[0, 2] ** 2
    l2 = t[1, 0] ** 2 + t[1, 1] ** 2 + t[1, 2] ** 2
    folded = nl <= 1e-12 * np.sqrt(l1 * l2)
    if folded and quad and rec[REC_IN] == 0.0:
        e = min(max(rec[REC_XI], -1.0), 1.0)
        h = min(max(rec[REC_XI + 1], -1.0), 1.0)
        _quad_tangents(P, e, h, t)
        n0 = t[0, 1] * t[1, 2] - t[0, 2] * t[1, 1]
        n1 = t[0, 2] * t[1, 0] - t[0, 0] * t[1, 2]
        n2 = t[0, 0] * t[1, 1] - t[0, 1] * t[1, 0]
        nl = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
        folded = nl == 0.0
    if folded:
        return FOLDED_NORMAL
    rec[REC_N], rec[REC_N + 1], rec[REC_N + 2] = n0 / nl, n1 / nl, n2 / nl
    return 0


@numba.njit(cache=True)
def project_pair(xs, P, quad, params, C, t, r, rec):
    """Closest-point projection of xs (3,) on the facet P (4, 3) (a triangle repeats its last
    node), as geometry.project_points for one pair. Writes rec (REC_LEN,): xi, weights, unit
    normal, gap [m], inside (0/1, with the edge check), distance [m] (to the clamped facet when
    outside). C (4, 3), t (2, 3), r (3,) work arrays. Returns a status code (0 = ok)."""
    if quad:
        status = _quad_local(xs, P, C, r, params, rec)
        if status:
            return status
        _quad_tangents(P, rec[REC_XI], rec[REC_XI + 1], t)
    else:
        status = _tri_local(xs, P, t, params, rec)
        if status:
            return status
    status = _normal(P, t, quad, rec)
    if status:
        return status
    gap = dist = 0.0
    for i in range(3):
        xc = (rec[REC_W] * P[0, i] + rec[REC_W + 1] * P[1, i]) + rec[REC_W + 2] * P[2, i]
        xc = xc + rec[REC_W + 3] * P[3, i]
        gap += (xs[i] - xc) * rec[REC_N + i]
        dist += (xs[i] - xc) ** 2
    dist = np.sqrt(dist)
    edge = _segment_distance(xs, P[0], P[1])
    for k in range(1, 4):
        edge = min(edge, _segment_distance(xs, P[k], P[(k + 1) % 4]))
    diag = np.sqrt((P[2, 0] - P[0, 0]) ** 2 + (P[2, 1] - P[0, 1]) ** 2 + (P[2, 2] - P[0, 2]) ** 2)
    if rec[REC_IN] == 1.0 and not dist <= edge + 1e-12 * (edge + diag):
        rec[REC_IN] = 0.0
    rec[REC_GAP] = gap
    rec[REC_DIST] = dist if rec[REC_IN] == 1.0 else edge
    return 0
