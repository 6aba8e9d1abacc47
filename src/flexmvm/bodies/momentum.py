"""The impulse-momentum terms of a flexible body in one compiled kernel.

For the Moreau-Jean residual (integrate.moreau_jean) of a body with elastic coordinates, at the
midpoint configuration (A, q_m) with the carried contractions L(q_m), L(q_dot_m) and k_hat q_m:

    inertia  = M(A, q_m) dv                                   (Shabana ch. 5; bodies.body)
    force    = Q_v(A, q_m, v_m) + gravity - k_hat q_m         (quadratic-velocity terms)
    momentum = M(A, q_m) v_m

exactly as FlexibleBody.inertia_terms, mass_times, velocity_forces and gravity_forces compute
them in numpy (tests/test_momentum_kernel.py holds them to round-off on random inputs), but
without forming the (3, 3, nq) array C = G1 + L(q_m) or any 6 x nq block: a step of a reduced
body is a few hundred small numpy calls otherwise (~0.5 ms per body and iterate on the seed
case), and the arithmetic is O(9 nq).
"""

from __future__ import annotations

import numba
import numpy as np

_CYC = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1]], dtype=np.int64)


@numba.njit(cache=True, nogil=True)
def _skew(v):  # pragma: no cover - compiled
    out = np.zeros((3, 3))
    out[0, 1] = -v[2]
    out[0, 2] = v[1]
    out[1, 0] = v[2]
    out[1, 2] = -v[0]
    out[2, 0] = -v[1]
    out[2, 1] = v[0]
    return out


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _frame_velocity_forces(A, S, J, w, W, Om, S1qd, H, force):  # pragma: no cover - compiled
    """The frame rows of the quadratic-velocity forces (FlexibleBody.velocity_forces):
    force[:3] = -A (w~ w~ S + 2 w~ S1 q_dot), force[3:6] = -(w x J w + 2 (tr H w - H^T w)),
    W = w~, Om = w~ w~, H[a, b] = C[a][b] . q_dot."""
    force[:3] = -(A @ (Om @ S + 2.0 * (W @ S1qd)))
    Jw = J @ w
    cwJw = np.array([w[1] * Jw[2] - w[2] * Jw[1], w[2] * Jw[0] - w[0] * Jw[2],
                     w[0] * Jw[1] - w[1] * Jw[0]])
    trH = H[0, 0] + H[1, 1] + H[2, 2]
    force[3:6] = -(cwJw + 2.0 * (trH * w - H.T @ w))


