"""Positions and velocities of the contact nodes of one body, compiled (numba).

Node arrays hold the contact nodes of one body only ("local" node indices 0..n_c-1), their
psi rows gathered once (contact.nodes.ContactNodes), dense (n_c, 3, nq) or in CSR form.
Kinematics of the floating frame (seed eq. 1-3): s = X + psi q in the body frame,
x = r + A s, x_dot = r_dot + A (w x s + psi q_dot). Units: metres, seconds.
"""

from __future__ import annotations

import math

import numba
import numpy as np


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
    for c in range(X.shape[0]):
        vmax, umax = node_frame(X, u, ud, r, A, v, c, s, x, xd, vmax, umax)
    return vmax, umax


@numba.njit(cache=True)
def node_frame(X, u, ud, r, A, v, c, s, x, xd, vmax, umax):
    """frame_kinematics for node c alone; returns (vmax, umax) raised by its |xd| components
    and its |u| (the running maxima of the caller's loop)."""
    w0, w1, w2 = v[3], v[4], v[5]
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
def same_bits(a, b):
    """a and b (1-D float64, equal length) hold the same values bit for bit (a NaN never
    matches, so it is always recomputed; 0.0 and -0.0 differ)."""
    for i in range(a.shape[0]):
        x, y = a[i], b[i]
        if not (x == y and (x != 0.0 or math.copysign(1.0, x) == math.copysign(1.0, y))):
            return False
    return True


@numba.njit(cache=True)
def body_kinematics_memo(
    X,
    psi_c,
    indptr,
    indices,
    data,
    dense,
    q,
    v,
    r,
    A,
    u,
    ud,
    s,
    x,
    xd,
    last_q,
    last_v,
    last_frame,
    last_out,
    version,
):
    """body_kinematics unless q, v, r and A are bit for bit those of the last call that
    filled u, ud, s, x, xd (last_q (nq,), last_v (6 + nq,), last_frame (12,) = [r, A row by
    row], last_out (2,) its result; NaN in last_frame: none yet): the outputs are a function
    of these inputs only, so they are then already there. version[0] counts the updates that
    computed (what was kept for the positions, ProjectionMemo, is valid while it stands).
    Returns (max |xd component| [m/s], max |u| [m]), as body_kinematics."""
    if unchanged(q, v, r, A, last_q, last_v, last_frame):
        return last_out[0], last_out[1]
    vmax, umax = body_kinematics(
        X, psi_c, indptr, indices, data, dense, q, v, r, A, u, ud, s, x, xd
    )
    remember(q, v, r, A, vmax, umax, last_q, last_v, last_frame, last_out, version)
    return vmax, umax


@numba.njit(cache=True)
def unchanged(q, v, r, A, last_q, last_v, last_frame):
    """q, v, r and A are bit for bit those last remembered (body_kinematics_memo)."""
    same = q.shape[0] == last_q.shape[0] and v.shape[0] == last_v.shape[0]
    if same:
        for i in range(3):
            same = same and same_bits(A[i], last_frame[3 + 3 * i : 6 + 3 * i])
        same = (
            same and same_bits(r, last_frame[0:3]) and same_bits(q, last_q) and same_bits(v, last_v)
        )
    return same


@numba.njit(cache=True)
def remember(q, v, r, A, vmax, umax, last_q, last_v, last_frame, last_out, version):
    """An update computed from q, v, r, A gave (vmax, umax): kept for the next unchanged()
    (a q or v of another length is not kept: NaN in last_frame), version advanced."""
    version[0] += 1
    if q.shape[0] == last_q.shape[0] and v.shape[0] == last_v.shape[0]:
        last_q[:] = q
        last_v[:] = v
        last_frame[0:3] = r
        for i in range(3):
            last_frame[3 + 3 * i : 6 + 3 * i] = A[i]
        last_out[0], last_out[1] = vmax, umax
    else:
        last_frame[0] = np.nan
