"""Start a flexible body in its quasi-static sag on its joints (`sagged = true` in
[bodies.placement]) instead of undeformed.

A body that starts undeformed under gravity is not in equilibrium: it starts to vibrate at its
bending frequencies (a 1 m rod hanging on two strings: ~10 um at 60 Hz and up), and nothing in
the model damps that. A rod hanging still is sagged. At rest (no velocity terms) the body's
frame accelerates by a, its strings pull with lambda, and its elastic coordinates follow the
load quasi-statically (q_ddot = 0; the body's modes are far faster than its swing):

    [M_ff  -C_f^T] [a     ]   [ F_f  ]        k_hat q = F_q - M_qf a + C_q^T lambda
    [C_f    0    ] [lambda] = [-gamma]

(gamma = dC/dt v: 0 at rest; for a frame translating at v, v_perp^2 / l for a string)
(F: generalized gravity, C = [C_f C_q]: the joint rows of the body, M: its mass matrix at the
current state; the body's other joints' ends held). For a body hanging still a = 0 and q is its
static sag; for a pendulum released from rest on tilted strings a is its tangential
acceleration and q the sag under the load g - a along the strings, which then changes only as
slowly as the swing. The frame is then moved by the least change (C_f delta = -C_q q) that keeps
the joint points where they were; two passes (the second at the moved state) leave the joint
rows satisfied to second order in the sag.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from flexmvm.bodies.rotation import axis_angle
from flexmvm.errors import InputError
from flexmvm.fe.modes import factor
from flexmvm.integrate.state import BodyState


def _joint_rows(system, states, b: int) -> np.ndarray:
    rows = []
    for joint in system.joints:
        _, r = joint.evaluate(system.bodies, states, 0.0)
        m = r.body_matrix(b)
        if m is not None:
            rows.append(m)
    return np.vstack(rows) if rows else np.zeros((0, system.bodies[b].nv))


def _rows_rate(system, states, b: int, eps_s: float = 1e-6) -> np.ndarray:
    """d(C)/dt v of body b's joint rows for a frame translating at v[:3] (central difference):
    the velocity terms of the constraint acceleration (for a string v_perp^2 / l)."""
    st = states[b]
    out = []
    for sgn in (1.0, -1.0):
        moved = list(states)
        moved[b] = BodyState(st.r + sgn * eps_s * st.v[:3], st.A, st.q, st.v)
        out.append(_joint_rows(system, moved, b) @ st.v)
    return (out[0] - out[1]) / (2 * eps_s)


def quasi_static_sag(
    system, states: list[BodyState], b: int, where: str = "", passes: int = 2
) -> BodyState:
    """The state of body b in its quasi-static sag (module docstring), at rest or translating
    (the constraint acceleration then has its velocity terms, v_perp^2 / l for a string);
    InputError if the frame turns or the body vibrates (omega, q_dot != 0). A rigid body
    (nq = 0) is returned unchanged."""
    body = system.bodies[b]
    st = states[b]
    if body.nq == 0:
        return st
    if np.any(st.v[3:]):
        raise InputError(
            f"{where or body.name}: sagged = true needs a body whose frame does not "
            f"turn, got angular velocity {st.v[3:6].tolist()} rad/s"
        )
    k_hat = body.k_hat
    solve = factor(sp.csc_matrix(k_hat)) if sp.issparse(k_hat) else None
    cur = [s.copy() for s in states]
    for _ in range(passes):
        s = cur[b]
        terms = body.inertia_terms(s.q)
        M_ff = body.frame_mass(s.A, terms[0], terms[1])
        M_fq = body.coupling_mass(s.A, terms[2])
        F = body.gravity_forces(s.A, s.q, system.gravity, terms[0])
        C = _joint_rows(system, cur, b)
        Cf, Cq = C[:, :6], C[:, 6:]
        m = len(C)
        kkt = np.block([[M_ff, -Cf.T], [Cf, np.zeros((m, m))]])
        gamma = _rows_rate(system, cur, b) if np.any(s.v) and m else np.zeros(m)
        sol = np.linalg.lstsq(kkt, np.concatenate([F[:6], -gamma]), rcond=None)[0]
        a, lam = sol[:6], sol[6:]
        rhs = F[6:] - M_fq.T @ a + Cq.T @ lam
        q = solve(rhs) if solve is not None else np.linalg.solve(np.asarray(k_hat), rhs)
        dq = q - s.q
        delta = -np.linalg.pinv(Cf) @ (Cq @ dq) if m else np.zeros(6)
        w = delta[3:6]
        A = s.A @ axis_angle(w, float(np.linalg.norm(w))) if np.any(w) else s.A
        cur[b] = BodyState(s.r + delta[:3], A, q, s.v.copy())
    return cur[b]
