"""Compiled kernels of the point-to-surface contact step (numba), on flat preallocated arrays.

The numpy implementation in contact.geometry is the specification: the closest-point
projection here (quad Newton with the same tolerances, line search, far check and fold test;
exact triangle projection; edge-distance check), the closest-facet choice and the clamping
of outside projections reproduce it pair by pair, to round-off. What differs is the search:
per slave node a cached superset of its broad-phase candidates and a warm start from the facet
chosen at the previous step, with facets pruned by a distance bound (see :func:`scan_nodes`).

Units: metres, seconds. Node arrays hold the contact nodes of one body only ("local" node
indices 0..n_c-1); master facets refer to local master node indices.

Tolerances of the projection travel in ``params`` (float64 array, see :func:`projection_params`)
rather than as module globals, so a compiled cache never holds stale values.

Projections made at unchanged node positions are kept and read again (contact.nodes.
ProjectionMemo, :func:`_try`): the penetration measure at the end of a step and the next
step's search project the same pairs at the same positions. The small helpers of the search
(_try, _closest, _candidates, ...) are separate compiled functions, not inlined: inlining them
into the scans (numba ``inline="always"``, same results bit for bit) saved 2.6 % of an
all-MVM seed run but doubled the first-run compilation of the MVM path (20 s -> 39 s).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from flexmvm.contact.geometry import (
    FAR_CHECK_ITER,
    FAR_XI,
    LINE_SEARCH_HALVINGS,
    NEWTON_MAX_ITER,
    NEWTON_TOL,
    TIE_ABS,
    TIE_REL,
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
    return np.array([NEWTON_MAX_ITER, LINE_SEARCH_HALVINGS, FAR_CHECK_ITER, FAR_XI,
                     NEWTON_TOL, XI_BOUND, inside_tol], dtype=np.float64)


# -- kinematics of the contact nodes --------------------------------------------------------------
@numba.njit(cache=True, fastmath={"reassoc", "contract"})
def dense_displacements(psi_c, q, qd, u, ud):
    """u = psi_k q, ud = psi_k qd (n_c, 3) for the gathered rows psi_c (n_c, 3, nq)."""
    n, _, nq = psi_c.shape
    for c in range(n):
        for j in range(3):
            a = 0.0
            b = 0.0
            for k in range(nq):
                p = psi_c[c, j, k]
                a += p * q[k]
                b += p * qd[k]
            u[c, j] = a
            ud[c, j] = b


@numba.njit(cache=True)
def csr_displacements(indptr, indices, data, q, qd, u, ud):
    """As dense_displacements for psi rows in CSR form (3 n_c rows, row 3 c + j)."""
    for row in range(len(indptr) - 1):
        a = 0.0
        b = 0.0
        for e in range(indptr[row], indptr[row + 1]):
            a += data[e] * q[indices[e]]
            b += data[e] * qd[indices[e]]
        u[row // 3, row % 3] = a
        ud[row // 3, row % 3] = b


@numba.njit(cache=True)
def frame_kinematics(X, u, ud, r, A, v, s, x, xd):
    """s = X + u (body frame), x = r + A s, xd = r_dot + A (w x s + ud) for all n_c nodes.

    v (6 + nq,) generalized velocity [r_dot, w]; writes s, x, xd (n_c, 3). Returns
    (max |xd component| [m/s], max |u| [m])."""
    vmax = 0.0
    umax = 0.0
    w0, w1, w2 = v[3], v[4], v[5]
    for c in range(X.shape[0]):
        s0, s1, s2 = X[c, 0] + u[c, 0], X[c, 1] + u[c, 1], X[c, 2] + u[c, 2]
        s[c, 0], s[c, 1], s[c, 2] = s0, s1, s2
        l0 = w1 * s2 - w2 * s1 + ud[c, 0]
        l1 = w2 * s0 - w0 * s2 + ud[c, 1]
        l2 = w0 * s1 - w1 * s0 + ud[c, 2]
        for i in range(3):
            x[c, i] = r[i] + (s0 * A[i, 0] + s1 * A[i, 1] + s2 * A[i, 2])
            xd[c, i] = v[i] + (l0 * A[i, 0] + l1 * A[i, 1] + l2 * A[i, 2])
            vmax = max(vmax, abs(xd[c, i]))
        umax = max(umax, np.sqrt(u[c, 0] ** 2 + u[c, 1] ** 2 + u[c, 2] ** 2))
    return vmax, umax


# -- closest-point projection of one pair ---------------------------------------------------------
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


@numba.njit(cache=True)
def body_kinematics(X, psi_c, indptr, indices, data, dense, q, v, r, A, u, ud, s, x, xd):
    """Contact-node kinematics of one body: u, ud, s (body frame) and x, xd (global), all
    (n_c, 3), from q (nq,), v (6 + nq,), r (3,), A (3, 3). psi rows gathered either dense
    (psi_c (n_c, 3, nq), dense=True) or CSR (indptr, indices, data over 3 n_c rows); a rigid
    body passes empty CSR rows. Returns (max |xd component| [m/s], max |u| [m])."""
    qd = v[6:]
    if dense:
        dense_displacements(psi_c, q, qd, u, ud)
    else:
        csr_displacements(indptr, indices, data, q, qd, u, ud)
    return frame_kinematics(X, u, ud, r, A, v, s, x, xd)


@numba.njit(cache=True)
def _same_bits(a, b):
    """a and b (1-D float64, equal length) hold the same values bit for bit (a NaN never
    matches, so it is always recomputed; 0.0 and -0.0 differ)."""
    for i in range(a.shape[0]):
        x, y = a[i], b[i]
        if not (x == y and (x != 0.0 or math.copysign(1.0, x) == math.copysign(1.0, y))):
            return False
    return True


@numba.njit(cache=True)
def body_kinematics_memo(X, psi_c, indptr, indices, data, dense, q, v, r, A, u, ud, s, x, xd,
                         last_q, last_v, last_frame, last_out, version):
    """body_kinematics unless q, v, r and A are bit for bit those of the last call that
    filled u, ud, s, x, xd (last_q (nq,), last_v (6 + nq,), last_frame (12,) = [r, A row by
    row], last_out (2,) its result; NaN in last_frame: none yet): the outputs are a function
    of these inputs only, so they are then already there. version[0] counts the updates that
    computed (what was kept for the positions, ProjectionMemo, is valid while it stands).
    Returns (max |xd component| [m/s], max |u| [m]), as body_kinematics."""
    same = q.shape[0] == last_q.shape[0] and v.shape[0] == last_v.shape[0]
    if same:
        for i in range(3):
            same = same and _same_bits(A[i], last_frame[3 + 3 * i:6 + 3 * i])
        same = same and _same_bits(r, last_frame[0:3]) and _same_bits(q, last_q) and _same_bits(
            v, last_v)
    if same:
        return last_out[0], last_out[1]
    vmax, umax = body_kinematics(X, psi_c, indptr, indices, data, dense, q, v, r, A, u, ud, s,
                                 x, xd)
    version[0] += 1
    if q.shape[0] == last_q.shape[0] and v.shape[0] == last_v.shape[0]:
        last_q[:] = q
        last_v[:] = v
        last_frame[0:3] = r
        for i in range(3):
            last_frame[3 + 3 * i:6 + 3 * i] = A[i]
        last_out[0], last_out[1] = vmax, umax
    else:
        last_frame[0] = np.nan
    return vmax, umax


# -- search: candidate lists, warm start, pruning -------------------------------------------------
@numba.njit(cache=True)
def _distance(p, c):
    return np.sqrt((p[0] - c[0]) ** 2 + (p[1] - c[1]) ** 2 + (p[2] - c[2]) ** 2)


@numba.njit(cache=True)
def _refresh_list(i, p, reach, rho, geo, lists, ref, gmeta, gdims, gstart, gfacets):
    """Candidate superset of node i: facets g with |p - c_g| - R_g <= reach + rho (geo (nf, 4):
    centroid, circumradius), stored in lists[i] (count first; -1 when it overflows: all
    facets then); ref[i] = (p, reach + rho). The facets come from the cells of the facet grid
    (nodes.facet_grid: gmeta = origin, cell edge, largest R; gdims; CSR gstart, gfacets) within
    reach + rho + R_max of p: a node's rebuild reads the facets about it, not all of them."""
    radius = reach + rho
    cap = lists.shape[1] - 1
    n = 0
    edge = gmeta[3]
    lo = np.empty(3, dtype=np.int64)
    hi = np.empty(3, dtype=np.int64)
    for j in range(3):
        top = gdims[j] - 1.0
        # clipped to the grid in floating point, then truncated (= floor of a value >= 0)
        lo[j] = np.int64(min(max((p[j] - radius - gmeta[4] - gmeta[j]) / edge, 0.0), top))
        hi[j] = np.int64(min(max((p[j] + radius + gmeta[4] - gmeta[j]) / edge, 0.0), top))
    overflow = False
    for ci in range(lo[0], hi[0] + 1):
        for cj in range(lo[1], hi[1] + 1):
            for ck in range(lo[2], hi[2] + 1):
                cell = (ci * gdims[1] + cj) * gdims[2] + ck
                for e in range(gstart[cell], gstart[cell + 1]):
                    g = gfacets[e]
                    if _distance(p, geo[g]) - geo[g, 3] <= radius:
                        if n == cap:
                            overflow = True
                            break
                        lists[i, 1 + n] = g
                        n += 1
                if overflow:
                    break
            if overflow:
                break
        if overflow:
            break
    lists[i, 0] = -1 if overflow else n
    ref[i, 0], ref[i, 1], ref[i, 2], ref[i, 3] = p[0], p[1], p[2], radius