@numba.njit(cache=True, nogil=True)
def _frame_gravity(mass, S, g, gb, force):  # pragma: no cover - compiled
    """Gravity on the frame rows (FlexibleBody.gravity_forces): m g and S x (A^T g); gb =
    A^T g. Zero g adds nothing."""
    if g[0] != 0.0 or g[1] != 0.0 or g[2] != 0.0:
        force[:3] += mass * g
        force[3] += S[1] * gb[2] - S[2] * gb[1]
        force[4] += S[2] * gb[0] - S[0] * gb[2]
        force[5] += S[0] * gb[1] - S[1] * gb[0]


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def momentum_terms(A, q, dv, vm, Lq, Lqd, Kq, mqq_dv, mqq_vm, mass, S0, S1, G0, G1, g,
                   inertia, force, momentum):  # pragma: no cover - compiled
    """Fill inertia, force, momentum (each (6 + nq,)) as described in the module docstring.

    A (3, 3); q (nq,) = q_m; dv, vm (6 + nq,); Lq, Lqd (3, 3, nq) = L(q_m), L(q_dot_m); Kq =
    k_hat q_m; mqq_dv, mqq_vm = M_qq dv_q, M_qq vm_q; S0 (3,), S1 (3, nq), G0 (3, 3), G1
    (3, 3, nq) with G1[a, b] = inv.G1[a][b]; g (3,) gravity [m/s^2] (zeros: none)."""
    nq = q.shape[0]
    # S = S0 + S1 q;  G[a, b] = G0[a, b] + G1[b][a] q + C[a][b] q,  C = G1 + L(q)
    S = S0.copy()
    G = G0.copy()
    for a in range(3):
        for k in range(nq):
            S[a] += S1[a, k] * q[k]
    for a in range(3):
        for b in range(3):
            acc = 0.0
            for k in range(nq):
                acc += (G1[b, a, k] + G1[a, b, k] + Lq[a, b, k]) * q[k]
            G[a, b] += acc
    Gs = 0.5 * (G + G.T)
    tr = Gs[0, 0] + Gs[1, 1] + Gs[2, 2]
    J = -Gs
    for a in range(3):
        J[a, a] += tr
    # M_wq[c] = C[a][b] - C[b][a] over cyclic (c, a, b): (3, nq), used by both products below
    Mwq = np.empty((3, nq))
    for c in range(3):
        a = _CYC[c, 1]
        b = _CYC[c, 2]
        for k in range(nq):
            Mwq[c, k] = G1[a, b, k] + Lq[a, b, k] - G1[b, a, k] - Lq[b, a, k]
    ASt = A @ _skew(S)
    w = vm[3:6]
    # --- inertia = M dv and momentum = M vm (M_fq = [A S1; M_wq]) -------------------------
    for out, x, mqq_x in ((inertia, dv, mqq_dv), (momentum, vm, mqq_vm)):
        xr, xw = x[:3], x[3:6]
        out[:3] = mass * xr - ASt @ xw
        out[3:6] = -(ASt.T @ xr) + J @ xw
        # + M_fq x_q
        s1x = np.zeros(3)
        mw = np.zeros(3)
        for k in range(nq):
            xk = x[6 + k]
            for a in range(3):
                s1x[a] += S1[a, k] * xk
            for c in range(3):
                mw[c] += Mwq[c, k] * xk
        out[:3] += A @ s1x
        out[3:6] += mw
        # q rows: M_fq^T x_f + M_qq x_q
        At_xr = A.T @ xr
        for k in range(nq):
            acc = mqq_x[k]
            for a in range(3):
                acc += S1[a, k] * At_xr[a]
            for c in range(3):
                acc += Mwq[c, k] * xw[c]
            out[6 + k] = acc
    # --- quadratic-velocity forces (FlexibleBody.velocity_forces) ---------------------------
    W = _skew(w)
    Om = W @ W
    qd = vm[6:]
    S1qd = np.zeros(3)
    H = np.zeros((3, 3))     # H[a, b] = C[a][b] . q_dot
    for k in range(nq):
        for a in range(3):
            S1qd[a] += S1[a, k] * qd[k]
            for b in range(3):
                H[a, b] += (G1[a, b, k] + Lq[a, b, k]) * qd[k]
    _frame_velocity_forces(A, S, J, w, W, Om, S1qd, H, force)
    any_w = w[0] != 0.0 or w[1] != 0.0 or w[2] != 0.0
    for k in range(nq):
        f = 0.0
        if any_w:
            for a in range(3):
                for b in range(3):
                    f -= Om[a, b] * (G1[b, a, k] + Lq[b, a, k])
            for c in range(3):
                a = _CYC[c, 1]
                b = _CYC[c, 2]
                f -= 2.0 * w[c] * (Lqd[a, b, k] - Lqd[b, a, k])
        force[6 + k] = f - Kq[k]
    # --- gravity (FlexibleBody.gravity_forces) -----------------------------------------------
    if g[0] != 0.0 or g[1] != 0.0 or g[2] != 0.0:
        gb = A.T @ g
        _frame_gravity(mass, S, g, gb, force)
        for k in range(nq):
            force[6 + k] += S1[0, k] * gb[0] + S1[1, k] * gb[1] + S1[2, k] * gb[2]


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def momentum_terms_nodal(A, q, dv, vm, Yq, Yqd, Kq, mqq_dv, mqq_vm, mass, S0, S1, G0, MsX,
                         node, comp, g, inertia, force, momentum):  # pragma: no cover
    """momentum_terms for a basis that selects nodal DOFs (full FE), from the compact
    contractions Yq = Y(q_m), Yqd = Y(q_dot_m) (3, n) of bodies.nodal_contraction: coordinate
    k is component c = comp[k] of node n = node[k], and every (3, 3, nq) array of
    momentum_terms has one nonzero per k and row a:

        C[a][b][k] = Cq[a, n] (b = c),  Cq = (M_s X)^T + Yq;    S1[a, k] = 0 for a != c;
        M_wq[:, k]: [c1] = Cq[c2, n], [c2] = -Cq[c1, n], [c] = 0   (c1, c2 = c + 1, c + 2 mod 3)

    Other arguments as momentum_terms; MsX (n, 3) = M_s X. O(nq) work reading 3 n + 4 nq
    numbers instead of ~30 nq."""
    nq = q.shape[0]
    # S = S0 + S1 q;  G[a, b] = G0[a, b] + G1[b][a] q + C[a][b] q
    S = S0.copy()
    G = G0.copy()
    for k in range(nq):
        c = comp[k]
        n = node[k]
        qk = q[k]
        S[c] += S1[c, k] * qk
        for b in range(3):
            G[c, b] += MsX[n, b] * qk
            G[b, c] += (MsX[n, b] + Yq[b, n]) * qk
    Gs = 0.5 * (G + G.T)
    tr = Gs[0, 0] + Gs[1, 1] + Gs[2, 2]
    J = -Gs
    for a in range(3):
        J[a, a] += tr
    ASt = A @ _skew(S)
    w = vm[3:6]
    W = _skew(w)
    Om = W @ W
    any_w = w[0] != 0.0 or w[1] != 0.0 or w[2] != 0.0
    xr_i, xw_i = dv[:3], dv[3:6]
    xr_m, xw_m = vm[:3], vm[3:6]
    At_i = A.T @ xr_i
    At_m = A.T @ xr_m
    gb = A.T @ g
    s1x_i = np.zeros(3)
    s1x_m = np.zeros(3)
    mw_i = np.zeros(3)
    mw_m = np.zeros(3)
    S1qd = np.zeros(3)
    H = np.zeros((3, 3))     # H[a, b] = C[a][b] . q_dot
    mwk = np.zeros(3)
    for k in range(nq):
        c = comp[k]
        n = node[k]
        c1 = (c + 1) % 3
        c2 = (c + 2) % 3
        cq0 = MsX[n, 0] + Yq[0, n]
        cq1 = MsX[n, 1] + Yq[1, n]
        cq2 = MsX[n, 2] + Yq[2, n]
        cq_c1 = cq1 if c1 == 1 else (cq2 if c1 == 2 else cq0)
        cq_c2 = cq1 if c2 == 1 else (cq2 if c2 == 2 else cq0)
        mwk[c] = 0.0
        mwk[c1] = cq_c2
        mwk[c2] = -cq_c1
        s1 = S1[c, k]
        xi = dv[6 + k]
        xm = vm[6 + k]
        s1x_i[c] += s1 * xi
        s1x_m[c] += s1 * xm
        for cy in range(3):
            mw_i[cy] += mwk[cy] * xi
            mw_m[cy] += mwk[cy] * xm
        inertia[6 + k] = (mqq_dv[k] + s1 * At_i[c]
                          + mwk[0] * xw_i[0] + mwk[1] * xw_i[1] + mwk[2] * xw_i[2])
        momentum[6 + k] = (mqq_vm[k] + s1 * At_m[c]
                           + mwk[0] * xw_m[0] + mwk[1] * xw_m[1] + mwk[2] * xw_m[2])
        # quadratic-velocity terms
        S1qd[c] += s1 * xm
        H[0, c] += cq0 * xm
        H[1, c] += cq1 * xm
        H[2, c] += cq2 * xm
        f = 0.0
        if any_w:
            f -= Om[c, 0] * cq0 + Om[c, 1] * cq1 + Om[c, 2] * cq2
            f -= 2.0 * (w[c1] * Yqd[c2, n] - w[c2] * Yqd[c1, n])
        force[6 + k] = f - Kq[k] + s1 * gb[c]
    inertia[:3] = mass * xr_i - ASt @ xw_i + A @ s1x_i
    inertia[3:6] = -(ASt.T @ xr_i) + J @ xw_i + mw_i
    momentum[:3] = mass * xr_m - ASt @ xw_m + A @ s1x_m
    momentum[3:6] = -(ASt.T @ xr_m) + J @ xw_m + mw_m
    _frame_velocity_forces(A, S, J, w, W, Om, S1qd, H, force)
    _frame_gravity(mass, S, g, A.T @ g, force)
