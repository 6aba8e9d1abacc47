"""The end-of-step velocity projection onto the joints' velocity constraint (issue 51, item 9).

The Moreau-Jean step (moreau_jean/scheme.py) closes the joints at position level,
phi(x(t) (+) h v_m) = 0, so its rows fix the midpoint velocity v_m = theta v+ + (1 - theta) v-
and leave v+ = (v_m - (1 - theta) v-) / theta along them: a velocity error e in
range(M^-1 Phi^T) changes neither v_m nor any position, and goes on as
e_{n+1} = -(1 - theta) / theta e_n, an alternation at the step's Nyquist frequency that
theta = 1/2 does not damp and theta = 0.505 hardly does. On a turning mechanism it is fed every
step and grows: the slider-crank's pin velocities alternated by +-17 m/s (MVM) on a ~20 m/s
signal at theta = 0.505, by +-190 m/s at theta = 1/2, while the midpoint velocities
(x(t + h) - x(t)) / h stayed smooth to 0.2 m/s (docs/notes/2026-11-29-velocity-ringing.md).

The cure, as RATTLE adds to SHAKE (Andersen 1983; Leimkuhler and Reich, "Simulating
Hamiltonian Dynamics", 2004, sec. 7.2): after the step, v+ is projected onto the velocity
constraint at the step's end,

    v+ <- v+ - W^-1 Phi_e^T mu,     (Phi_e W^-1 Phi_e^T) mu = Phi_e v+ + d phi / d t,

Phi_e the joints' rows at x(t + h), d phi / d t their explicit time rate (drives, prescribed
motions), W = M + theta^2 h^2 K the step's factored iteration matrix (the projection's metric:
no other factorization; the rows are closed exactly whatever the metric). Positions are not
touched (the joints stay closed at position level) and a system without joints is not touched
at all (the seed case's histories stay bit for bit).

Taken only at theta > 1/2 (moreau_jean/scheme.py), where the scheme already damps what the step
cannot resolve: the projection removes the energy of the velocity's part across the rows (1/2 r^T
D^-1 r per step, r = Phi_e v+ + d phi / d t), so at theta = 1/2 it would spoil the midpoint
rule's energy balance, which tests hold to 1e-8 (a driven arm) and 1e-10 J (a rotational
spring); a mechanism run at theta = 1/2 keeps its ringing (the slider-crank: +-190 m/s at pin B).
"""

from __future__ import annotations

import numpy as np

from flexmvm.constraints.rows import Rows, stack
from flexmvm.integrate.row_products import flat_product


def end_rows(system, states, t: float) -> tuple[Rows, np.ndarray]:
    """(Phi_v at ``states``, d phi / d t at fixed configuration) of every joint at time t."""
    bodies = system.bodies
    parts, rates = [], []
    for joint in system.joints:
        _, rows = joint.evaluate(bodies, states, t)
        parts.append(rows)
        rates.append(np.asarray(joint.time_rate(bodies, states, t), float))
    return stack(parts), np.concatenate(rates)


def project_joint_velocities(system, matrices, carried, states, t: float, h: float) -> np.ndarray:
    """Project the velocities of ``states`` (the step's end at time t, written in place) onto
    Phi_e v + d phi / d t = 0 in the metric of the step's W (module doc); matrices: the
    integrator's IterationMatrices (W^-1 Phi^T), carried: its CarriedState, whose contractions
    of the end states follow the change. Returns -mu [N s] (n_j,): the projection's
    impulses, v+ changed by W^-1 Phi_e^T (-mu), in the sign of the step's joint impulses."""
    rows, rate = end_rows(system, states, t)
    r = rows.times([st.v for st in states]) + rate
    # W's frame blocks at the end configuration (the next step starts from them): the
    # impulses then change the momenta by Phi_e^T mu exactly, as the rows' forces would
    matrices.prepare(states, h, refresh_tol=None)
    Y = matrices.joint_columns(rows, h)
    D = np.zeros((rows.m, rows.m))
    for b, Yb in Y.items():
        D += rows.body_matrix(b) @ Yb
    mu = np.linalg.solve(D, r)
    for b, Yb in Y.items():
        _shift_velocity(system.bodies[b], carried, b, states[b], -(Yb @ mu))
    return -mu


def _shift_velocity(body, carried, b: int, st, dv: np.ndarray) -> None:
    """st.v += dv (a new array) with body b's carried L(q_dot), k_hat q_dot and M_qq q_dot
    updated by the same increment (integrate.moreau_jean.carried), when they were made for st."""
    c = carried.of_state(b, st)
    st.v = st.v + dv
    if c is None:
        return
    c.v = st.v
    dqd = dv[6:]
    if body.nq and np.any(dqd):
        LD = body.carried_contractions(dqd, carried.pool)
        c.Lqd = c.Lqd + LD
        c.Kqd = c.Kqd + flat_product(body.k_hat, dqd)
        c.Mqd = c.Mqd + body.contraction_trace(LD)