@numba.njit(cache=True)
def _candidates(i, p, reach, rho, geo, lists, ref, mark, tag, cand, lb, grid):
    """Broad-phase candidates of node i, exactly BroadPhase.query's set {g : |p - c_g| <=
    reach + R_g}, from its cached superset; the superset is rebuilt when the node has moved
    so far (|p - p_ref| + reach > radius_ref, with a round-off margin) that it may miss one.
    Marks mark[g] = tag, writes cand[:n] and lower bounds lb[:n] = |p - c_g| - R_g [m].
    Returns n."""
    radius = ref[i, 3]
    moved = _distance(p, ref[i, :3])
    if radius < 0.0 or moved + reach > radius - (1e-12 + 1e-9 * radius):
        _refresh_list(i, p, reach, rho, geo, lists, ref, grid[0], grid[1], grid[2], grid[3])
    n_list = lists[i, 0]
    n_all = geo.shape[0] if n_list < 0 else n_list
    n = 0
    for k in range(n_all):
        g = k if n_list < 0 else lists[i, 1 + k]
        d = _distance(p, geo[g])
        if d <= reach + geo[g, 3]:
            mark[g] = tag
            cand[n] = g
            lb[n] = d - geo[g, 3]
            n += 1
    return n


@numba.njit(cache=True)
def _score(rec):
    """A projection's distance to its facet [m] for closest_facets' order: |gap| inside, the
    distance to the clamped facet outside, the latter raised by a round-off margin
    (TIE_REL, TIE_ABS) so that an inside projection wins a tie."""
    if rec[REC_IN] == 1.0:
        return abs(rec[REC_GAP])
    return rec[REC_DIST] * (1.0 + TIE_REL) + TIE_ABS


