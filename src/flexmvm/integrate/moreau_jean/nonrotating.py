"""The Moreau-Jean step of bodies whose frames do not rotate: one solve per body.

When every body enters the step with omega = 0 and no joint acts, take omega+ = 0. The
quadratic-velocity forces vanish, A stays constant, and the translational and elastic rows of
the scheme (see moreau_jean/scheme.py) are linear in dv = v+ - v- with constant coefficients:

    [ m I       A S1 ] [dr_dot]   [ h (m g + f_r)                                      ]
    [ S1^T A^T  W_qq ] [dq_dot] = [ h (S1^T A^T g + f_q - K (q + theta h q_dot) - C q_dot) ]
                                  + Phi_t^T lambda

with W_qq = M_qq + theta h C + theta^2 h^2 K (body_solver). So one back-substitution per body
gives v_free, D = Phi W_t^-1 Phi^T and W_t^-1 Phi^T lambda come from the cached nodal
columns (integrate.moreau_jean.compliance), and the LCP on D gives lambda. No Newton iteration is
needed.

Then the rotational rows of the full scheme are evaluated at this solution (omega_m = 0,
domega = 0):

    res_w = S(q_m) x (A^T dr_dot) + M_wq(q_m) dq_dot - h S(q_m) x (A^T g) - h tau_loads
            - Phi_w^T lambda

If |res_w| <= rtol * scale for every body, omega+ = 0 satisfies every equation of the scheme
to the Newton tolerance, so this IS the step of the full scheme. Otherwise the caller takes
the general Newton step. An axial impact of rods is such a case (symmetric about the axis,
so no moment acts on either frame).
"""

from __future__ import annotations

import numpy as np

from flexmvm.bodies.rotation import cross3
from flexmvm.integrate.moreau_jean.compliance import DenseCompliance
from flexmvm.integrate.moreau_jean.coulomb import solve_contact_impulses
from flexmvm.integrate.state import BodyState
from flexmvm.integrate.system import ContactRows
from flexmvm.loads.applied import applied_forces


def applies(system, states: list[BodyState]) -> bool:
    """True when no joint acts, every load is fixed in space (loads: state_independent) and
    every frame enters the step with omega exactly 0."""
    return (
        not system.joints
        and all(load.state_independent for load in system.loads)
        and all(not np.any(st.v[3:6]) for st in states)
    )


def nonrotating_step(
    system,
    solvers,
    theta: float,
    rtol: float,
    loads: tuple,
    t: float,
    states: list[BodyState],
    h: float,
    crows: ContactRows,
):
    """The step above. Returns (new states, contact impulses, translational residual summed
    over the bodies (3,) [N s], complementarity residual of the LCP) or None when a rotational
    residual exceeds rtol times the body's momentum scale (the frame would rotate)."""
    g = system.gravity
    f0 = applied_forces(loads, system.bodies, states, t + theta * h)  # fixed in space
    v_free, rhs_scale = [], []
    for b, (body, solver, st) in enumerate(zip(system.bodies, solvers, states)):
        solver.prepare_translation(h, st.A)
        rhs = _free_rhs(body, st, g, f0.get(b), theta, h)
        dv = solver.solve_translation(rhs)
        v = st.v.copy()
        v[:3] += dv[:3]
        v[6:] += dv[3:]
        v_free.append(v)
        rhs_scale.append(float(np.abs(rhs).max()) if rhs.size else 0.0)
    v_plus = [v.copy() for v in v_free]
    lam, lcp_res = np.zeros(crows.rows.m), 0.0
    if crows.rows.m:
        lam, lcp_res = _contact_impulses(system, solvers, h, crows, v_free, v_plus)
    taus = _load_torques(system.bodies, loads, states, v_plus, theta, h, t)
    for b, (body, st, vp) in enumerate(zip(system.bodies, states, v_plus)):
        tau = taus[b][3:6] if b in taus else np.zeros(3)
        if not _rotation_balanced(
            body, st, vp, crows, lam, b, tau, g, theta, h, rtol, rhs_scale[b]
        ):
            return None
    res_t = sum(
        (
            _translation_residual(body, st, vp, crows, lam, b, g, f0.get(b), h)
            for b, (body, st, vp) in enumerate(zip(system.bodies, states, v_plus))
        ),
        np.zeros(3),
    )
    new_states = []
    for st, vp in zip(states, v_plus):
        vm = theta * vp + (1.0 - theta) * st.v
        new_states.append(BodyState(st.r + h * vm[:3], st.A.copy(), st.q + h * vm[6:], vp))
    return new_states, lam, res_t, lcp_res


