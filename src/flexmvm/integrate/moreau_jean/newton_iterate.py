"""The state of one step's modified Newton iteration (NewtonIterate) and what it measures:
the joints' constraint values and rows (joint_rows) and the momentum residual relative to each
body's momentum scale, constraint impulses included (relative_residual), and the residual that
round-off in the positions alone leaves (roundoff_momenta, at_roundoff). Used by the scheme,
integrate.moreau_jean."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from flexmvm.constraints.rows import Rows, stack
from flexmvm.integrate.moreau_jean.relaxation import ACTIVATE_RATIO
from flexmvm.integrate.row_products import body_impulse

ROUNDOFF_FLOOR = 1e-7  # a residual below this that stops decreasing is round-off (large bases)
TRANSLATION_RTOL = 1e-13  # ...but the frame's translational rows (sums: no such floor) must
# converge to this, so linear momentum drifts < 1e-9 over an impact


@dataclass
class NewtonIterate:
    """The modified Newton iteration of one step: the iterate v+ (per body), the free
    velocity v_free = v+ - W^-1 R it came from, the constraint impulses lambda (joint rows
    first), the contact rows' compliance per body and their Delassus matrix D_cc (made
    once, again when W is refreshed), and what the convergence test keeps."""

    v_plus: list[np.ndarray]
    v_free: list[np.ndarray]
    lam: np.ndarray
    contact_compliance: dict | None = None
    contact_delassus: np.ndarray | None = None
    last_norm: float = np.inf  # largest absolute residual of the last iterate
    last_rel: float = np.inf  # its relative residual
    lcp_max: float = 0.0  # largest complementarity residual of the LCP solves
    relaxed: bool = False  # the last iterate was relaxed (integrate.moreau_jean.relaxation)
    stalled: bool = False
    at_roundoff: bool = False  # stopped on the round-off of the positions (at_roundoff)
    rel: float = np.inf  # relative residual (constraint impulses included)
    rel_translation: float = np.inf  # the same of the translational rows alone
    translation_sum: np.ndarray = field(default_factory=lambda: np.zeros(3))  # [N s]
    residuals: list = field(default_factory=list)  # per body, constraint impulses included

    def converged_at(self, it, h, phi, rtol, max_iter, stall, roundoff_kgm) -> bool:
        """Convergence test of iterate it > 0, after relative_residual filled rel,
        rel_translation and residuals: the residual within rtol and the joints closed (phi
        [m] within 1e-12), or a residual on the round-off floor (below ROUNDOFF_FLOOR, not
        gaining a factor ``stall`` per iterate, translational rows within TRANSLATION_RTOL or
        max_iter reached: accepted, and counted as not converged in StepResult, unless every
        body's residual is below the round-off of its positions, at_roundoff: converged).
        Not accepted: marks ``stalled`` for the relaxation and keeps rel as last_rel."""
        phi_ok = not (phi.size and np.abs(phi).max() > 1e-12)
        stalled = it > 2 and (self.rel >= stall * self.last_rel or it >= max_iter)
        floor = stalled and self.rel < ROUNDOFF_FLOOR
        self.at_roundoff = stalled and at_roundoff(self.residuals, roundoff_kgm, h)
        if phi_ok and (
            self.rel <= rtol
            or self.at_roundoff
            or (floor and (self.rel_translation <= TRANSLATION_RTOL or it >= max_iter))
        ):
            return True
        # a residual over the tolerance only in its translational rows is not accepted either,
        # though their balance (integrate.moreau_jean.momentum_balance) would bring it within:
        # accepting it raised the momentum error after the seed case's separation fourfold
        self.stalled = it >= 2 and self.rel > ACTIVATE_RATIO * self.last_rel
        self.last_rel = self.rel
        return False


def joint_rows(system, t, h, mids, ends):
    """(phi at the end configurations, rows Phi_v at the midpoint) of the joints."""
    if not system.joints:
        return np.zeros(0), Rows.empty()
    bodies = system.bodies
    phis, parts = [], []
    for joint in system.joints:
        _, rows = joint.evaluate(bodies, mids, t + 0.5 * h)
        phis.append(joint.value(bodies, ends, t + h))
        parts.append(rows)
    return np.concatenate(phis), stack(parts)


def relative_residual(bodies, R, joint_jacobian, crows: Rows, lam, n_j, scales) -> tuple:
    """Largest momentum residual (constraint impulses included) relative to each body's
    momentum scale (the largest of its inertia, force, momentum and constraint impulse
    terms); the same for the translational rows alone; the sum over bodies of
    the translational rows [N s] (the step's linear-momentum error: internal and constraint
    forces cancel between bodies); and per body its residual with the constraint impulses."""
    worst, worst_t = 0.0, 0.0
    res_t = np.zeros(3)
    residuals = []
    for b, (r, sc) in enumerate(zip(R, scales)):
        res = r
        # the scale includes the constraint impulses on the body: a body held still by a
        # joint (a grounded wall) balances them alone, with no momentum of its own
        if b in joint_jacobian:
            imp = joint_jacobian[b].T @ lam[:n_j]
            res = res - imp
            sc = max(sc, float(np.abs(imp).max()))
        if b in crows.blocks:
            imp = body_impulse(crows, b, bodies[b], lam[n_j:])
            res = res - imp
            sc = max(sc, float(np.abs(imp).max()))
        worst = max(worst, float(np.abs(res).max()) / max(sc, 1e-300))
        worst_t = max(worst_t, float(np.abs(res[:3]).max()) / max(sc, 1e-300))
        res_t += res[:3]
        residuals.append(res)
    return worst, worst_t, res_t, residuals


def roundoff_momenta(bodies) -> np.ndarray:
    """eps m L per body [kg m] (m its mass, L the largest extent of its undeformed nodes):
    divided by the step h, the momentum of a position error of one unit in the last place
    over the step, eps L / h, on the whole body. No residual of the step's momentum balance
    can be trusted below it: positions carry that error, velocities derived from them over
    one step carry eps L / h."""
    eps = np.finfo(float).eps
    out = np.empty(len(bodies))
    for b, body in enumerate(bodies):
        extent = float(np.ptp(body.X, axis=0).max()) if len(body.X) else 1.0
        out[b] = eps * float(body.inv.mass) * extent
    return out


def at_roundoff(residuals, momenta_kgm: np.ndarray, h: float) -> bool:
    """True if every body's residual (constraint impulses included) [N s, N m s] is below
    its round-off momentum eps m L / h (roundoff_momenta): an iteration stalled there has
    converged as far as the positions allow. A body at rest holds a momentum scale of
    round-off (a joint's impulse against the round-off of its constraint), so that a
    residual relative to it cannot fall below the floor that relative_residual assumes."""
    return all(float(np.abs(r).max(initial=0.0)) <= p / h for r, p in zip(residuals, momenta_kgm))