@numba.njit(cache=True)
def _better(rec, g, best, best_g):
    """closest_facets' order: the closer facet (_score), then an inside projection, then the
    lower facet index."""
    if best_g < 0:
        return True
    sa, sb = _score(rec), _score(best)
    if sa != sb:
        return sa < sb
    a_in = rec[REC_IN] == 1.0
    b_in = best[REC_IN] == 1.0
    if a_in != b_in:
        return a_in
    return g < best_g


@numba.njit(cache=True)
def _memo_begin(memo, ver_s, ver_m):
    """Forget the kept projections of memo = (facets, count, records, versions) unless the
    node and facet positions are still those they were made at (their ContactNodes versions
    ver_s[0], ver_m[0])."""
    count, versions = memo[1], memo[3]
    if versions[0] != ver_s[0] or versions[1] != ver_m[0]:
        count[:] = 0
        versions[0], versions[1] = ver_s[0], ver_m[0]


@numba.njit(cache=True)
def _try(g, i, xs, xm, conn, n_quads, params, work, memo, best, best_g):
    """Project xs (node i) on facet g; keep it in best when it beats best_g. Returns (status,
    best_g). memo = (facets (n, k), count (n,), records (n, k, REC_LEN), versions): up to k
    projections of node i at the current positions (_memo_begin), read instead of projecting
    again (project_pair writes every entry of a record and depends on xs, the facet's nodes
    and params only: the same record bit for bit); k = 0: none kept."""
    C, t, r, P, rec = work
    m_fac, m_count, m_rec = memo[0], memo[1], memo[2]
    kept = -1
    for k in range(m_count[i]):
        if m_fac[i, k] == g:
            kept = k
            break
    if kept >= 0:
        rec[:] = m_rec[i, kept]
        status = 0
    else:
        for a in range(4):
            for j in range(3):
                P[a, j] = xm[conn[g, a], j]
        status = project_pair(xs, P, g < n_quads, params, C, t, r, rec)
        c = m_count[i]
        if status == 0 and c < m_fac.shape[1]:
            m_fac[i, c] = g
            m_rec[i, c] = rec
            m_count[i] = c + 1
    if status == 0 and _better(rec, g, best, best_g):
        best[:] = rec
        best_g = g
    return status, best_g


