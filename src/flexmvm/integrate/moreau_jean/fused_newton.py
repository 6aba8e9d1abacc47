"""A body's Moreau-Jean residual in one compiled call per Newton iterate (issue 49 item 3).

moreau_jean._residual forms, per body and iterate: v_m and dv, the midpoint and end
configurations (r, A exp(dt w~), q: two BodyState.advanced), the carried midpoint
contractions (carried.CarriedState.midpoint: L(q_m), L(q_dot_m), k_hat q_m, M_qq dq_dot,
M_qq v_m), the momentum terms and R = M dv - h F with its momentum scale: ~30 numpy and
Python calls of 1-20 us each around two kernels, twice per body and iterate. Here the G2
contraction L(dq_dot) and k_hat dq_dot stay where they were (one kernel each, the former
on the contraction's thread pool) and the rest is ONE compiled call, `body_residual`, over
plain arrays.

Same arithmetic, same order: elementwise operations without fused multiply-add (no
fastmath here), exp(theta~) by Rodrigues written out as bodies.rotation.expm_so3 (libm's
sin and cos, as Python's math), A exp(theta~) and the kernels it calls (momentum_terms,
residual_and_scale) as before, the 3 x 3 product through the BLAS numpy uses. So the
residual, the states and the carried terms are the reference path's bit for bit
(tests/test_fused_step.py).

Taken by dense reduced and rigid bodies (no nodal contraction, damping, stiffening,
plastic history, and k_hat dq_dot by the product, not the W-images): `applies`.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from flexmvm.bodies.momentum import momentum_terms
from flexmvm.bodies.rotation import expm_so3
from flexmvm.integrate.moreau_jean.carried import MidpointTerms
from flexmvm.integrate.moreau_jean.residual_kernels import residual_and_scale
from flexmvm.integrate.row_products import flat_product
from flexmvm.integrate.state import BodyState

_NO_Q = np.zeros(0)
_NO_L = np.zeros((3, 3, 0))
_NO_S1 = np.zeros((3, 0))


def applies(integ, b: int) -> bool:
    """Whether body b of the integrator takes the fused residual (module doc)."""
    body = integ.system.bodies[b]
    return (
        body.nodal is None
        and body.c_hat is None
        and body.stiffening is None
        and b not in integ.plastic
        and b not in integ.images.bodies
    )


@numba.njit(cache=True, nogil=True)
def _advanced_rotation(A, w, dt, out):  # pragma: no cover - compiled
    """out = A exp((dt w)~) as BodyState.advanced with expm_so3 (its scalar operations in its
    order); returns False when the rotation vector is not finite (the caller raises)."""
    x, y, z = dt * w[0], dt * w[1], dt * w[2]
    xx, yy, zz = x * x, y * y, z * z
    angle = math.sqrt(xx + yy + zz)
    if angle < 1e-8:
        s, c = 1.0, 0.5
    elif not angle < math.inf:
        return False
    else:
        s, c = math.sin(angle) / angle, (1.0 - math.cos(angle)) / angle**2
    xy, xz, yz = c * (x * y), c * (x * z), c * (y * z)
    E = np.empty((3, 3))
    E[0, 0], E[0, 1], E[0, 2] = 1.0 - c * (yy + zz), xy - s * z, xz + s * y
    E[1, 0], E[1, 1], E[1, 2] = xy + s * z, 1.0 - c * (xx + zz), yz - s * x
    E[2, 0], E[2, 1], E[2, 2] = xz - s * y, yz + s * x, 1.0 - c * (xx + yy)
    out[:, :] = A @ E
    return True


@numba.njit(cache=True, nogil=True)
def _advanced(r, A, q, vm, dt, r_out, A_out, q_out):  # pragma: no cover - compiled
    """The configuration after moving with vm for dt (BodyState.advanced, bit for bit)."""
    for i in range(3):
        r_out[i] = r[i] + dt * vm[i]
    for i in range(q.shape[0]):
        q_out[i] = q[i] + dt * vm[6 + i]
    return _advanced_rotation(A, vm[3:6], dt, A_out)


@numba.njit(cache=True, nogil=True)
def body_residual(
    r, A, q, v, vp, th, h, Lq, Lqd, Kq, Kqd, Mqd, has_d, LD, KD, applied,
    mass, S0, S1, G0, G1, g, mid_r, mid_A, mid_q, end_r, end_A, end_q, Lq_m, Lqd_m, Kqd_m, MD,
):  # fmt: skip  # pragma: no cover - compiled
    """One body's residual of an iterate v+ = vp from the state (r, A, q, v) and its carried
    contractions (Lq, Lqd, Kq, Kqd, Mqd); has_d: dq_dot != 0, with LD = L(dq_dot) and
    KD = k_hat dq_dot (else not read, and Lqd_m, Kqd_m not written: they are Lqd, Kqd).
    Fills the midpoint and end configurations, L(q_m), L(q_dot_m), k_hat q_dot_m and
    M_qq dq_dot; returns (ok, vm, R, scale). ok False: a rotation vector not finite."""
    nq = q.shape[0]
    n = v.shape[0]
    vm = np.empty(n)
    dv = np.empty(n)
    cm = 1.0 - th
    for i in range(n):  # residual_kernels.iterate_velocities
        vm[i] = th * vp[i] + cm * v[i]
        dv[i] = vp[i] - v[i]
    th_h = th * h
    ok = _advanced(r, A, q, vm, th_h, mid_r, mid_A, mid_q)
    ok = _advanced(r, A, q, vm, h, end_r, end_A, end_q) and ok
    if not ok:
        return False, vm, dv, 0.0
    # carried.CarriedState.midpoint and _midpoint
    Lq_f, Lqd_f, Lqm_f = Lq.reshape(-1), Lqd.reshape(-1), Lq_m.reshape(-1)
    if has_d:
        LD_f, Lqdm_f = LD.reshape(-1), Lqd_m.reshape(-1)
        for i in range(Lq_f.shape[0]):
            x = Lqd_f[i] + th * LD_f[i]
            Lqdm_f[i] = x
            Lqm_f[i] = Lq_f[i] + th_h * x
        for k in range(nq):
            MD[k] = LD[0, 0, k] + LD[1, 1, k] + LD[2, 2, k]
            Kqd_m[k] = Kqd[k] + th * KD[k]
        Lqd_use, Kqd_use = Lqd_m, Kqd_m
    else:
        for i in range(Lq_f.shape[0]):
            Lqm_f[i] = Lq_f[i] + th_h * Lqd_f[i]
        MD[:] = 0.0
        Lqd_use, Kqd_use = Lqd, Kqd
    Kq_m = np.empty(nq)
    mqq_vm = np.empty(nq)
    for k in range(nq):
        Kq_m[k] = Kq[k] + th_h * Kqd_use[k]
        mqq_vm[k] = Mqd[k] + th * MD[k]
    inertia, F, momentum = np.empty(n), np.empty(n), np.empty(n)
    momentum_terms(
        mid_A, mid_q, dv, vm, Lq_m, Lqd_use, Kq_m, MD, mqq_vm, mass, S0, S1, G0, G1, g,
        inertia, F, momentum,
    )  # fmt: skip
    R, scale = residual_and_scale(inertia, F, momentum, applied, h)
    return True, vm, R, scale


def fused_residual(integ, b: int, t, st: BodyState, vp, h, th, applied=None):
    """moreau_jean._residual of body b (applies(integ, b)) through body_residual: (R, mid,
    end, scale), the carried midpoint terms left with integ.carried_state as its midpoint()
    leaves them."""
    body = integ.system.bodies[b]
    nq = body.nq
    inv = body.inv
    if nq:
        carried = integ.carried_state
        c = carried.at(b, st)
        Lq, Lqd, Kq, Kqd, Mqd = c.Lq, c.Lqd, c.Kq, c.Kqd, c.Mqd
        dqd = vp[6:] - st.v[6:]
        has_d = bool(np.any(dqd))
        LD = body.carried_contractions(dqd, carried.pool) if has_d else Lq
        KD = flat_product(body.k_hat, dqd) if has_d else Kq
        S1, G1 = inv.S1, body.G1_array
    else:
        Lq = Lqd = LD = _NO_L
        Kq = Kqd = Mqd = KD = _NO_Q
        has_d, S1, G1 = False, _NO_S1, _NO_L
    shape = Lq.shape
    Lq_m = np.empty(shape)
    Lqd_m = np.empty(shape) if has_d else Lqd
    Kqd_m = np.empty(nq) if has_d else Kqd
    MD = np.empty(nq)
    mid_r, end_r, mid_A, end_A = np.empty(3), np.empty(3), np.empty((3, 3)), np.empty((3, 3))
    mid_q, end_q = np.empty(nq), np.empty(nq)
    ok, vm, R, scale = body_residual(
        st.r, st.A, st.q, st.v, vp, th, h, Lq, Lqd, Kq, Kqd, Mqd, has_d, LD, KD,
        _NO_Q if applied is None else applied, inv.mass, inv.S0, S1, inv.G0, G1,
        integ.gravity, mid_r, mid_A, mid_q, end_r, end_A, end_q, Lq_m, Lqd_m, Kqd_m, MD,
    )  # fmt: skip
    if not ok:  # a rotation vector not finite: expm_so3's SolverError, word for word
        expm_so3((th * h) * vm[3:6])
        expm_so3(h * vm[3:6])
    if nq:
        integ.carried_state.set_midpoint(
            b, MidpointTerms(LD if has_d else None, Lqd_m, KD if has_d else None, Kqd_m, MD)
        )
    return R, BodyState(mid_r, mid_A, mid_q, vm), BodyState(end_r, end_A, end_q, vm), scale