def _translation_residual(body, st, vp, crows, lam, b, g, f_applied, h) -> np.ndarray:
    """Translational rows of the scheme at the step's solution [N s] (global frame):
    m dr_dot + A S1 dq_dot - h (m g + f) - Phi_r^T lambda."""
    dv = vp - st.v
    res = body.inv.mass * dv[:3] - h * body.inv.mass * g
    if body.nq:
        res += st.A @ (body.inv.S1 @ dv[6:])
    if f_applied is not None:
        res -= h * f_applied[:3]
    blk = crows.rows.blocks.get(b)
    if blk is not None:
        res -= blk[0][:, :3].T @ lam
    return res


def _free_rhs(body, st, g, f_applied, theta, h) -> np.ndarray:
    """Right-hand side [h (m g + f_r), h (S1^T A^T g + f_q - K q_pred - C q_dot)] (3 + nq,)."""
    rhs = np.zeros(3 + body.nq)
    if np.any(g):
        rhs[:3] = h * body.inv.mass * g
        if body.nq:
            rhs[3:] = h * (body.inv.S1.T @ (st.A.T @ g))
    if body.nq:
        q_pred = st.q + (theta * h) * st.v[6:]
        rhs[3:] += h * body.elastic_forces(q_pred, st.v[6:])
    if f_applied is not None:
        rhs[:3] += h * f_applied[:3]
        rhs[3:] += h * f_applied[6:]
    return rhs


def _contact_impulses(
    system, solvers, h, crows: ContactRows, v_free, v_plus
) -> tuple[np.ndarray, float]:
    """(lambda (m,), complementarity residual) of the LCP on D = Phi W_t^-1 Phi^T; adds W_t^-1 Phi^T lambda to v_plus.
    Bodies with nodal rows go through the cached nodal columns
    (integrate.moreau_jean.compliance)."""
    rows = crows.rows
    D = np.zeros((rows.m, rows.m))
    c = -crows.lower.copy()
    comps = {}
    for b, (bf, bq) in rows.blocks.items():
        solver, body, v = solvers[b], system.bodies[b], v_free[b]
        sel = rows.nodal.get(b)
        if sel is not None and body.nq:
            comps[b] = solver.translation_compliance(h, bf, sel)
            phi_q_v = (sel @ body.psi) @ v[6:] if body.is_sparse else bq @ v[6:]
        else:
            phi = np.hstack([bf[:, :3], bq])
            comps[b] = DenseCompliance(phi, solver.solve_translation(phi.T))
            phi_q_v = bq @ v[6:] if body.nq else 0.0
        D += comps[b].D
        c += bf[:, :3] @ v[:3] + phi_q_v
    lam, res = solve_contact_impulses(D, c, 0, crows)
    for b, comp in comps.items():
        dv = comp.velocity(lam)
        v_plus[b][:3] += dv[:3]
        v_plus[b][6:] += dv[3:]
    return lam, res


def _load_torques(bodies, loads, states, v_plus, theta, h, t) -> dict[int, np.ndarray]:
    """The applied loads' generalized forces at the step's elastic midpoint q_m (frames fixed)."""
    if not loads:
        return {}
    mids = []
    for st, vp in zip(states, v_plus):
        vm = theta * vp + (1.0 - theta) * st.v
        mids.append(BodyState(st.r, st.A, st.q + theta * h * vm[6:], vm))
    return applied_forces(loads, bodies, mids, t + theta * h)


def _rotation_balanced(body, st, vp, crows, lam, b, tau, g, theta, h, rtol, rhs_scale) -> bool:
    """|res_w| <= rtol * scale at the step's solution (module docstring)."""
    dv = vp - st.v
    vm = st.v + theta * dv
    q_m = st.q + theta * h * vm[6:]
    S = body.first_moment(q_m) if body.nq else body.inv.S0
    res = cross3(S, st.A.T @ dv[:3]) - h * tau
    if np.any(g):
        res -= h * cross3(S, st.A.T @ g)
    if body.nq:
        res += body.rotational_coupling(q_m) @ dv[6:]
    blk = crows.rows.blocks.get(b)
    contact = np.zeros(3 + body.nq)
    if blk is not None:
        res -= blk[0][:, 3:6].T @ lam
        contact[:3] = blk[0][:, :3].T @ lam
        if body.nq:
            contact[3:] = blk[1].T @ lam
    momentum = body.inv.mass * float(np.abs(vm[:3]).max())
    scale = max(rhs_scale, float(np.abs(contact).max()) if contact.size else 0.0, momentum)
    return float(np.abs(res).max()) <= rtol * max(scale, 1e-300)