@numba.njit(cache=True)
def _closest(i, xs, n, cand, lb, mark, tag, f0, adj_ptr, adj_idx, geo, u_max, xm, conn,
             n_quads, params, work, memo, best):
    """Closest facet among the n candidates (marked mark[g] == tag): the previous facet f0
    first (warm start), its neighbours next unless f0 holds an inside projection, then the
    rest. Once an inside projection with score
    |gap| is known, a candidate g is skipped when the lower bound of its distance,
    |p - c_g| - R_g - u_max (undeformed facet moved by at most the largest master node
    displacement u_max), minus a margin for the inside tolerance and round-off, exceeds that
    score: an inside projection on g has |gap| = distance >= that bound, so g cannot win.
    Returns (status, facet; -1 when none)."""
    best_g = -1
    if f0 >= 0:
        if mark[f0] == tag:
            status, best_g = _try(f0, i, xs, xm, conn, n_quads, params, work, memo, best,
                                  best_g)
            mark[f0] = tag + 1
            if status:
                return status, f0
        start = adj_ptr[f0 + 1] if best_g >= 0 and best[REC_IN] == 1.0 else adj_ptr[f0]
        for k in range(start, adj_ptr[f0 + 1]):
            g = adj_idx[k]
            if mark[g] == tag:
                status, best_g = _try(g, i, xs, xm, conn, n_quads, params, work, memo, best,
                                      best_g)
                mark[g] = tag + 1
                if status:
                    return status, g
    for k in range(n):
        g = cand[k]
        if mark[g] != tag:
            continue
        if best_g >= 0:
            R = geo[g, 3]
            margin = u_max * (1.0 + 1e-5) + 1e-5 * R + 1e-9 * (lb[k] + R) + 1e-15
            if lb[k] - margin > _score(best):
                continue
        status, best_g = _try(g, i, xs, xm, conn, n_quads, params, work, memo, best, best_g)
        mark[g] = tag + 1
        if status:
            return status, g
    return 0, best_g


@numba.njit(cache=True)
def _finish(i, g, best, xs, vs, xm, vm, conn, n_quads, out):
    """Row i of out (ns, 11): weights (4), xi (2), normal (3), gap [m], normal velocity u_N
    [m/s]. A projection outside its facet is clamped as pairs._clamp does: local coordinates
    clamped to the facet, weights and gap recomputed there, the normal kept."""
    e, h = best[REC_XI], best[REC_XI + 1]
    w = out[i, 0:4]
    w[:] = best[REC_W:REC_W + 4]
    gap = best[REC_GAP]
    if best[REC_IN] == 0.0:
        if g < n_quads:
            e, h = min(max(e, -1.0), 1.0), min(max(h, -1.0), 1.0)
            w[0], w[1] = 0.25 * ((1 - e) * (1 - h)), 0.25 * ((1 + e) * (1 - h))
            w[2], w[3] = 0.25 * ((1 + e) * (1 + h)), 0.25 * ((1 - e) * (1 + h))
        else:
            b0, b1, b2 = max((1 - e) - h, 0.0), max(e, 0.0), max(h, 0.0)
            total = (b0 + b1) + b2
            w[0], w[1], w[2], w[3] = b0 / total, b1 / total, b2 / total, 0.0
            e, h = w[1], w[2]
        gap = 0.0
        for k in range(3):
            xc = ((w[0] * xm[conn[g, 0], k] + w[1] * xm[conn[g, 1], k]) + w[2] * xm[conn[g, 2], k])
            gap += best[REC_N + k] * (xs[k] - (xc + w[3] * xm[conn[g, 3], k]))
    un = 0.0
    for k in range(3):
        vc = ((w[0] * vm[conn[g, 0], k] + w[1] * vm[conn[g, 1], k]) + w[2] * vm[conn[g, 2], k])
        un += best[REC_N + k] * (vs[k] - (vc + w[3] * vm[conn[g, 3], k]))
    out[i, 4], out[i, 5] = e, h
    out[i, 6:9] = best[REC_N:REC_N + 3]
    out[i, 9], out[i, 10] = gap, un


