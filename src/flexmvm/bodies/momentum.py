"""The impulse-momentum terms of a flexible body in one compiled kernel.

For the Moreau-Jean residual (integrate.moreau_jean) of a body with elastic coordinates, at the
midpoint configuration (A, q_m) with the carried contractions L(q_m), L(q_dot_m) and k_hat q_m:

    inertia  = M(A, q_m) dv                                   (Shabana ch. 5; bodies.body)
    force    = Q_v(A, q_m, v_m) + gravity - k_hat q_m         (quadratic-velocity terms)
    momentum = M(A, q_m) v_m

exactly as FlexibleBody.inertia_terms, mass_times, velocity_forces and gravity_forces compute
them in numpy (tests/test_momentum_kernel.py holds them to round-off on random inputs), but
without forming the (3, 3, nq) array C = G1 + L(q_m) or any 6 x nq block: a step of a reduced
body is a few hundred small numpy calls otherwise, each costing more in its call overhead
than in its arithmetic, which is O(9 nq) (docs/notes/2026-11-27-comment-measurements.md).
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
    cwJw = np.array(
        [w[1] * Jw[2] - w[2] * Jw[1], w[2] * Jw[0] - w[0] * Jw[2], w[0] * Jw[1] - w[1] * Jw[0]]
    )
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
def _frame_inertia(q, Lq, S0, S1, G0, G1):  # pragma: no cover - compiled
    """S = S0 + S1 q (3,) and the inertia tensor J = tr(Gs) I - Gs (3, 3), Gs the symmetric
    part of G[a, b] = G0[a, b] + G1[b][a] q + C[a][b] q, C = G1 + L(q) (Shabana ch. 5)."""
    nq = q.shape[0]
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
    return S, J


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _rotation_coupling(Lq, G1):  # pragma: no cover - compiled
    """M_wq (3, nq): row c = C[a][b] - C[b][a] over cyclic (c, a, b), C = G1 + L(q)."""
    nq = Lq.shape[2]
    Mwq = np.empty((3, nq))
    for c in range(3):
        a = _CYC[c, 1]
        b = _CYC[c, 2]
        for k in range(nq):
            Mwq[c, k] = G1[a, b, k] + Lq[a, b, k] - G1[b, a, k] - Lq[b, a, k]
    return Mwq


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _mass_times(A, ASt, J, S1, Mwq, mass, x, mqq_x, out):  # pragma: no cover - compiled
    """out = M x (6 + nq,), M = [[m I, -A S~, A S1], [., J, M_wq], [., ., M_qq]] symmetric
    (Shabana ch. 5); ASt = A S~, mqq_x = M_qq x_q."""
    nq = S1.shape[1]
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


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _elastic_velocity_forces(w, Om, Lq, Lqd, G1, Kq, force):  # pragma: no cover - compiled
    """The q rows of the quadratic-velocity forces (FlexibleBody.velocity_forces) minus the
    elastic force: force[6 + k] = -Om : C[.][.][k]^T - 2 w . (L(q_dot) skew part) - Kq[k];
    Om = w~ w~. Without spin only -Kq."""
    nq = Kq.shape[0]
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


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def momentum_terms(
    A, q, dv, vm, Lq, Lqd, Kq, mqq_dv, mqq_vm, mass, S0, S1, G0, G1, g, inertia, force, momentum
):  # pragma: no cover - compiled
    """Fill inertia, force, momentum (each (6 + nq,)) as described in the module docstring.

    A (3, 3); q (nq,) = q_m; dv, vm (6 + nq,); Lq, Lqd (3, 3, nq) = L(q_m), L(q_dot_m); Kq =
    k_hat q_m; mqq_dv, mqq_vm = M_qq dv_q, M_qq vm_q; S0 (3,), S1 (3, nq), G0 (3, 3), G1
    (3, 3, nq) with G1[a, b] = inv.G1[a][b]; g (3,) gravity [m/s^2] (zeros: none)."""
    nq = q.shape[0]
    S, J = _frame_inertia(q, Lq, S0, S1, G0, G1)
    Mwq = _rotation_coupling(Lq, G1)
    ASt = A @ _skew(S)
    w = vm[3:6]
    # --- inertia = M dv and momentum = M vm (M_fq = [A S1; M_wq]) -------------------------
    _mass_times(A, ASt, J, S1, Mwq, mass, dv, mqq_dv, inertia)
    _mass_times(A, ASt, J, S1, Mwq, mass, vm, mqq_vm, momentum)
    # --- quadratic-velocity forces (FlexibleBody.velocity_forces) ---------------------------
    W = _skew(w)
    Om = W @ W
    qd = vm[6:]
    S1qd = np.zeros(3)
    H = np.zeros((3, 3))  # H[a, b] = C[a][b] . q_dot
    for k in range(nq):
        for a in range(3):
            S1qd[a] += S1[a, k] * qd[k]
            for b in range(3):
                H[a, b] += (G1[a, b, k] + Lq[a, b, k]) * qd[k]
    _frame_velocity_forces(A, S, J, w, W, Om, S1qd, H, force)
    _elastic_velocity_forces(w, Om, Lq, Lqd, G1, Kq, force)
    # --- gravity (FlexibleBody.gravity_forces) -----------------------------------------------
    if g[0] != 0.0 or g[1] != 0.0 or g[2] != 0.0:
        gb = A.T @ g
        _frame_gravity(mass, S, g, gb, force)
        for k in range(nq):
            force[6 + k] += S1[0, k] * gb[0] + S1[1, k] * gb[1] + S1[2, k] * gb[2]


# no "reassoc" (as nodal_contraction._compact): its sums gather by node, which LLVM's
# vectorised reassociated sums run slower; the results differ by round-off only
# (docs/notes/2026-11-27-comment-measurements.md)
@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def _nodal_frame_inertia(q, Yq, S0, S1, G0, MsX, node, comp):  # pragma: no cover - compiled
    """_frame_inertia for a nodal basis (momentum_terms_nodal's docstring): S (3,) and J
    (3, 3) from the compact contraction Yq = Y(q_m), in scalar accumulators."""
    nq = q.shape[0]
    # S = S0 + S1 q;  G[a, b] = G0[a, b] + G1[b][a] q + C[a][b] q, where for coordinate k
    # (component c): G1[b][a] q adds M_s X[n, b] q_k to row c, C[a][b] q adds Cq[a, n] q_k
    # to column c
    s0, s1_, s2 = S0[0], S0[1], S0[2]
    g00 = g01 = g02 = g10 = g11 = g12 = g20 = g21 = g22 = 0.0
    for k in range(nq):
        c = comp[k]
        n = node[k]
        qk = q[k]
        m0 = MsX[n, 0] * qk
        m1 = MsX[n, 1] * qk
        m2 = MsX[n, 2] * qk
        t0 = m0 + Yq[0, n] * qk
        t1 = m1 + Yq[1, n] * qk
        t2 = m2 + Yq[2, n] * qk
        sq = S1[c, k] * qk
        if c == 0:
            s0 += sq
            g00 += m0 + t0
            g01 += m1
            g02 += m2
            g10 += t1
            g20 += t2
        elif c == 1:
            s1_ += sq
            g11 += m1 + t1
            g10 += m0
            g12 += m2
            g01 += t0
            g21 += t2
        else:
            s2 += sq
            g22 += m2 + t2
            g20 += m0
            g21 += m1
            g02 += t0
            g12 += t1
    S = np.array([s0, s1_, s2])
    G = G0 + np.array([[g00, g01, g02], [g10, g11, g12], [g20, g21, g22]])
    Gs = 0.5 * (G + G.T)
    tr = Gs[0, 0] + Gs[1, 1] + Gs[2, 2]
    J = -Gs
    for a in range(3):
        J[a, a] += tr
    return S, J


# long: one loop over the coordinates, its three component branches written out (docstring);
# no "reassoc", as _nodal_frame_inertia
@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def momentum_terms_nodal(
    A,
    q,
    dv,
    vm,
    Yq,
    Yqd,
    Kq,
    mqq_dv,
    mqq_vm,
    mass,
    S0,
    S1,
    G0,
    MsX,
    node,
    comp,
    g,
    inertia,
    force,
    momentum,
):  # pragma: no cover
    """momentum_terms for a basis that selects nodal DOFs (full FE), from the compact
    contractions Yq = Y(q_m), Yqd = Y(q_dot_m) (3, n) of bodies.nodal_contraction: coordinate
    k is component c = comp[k] of node n = node[k], and every (3, 3, nq) array of
    momentum_terms has one nonzero per k and row a:

        C[a][b][k] = Cq[a, n] (b = c),  Cq = (M_s X)^T + Yq;    S1[a, k] = 0 for a != c;
        M_wq[:, k]: [c1] = Cq[c2, n], [c2] = -Cq[c1, n], [c] = 0   (c1, c2 = c + 1, c + 2 mod 3)

    Other arguments as momentum_terms; MsX (n, 3) = M_s X. O(nq) work reading 3 n + 4 nq
    numbers instead of ~30 nq. The sums over k go into scalar accumulators, one branch per
    component (written out below): accumulating into small arrays indexed by c made every
    update a store and a load, and a call about twice as slow
    (docs/notes/2026-11-27-comment-measurements.md)."""
    nq = q.shape[0]
    S, J = _nodal_frame_inertia(q, Yq, S0, S1, G0, MsX, node, comp)
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
    wi0, wi1, wi2 = xw_i[0], xw_i[1], xw_i[2]
    wm0, wm1, wm2 = xw_m[0], xw_m[1], xw_m[2]
    w0, w1, w2 = w[0], w[1], w[2]
    # S1 x_q (inertia: x = dv, momentum: x = vm; the latter is also S1 q_dot of the forces),
    # M_wq x_q, and H[a, b] = C[a][b] . q_dot
    si0 = si1 = si2 = sm0 = sm1 = sm2 = 0.0
    ai0 = ai1 = ai2 = am0 = am1 = am2 = 0.0
    h00 = h01 = h02 = h10 = h11 = h12 = h20 = h21 = h22 = 0.0
    for k in range(nq):
        c = comp[k]
        n = node[k]
        cq0 = MsX[n, 0] + Yq[0, n]
        cq1 = MsX[n, 1] + Yq[1, n]
        cq2 = MsX[n, 2] + Yq[2, n]
        s1 = S1[c, k]
        xi = dv[6 + k]
        xm = vm[6 + k]
        f = 0.0
        if c == 0:  # M_wq[:, k] = [0, cq2, -cq1]
            si0 += s1 * xi
            sm0 += s1 * xm
            ai1 += cq2 * xi
            ai2 -= cq1 * xi
            am1 += cq2 * xm
            am2 -= cq1 * xm
            inertia[6 + k] = mqq_dv[k] + s1 * At_i[0] + cq2 * wi1 - cq1 * wi2
            momentum[6 + k] = mqq_vm[k] + s1 * At_m[0] + cq2 * wm1 - cq1 * wm2
            h00 += cq0 * xm
            h10 += cq1 * xm
            h20 += cq2 * xm
            if any_w:
                f = -(Om[0, 0] * cq0 + Om[0, 1] * cq1 + Om[0, 2] * cq2) - 2.0 * (
                    w1 * Yqd[2, n] - w2 * Yqd[1, n]
                )
            force[6 + k] = f - Kq[k] + s1 * gb[0]
        elif c == 1:  # M_wq[:, k] = [-cq2, 0, cq0]
            si1 += s1 * xi
            sm1 += s1 * xm
            ai0 -= cq2 * xi
            ai2 += cq0 * xi
            am0 -= cq2 * xm
            am2 += cq0 * xm
            inertia[6 + k] = mqq_dv[k] + s1 * At_i[1] - cq2 * wi0 + cq0 * wi2
            momentum[6 + k] = mqq_vm[k] + s1 * At_m[1] - cq2 * wm0 + cq0 * wm2
            h01 += cq0 * xm
            h11 += cq1 * xm
            h21 += cq2 * xm
            if any_w:
                f = -(Om[1, 0] * cq0 + Om[1, 1] * cq1 + Om[1, 2] * cq2) - 2.0 * (
                    w2 * Yqd[0, n] - w0 * Yqd[2, n]
                )
            force[6 + k] = f - Kq[k] + s1 * gb[1]
        else:  # M_wq[:, k] = [cq1, -cq0, 0]
            si2 += s1 * xi
            sm2 += s1 * xm
            ai0 += cq1 * xi
            ai1 -= cq0 * xi
            am0 += cq1 * xm
            am1 -= cq0 * xm
            inertia[6 + k] = mqq_dv[k] + s1 * At_i[2] + cq1 * wi0 - cq0 * wi1
            momentum[6 + k] = mqq_vm[k] + s1 * At_m[2] + cq1 * wm0 - cq0 * wm1
            h02 += cq0 * xm
            h12 += cq1 * xm
            h22 += cq2 * xm
            if any_w:
                f = -(Om[2, 0] * cq0 + Om[2, 1] * cq1 + Om[2, 2] * cq2) - 2.0 * (
                    w0 * Yqd[1, n] - w1 * Yqd[0, n]
                )
            force[6 + k] = f - Kq[k] + s1 * gb[2]
    s1x_i = np.array([si0, si1, si2])
    s1x_m = np.array([sm0, sm1, sm2])
    H = np.array([[h00, h01, h02], [h10, h11, h12], [h20, h21, h22]])
    inertia[:3] = mass * xr_i - ASt @ xw_i + A @ s1x_i
    inertia[3:6] = -(ASt.T @ xr_i) + J @ xw_i + np.array([ai0, ai1, ai2])
    momentum[:3] = mass * xr_m - ASt @ xw_m + A @ s1x_m
    momentum[3:6] = -(ASt.T @ xr_m) + J @ xw_m + np.array([am0, am1, am2])
    _frame_velocity_forces(A, S, J, w, W, Om, s1x_m, H, force)
    _frame_gravity(mass, S, g, gb, force)


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def increment_norm(
    A, q, Lq, mass, S0, S1, G0, G1, dv, mqq_dqd, dq, k_dq
):  # pragma: no cover - compiled
    """dv^T M(A, q) dv + dq^T k_hat dq for the energy ledger's numerical dissipation
    (integrate.energy_ledger): M from Lq = L(q) (3, 3, nq) as in momentum_terms, mqq_dqd =
    M_qq dv_q, k_dq = k_hat dq. One call instead of ~25 numpy calls per body and step; the
    same terms to round-off."""
    S, J = _frame_inertia(q, Lq, S0, S1, G0, G1)
    Mwq = _rotation_coupling(Lq, G1)
    ASt = A @ _skew(S)
    out = np.empty(dv.shape[0])
    _mass_times(A, ASt, J, S1, Mwq, mass, dv, mqq_dqd, out)
    total = 0.0
    for i in range(dq.shape[0]):
        total += dq[i] * k_dq[i]
    for i in range(dv.shape[0]):
        total += dv[i] * out[i]
    return total