@numba.njit(cache=True)
def _search_node(i, xs, xm, r_m, A_m, box, reach, rho, u_max, geo, conn, n_quads, adj_ptr,
                 adj_idx, params, lists, ref, prev, mark, counter, cand, lb, grid, work, memo,
                 best, p):
    """Closest facet of node i of xs, shared by scan_nodes and penetration_scan: the box test
    in the facet body's frame (r_m, A_m), the candidate superset, the closest projection.
    Returns (searched: False when outside the box or without candidates, status, facet)."""
    inside_box = True
    for j in range(3):
        p[j] = ((xs[i, 0] - r_m[0]) * A_m[0, j] + (xs[i, 1] - r_m[1]) * A_m[1, j]) + (
            xs[i, 2] - r_m[2]) * A_m[2, j]
        inside_box = inside_box and box[0, j] - reach <= p[j] <= box[1, j] + reach
    if not inside_box:
        return False, 0, -1
    counter[0] += 2
    tag = counter[0]
    n = _candidates(i, p, reach, rho, geo, lists, ref, mark, tag, cand, lb, grid)
    if n == 0:
        return False, 0, -1
    status, g = _closest(i, xs[i], n, cand, lb, mark, tag, prev[i], adj_ptr, adj_idx, geo,
                         u_max, xm, conn, n_quads, params, work, memo, best)
    return True, status, g


@numba.njit(cache=True)
def scan_nodes(xs, vs, xm, vm, r_m, A_m, box, reach, rho, u_max, geo, conn, n_quads, adj_ptr,
               adj_idx, params, lists, ref, prev, mark, counter, cand, lb, gmeta, gdims,
               gstart, gfacets, facet, out,
               memo_fac, memo_count, memo_rec, memo_ver, ver_s, ver_m):
    """Closest facet of every slave node within reach, as PointToSurfaceContact's numpy path
    (box test in the master frame, BroadPhase candidates, project_points, closest_facets,
    clamping) and its normal velocity.

    xs, vs (ns, 3) slave node positions [m] / velocities [m/s]; xm, vm (nm, 3) master surface
    nodes; r_m (3,), A_m (3, 3) master frame; box (2, 3) lower / upper corner of the master
    surface (body frame); reach [m]; rho [m] extra radius of the cached candidate supersets;
    u_max [m] largest master node displacement; geo (nf, 4) facet centroid and circumradius;
    conn (nf, 4) local master node ids; adj_ptr, adj_idx facet adjacency (CSR).
    State kept between calls: lists (ns, cap + 1), ref (ns, 4), prev (ns,) last facet per node.
    Work: mark (nf,), counter (1,), cand (nf,), lb (nf,); the facet grid gmeta, gdims,
    gstart, gfacets (nodes.facet_grid). Output: facet (ns,) (-1: none),
    out (ns, 11) as in _finish. Projections kept for the positions of versions ver_s[0],
    ver_m[0] of the two node sets (ContactNodes.version): memo_fac (ns, k), memo_count (ns,),
    memo_rec (ns, k, REC_LEN), memo_ver (2,) (contact.nodes.ProjectionMemo; _try).
    Returns (status, facet of the failure, number of pairs)."""
    C, t, r = np.empty((4, 3)), np.empty((2, 3)), np.empty(3)
    P, rec, best = np.empty((4, 3)), np.empty(REC_LEN), np.empty(REC_LEN)
    work = (C, t, r, P, rec)
    memo = (memo_fac, memo_count, memo_rec, memo_ver)
    _memo_begin(memo, ver_s, ver_m)
    p = np.empty(3)
    n_pairs = 0
    for i in range(xs.shape[0]):
        facet[i] = -1
        searched, status, g = _search_node(i, xs, xm, r_m, A_m, box, reach, rho, u_max, geo,
                                           conn, n_quads, adj_ptr, adj_idx, params, lists, ref,
                                           prev, mark, counter, cand, lb,
                                           (gmeta, gdims, gstart, gfacets), work, memo, best,
                                           p)
        if not searched:
            continue
        if status:
            return status, g, n_pairs
        facet[i] = g
        prev[i] = g
        _finish(i, g, best, xs[i], vs[i], xm, vm, conn, n_quads, out)
        n_pairs += 1
    return 0, -1, n_pairs


@numba.njit(cache=True)
def predicted_min_gap(facet, out, horizon):
    """min over the projected nodes of gap + horizon min(u_N, 0) [m] (inf when none)."""
    low = np.inf
    for i in range(len(facet)):
        if facet[i] >= 0:
            low = min(low, out[i, 9] + horizon * min(out[i, 10], 0.0))
    return low


@numba.njit(cache=True)
def active_nodes(facet, out, h, gap_tol, bonded, idx):
    """Slave nodes predicted to close within the step, gap + h u_N <= gap_tol, not bonded,
    into idx (ascending). Returns their number."""
    m = 0
    for i in range(len(facet)):
        if facet[i] >= 0 and out[i, 9] + h * out[i, 10] <= gap_tol and not bonded[i]:
            idx[m] = i
            m += 1
    return m


@numba.njit(cache=True)
def active_pairs(facet, out, h, gap_tol, bonded, idx, conn, n_quads, slave_nodes):
    """active_nodes (into idx), then the data of those m pairs in one call: (m, nodes (m,)
    their slave indices, slave_ids (m,) = slave_nodes[nodes], facets (m,), normal (m, 3),
    gap (m,), u_N (m,) (copies of their rows of out), and pair_nodes' slave (s_nodes,
    s_w, s_k) and master (m_nodes, m_w, m_k) row data)."""
    m = active_nodes(facet, out, h, gap_tol, bonded, idx)
    nodes = idx[:m].copy()
    slave_ids, facets = np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64)
    normal, gap, u_n = np.empty((m, 3)), np.empty(m), np.empty(m)
    for a in range(m):
        i = nodes[a]
        slave_ids[a], facets[a] = slave_nodes[i], facet[i]
        normal[a, 0], normal[a, 1], normal[a, 2] = out[i, 6], out[i, 7], out[i, 8]
        gap[a], u_n[a] = out[i, 9], out[i, 10]
    s_nodes, s_w, s_k = np.empty((m, 1), np.int64), np.empty((m, 1)), np.empty(m, np.int64)
    m_nodes, m_w, m_k = np.empty((m, 4), np.int64), np.empty((m, 4)), np.empty(m, np.int64)
    pair_nodes(nodes, facet, out, conn, n_quads, s_nodes, s_w, s_k, m_nodes, m_w, m_k)
    return (m, nodes, slave_ids, facets, normal, gap, u_n, (s_nodes, s_w, s_k),
            (m_nodes, m_w, m_k))


@numba.njit(cache=True)
def _normal_offset(w, n, g, conn, xs_i, vs_i, xm, vm):
    """(n . (x_S - sum_P w_P x_P), n . (x_dot_S - sum_P w_P x_dot_P)) of slave node
    position xs_i and velocity vs_i (3,) against master facet g with weights w (4,)."""
    proj = un = 0.0
    for k in range(3):
        xc = vc = 0.0
        for b in range(4):
            wb = w[b]
            if wb != 0.0:
                xc += wb * xm[conn[g, b], k]
                vc += wb * vm[conn[g, b], k]
        proj += n[k] * (xs_i[k] - xc)
        un += n[k] * (vs_i[k] - vc)
    return proj, un


@numba.njit(cache=True)
def hold_pairs(held, held_w, held_n, held_off, held_d, facet, out, xs, vs, xm, vm, A_m, conn,
               tol, d_max):
    """Closed pairs on the geometry they closed with (pairs.PointToSurfaceContact, position
    law). held[i] >= 0: slave node i keeps master facet held[i], its weights held_w[i] (4,),
    its normal held_n[i] (3,) in the master's body frame and the gap offset held_off[i]; its
    gap is linear in the node positions, g = n . (x_S - sum_P w_P x_P) + off with n = A_m
    held_n[i], and its normal velocity n . (x_dot_S - sum_P w_P x_dot_P). Written over the
    scan's row i of out (weights, normal, gap, u_N; xi kept) and facet[i].

    d = g - g_scan is what the linear gap differs from the scan's exact one; held_d[i] is d
    when the geometry was taken. When d has moved by more than tol [m] since (sliding along a
    curved master, facets turning), the pair takes the scan's geometry with the offset that
    keeps g where it is (no jump of the gap, so no work and no impulse: held_d[i] = d), while
    |d| <= d_max; beyond, or when the scan found no facet, held[i] = -1 and the scan's row
    stays (the pair is projected again). Returns (taken anew, released)."""
    anew = released = 0
    for i in range(len(held)):
        g = held[i]
        if g < 0:
            continue
        n = np.empty(3)
        for k in range(3):
            n[k] = (A_m[k, 0] * held_n[i, 0] + A_m[k, 1] * held_n[i, 1]) + A_m[k, 2] * held_n[i, 2]
        proj, un = _normal_offset(held_w[i], n, g, conn, xs[i], vs[i], xm, vm)
        gap = held_off[i] + proj
        d = gap - out[i, 9]
        if facet[i] < 0 or abs(d) > d_max:
            held[i] = -1
            released += 1
            continue
        if abs(d - held_d[i]) > tol:
            # the scan's geometry, offset so that the gap stays gap
            g = facet[i]
            for k in range(3):
                n[k] = out[i, 6 + k]
            proj, un = _normal_offset(out[i, 0:4], n, g, conn, xs[i], vs[i], xm, vm)
            held[i] = g
            for b in range(4):
                held_w[i, b] = out[i, b]
            for k in range(3):   # A_m^T n
                held_n[i, k] = (A_m[0, k] * n[0] + A_m[1, k] * n[1]) + A_m[2, k] * n[2]
            held_off[i] = gap - proj
            held_d[i] = d
            anew += 1
        facet[i] = g
        for b in range(4):
            out[i, b] = held_w[i, b]
        out[i, 6], out[i, 7], out[i, 8] = n[0], n[1], n[2]
        out[i, 9], out[i, 10] = gap, un
    return anew, released


@numba.njit(cache=True)
def gap_offsets(idx, facet, out, xs, xm, conn, offsets):
    """offsets[a] = g - n . (x_S - sum_P w_P x_P) of the pairs idx (rows of out): what a
    linear gap in the node positions must add to equal the scan's gap (0 up to round-off for
    a projection on its facet; the clamped ones are computed that way)."""
    for a in range(len(idx)):
        i = idx[a]
        d, _ = _normal_offset(out[i, 0:4], out[i, 6:9], facet[i], conn, xs[i], xs[i], xm, xm)
        offsets[a] = out[i, 9] - d


# -- constraint rows ------------------------------------------------------------------------------
@numba.njit(cache=True)
def pair_nodes(idx, facet, out, conn, n_quads, s_nodes, s_w, s_k, m_nodes, m_w, m_k):
    """Row data of the m = len(idx) active pairs: slave (node idx, weight 1, one node) and
    master (facet nodes, weights, 4 for a quad, 3 for a triangle)."""
    for a in range(len(idx)):
        i = idx[a]
        g = facet[i]
        s_nodes[a, 0], s_w[a, 0], s_k[a] = i, 1.0, 1
        m_k[a] = 4 if g < n_quads else 3
        for b in range(4):
            m_nodes[a, b] = conn[g, b]
            m_w[a, b] = out[i, b]


@numba.njit(cache=True)
def body_rows(nodes, w, kc, dirs, A, s, sign, psi_c, indptr, indices, data, dense, gdof,
              frame, elastic, sel_data, sel_idx, sel_ptr):
    """sign * (rows d_a^T sum_k w_ak dx_{node_ak}/dv) of one body (seed eq. 9), as
    pairs.body_rows: frame (m, 6) = [d wsum, sw x A^T d], elastic (m, nq) = N psi with the
    nodal selector N (m, 3 n_nodes) in CSR (sel_data, sel_idx (m*12,), sel_ptr (m + 1,),
    columns gdof[node] + j, sorted within a row). nodes, w (m, 4) local node ids / weights,
    kc (m,) nodes used per row, dirs (m, 3) global directions, s (n_c, 3) body-frame node
    positions; psi rows dense or CSR as in body_kinematics."""
    sel_ptr[0] = 0
    elastic[:] = 0.0
    for a in range(len(kc)):
        dl0 = (dirs[a, 0] * A[0, 0] + dirs[a, 1] * A[1, 0]) + dirs[a, 2] * A[2, 0]
        dl1 = (dirs[a, 0] * A[0, 1] + dirs[a, 1] * A[1, 1]) + dirs[a, 2] * A[2, 1]
        dl2 = (dirs[a, 0] * A[0, 2] + dirs[a, 1] * A[1, 2]) + dirs[a, 2] * A[2, 2]
        wsum = sw0 = sw1 = sw2 = 0.0
        for k in range(len(w[a])):
            wk = w[a, k] if k < kc[a] else 0.0
            c = nodes[a, k]
            wsum += wk
            sw0 += wk * s[c, 0]
            sw1 += wk * s[c, 1]
            sw2 += wk * s[c, 2]
        frame[a, 0], frame[a, 1], frame[a, 2] = (sign * (dirs[a, 0] * wsum), sign * (dirs[a, 1] * wsum),
                                                 sign * (dirs[a, 2] * wsum))
        frame[a, 3] = sign * (sw1 * dl2 - sw2 * dl1)
        frame[a, 4] = sign * (sw2 * dl0 - sw0 * dl2)
        frame[a, 5] = sign * (sw0 * dl1 - sw1 * dl0)
        dl = (dl0, dl1, dl2)
        start = sel_ptr[a]
        for k in range(kc[a]):
            c = nodes[a, k]
            for j in range(3):
                coef = w[a, k] * dl[j]
                _add_row(elastic[a], sign * coef, psi_c, indptr, indices, data, dense, 3 * c + j)
                sel_data[start + 3 * k + j] = sign * coef
                sel_idx[start + 3 * k + j] = gdof[c] + j
        sel_ptr[a + 1] = start + 3 * kc[a]
        _sort_row(sel_idx, sel_data, start, sel_ptr[a + 1])


@numba.njit(cache=True, fastmath={"reassoc", "contract"})
def _add_row(out, coef, psi_c, indptr, indices, data, dense, row):
    """out += coef * psi row `row` (row 3 c + j of the gathered rows)."""
    if dense:
        src = psi_c[row // 3, row % 3]
        for k in range(len(out)):
            out[k] += coef * src[k]
    else:
        for e in range(indptr[row], indptr[row + 1]):
            out[indices[e]] += coef * data[e]


@numba.njit(cache=True)
def _sort_row(idx, val, lo, hi):
    """Insertion sort of idx[lo:hi] (with val alongside); a few entries per row."""
    for a in range(lo + 1, hi):
        ki, kv = idx[a], val[a]
        b = a - 1
        while b >= lo and idx[b] > ki:
            idx[b + 1], val[b + 1] = idx[b], val[b]
            b -= 1
        idx[b + 1], val[b + 1] = ki, kv


# -- penetration measure --------------------------------------------------------------------------
@numba.njit(cache=True)
def penetration_scan(xs, xm, r_m, A_m, box, reach, rho, u_max, geo, conn, n_quads, adj_ptr,
                     adj_idx, params, edge_tol, floor, lists, ref, prev, mark, counter, cand, lb,
                     gmeta, gdims, gstart, gfacets,
                     memo_fac, memo_count, memo_rec, memo_ver, ver_s, ver_m):
    """Deepest penetration of the nodes xs (ns, 3) [m] into the facet surface xm (nm, 3) (local
    node ids in conn), searched as scan_nodes does (box test in the facet body's frame r_m,
    A_m; candidate supersets, warm start, pruning; same state arrays and meaning).

    A node counts when the closest facet's projection is inside it (params[6], the local
    coordinate tolerance of the constraint pass) or outside it by a lateral offset
    sqrt(distance^2 - gap^2) <= edge_tol * R_g (R_g the facet's circumradius), with a
    negative normal gap; its depth is -gap [m]. Nodes beyond reach of every facet are not
    seen: reach bounds the depth that can be measured.

    floor [m]: only depths above it are sought (0, -1 when none). Warm start: a node whose
    last facet (prev) still holds an inside projection with gap >= -depth (depth: the floor,
    or the deepest found so far in this call) is taken at that reading, without a search.
    With gap <= 0 that is exact: a facet that beats it in the search has an inside
    projection with a smaller |gap|, no deeper. With gap = g0 > 0 (in front of the facet),
    another facet could only win with an inside projection behind it at a distance < g0,
    i.e. if the other surface folded back over the facet within g0 of the node (a sheet
    thinner than the node's gap); at a ridge (convex edge) of plane facets the projection
    on the far facet is outside it. Contact surfaces do not fold so: the search is skipped.
    Projections kept as in scan_nodes (memo_*, ver_s, ver_m): the warm start's projection
    is not made again in the node's search, nor, with the constraint pass's memo at the same
    positions, in the next step's scan_nodes.
    Returns (status, facet of a failure, depth [m], node (-1 when none), facet of the
    deepest node)."""
    C, t, r = np.empty((4, 3)), np.empty((2, 3)), np.empty(3)
    P, rec, best = np.empty((4, 3)), np.empty(REC_LEN), np.empty(REC_LEN)
    work = (C, t, r, P, rec)
    memo = (memo_fac, memo_count, memo_rec, memo_ver)
    _memo_begin(memo, ver_s, ver_m)
    p = np.empty(3)
    depth, node, at = floor, -1, -1
    for i in range(xs.shape[0]):
        f0 = prev[i]
        if f0 >= 0:
            status, g = _try(f0, i, xs[i], xm, conn, n_quads, params, work, memo, best, -1)
            if status:
                return status, f0, 0.0, -1, -1
            if best[REC_IN] == 1.0 and best[REC_GAP] >= -depth:
                continue
        searched, status, g = _search_node(i, xs, xm, r_m, A_m, box, reach, rho, u_max, geo,
                                           conn, n_quads, adj_ptr, adj_idx, params, lists, ref,
                                           prev, mark, counter, cand, lb,
                                           (gmeta, gdims, gstart, gfacets), work, memo, best,
                                           p)
        if not searched:
            continue
        if status:
            return status, g, 0.0, -1, -1
        if g < 0:
            continue
        prev[i] = g
        gap = best[REC_GAP]
        if gap >= 0.0:
            continue
        if best[REC_IN] == 0.0:
            lateral2 = best[REC_DIST] ** 2 - gap * gap
            if lateral2 > (edge_tol * geo[g, 3]) ** 2:
                continue
        if -gap > depth:
            depth, node, at = -gap, i, g
    return 0, -1, depth if node >= 0 else 0.0, node, at
