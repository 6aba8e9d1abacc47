"""Balancing the translational rows of an accepted step's residual (systems without joints),
so a run's linear momentum is conserved to round-off, not to the Newton tolerance.

The residual is linear in each body's frame velocity r_dot+ with the midpoint mass matrix's
columns [m I; S~ A^T; S1^T A^T] (bodies.body.FlexibleBody.mass_times; the forces do not
depend on r_dot, the contact rows are those of the step's start), so r_dot+ += d with
d = -res_t / m zeroes the body's translational rows exactly and moves its other rows by
[S~ A^T d; S1^T A^T d], of the size of m d times a lever (~1e-11 relative where the rows were
at the tolerance). Taken only if every row stays within rtol. Without it the step's linear
momentum error is the translational residuals it was accepted with, and one-iterate steps
leave them with a sign, so they add up over a run (docs/performance.md).
"""

from __future__ import annotations

import numpy as np

from flexmvm.bodies.rotation import skew


def balanced_residuals(bodies, res, scales, mids) -> tuple[float, np.ndarray, list]:
    """(relative residual, translational residual sum, per-body r_dot moves d) of the
    residuals res (per body, constraint impulses included) once their translational rows
    are balanced; scales: per body its momentum scale; mids: the midpoint states."""
    new_rel, new_t, moves = 0.0, np.zeros(3), []
    for body, r, mid, scale in zip(bodies, res, mids, scales):
        d = -r[:3] / body.inv.mass
        Ad = mid.A.T @ d
        r = r.copy()
        r[:3] += body.inv.mass * d
        r[3:6] += skew(body.first_moment(mid.q)) @ Ad
        if body.nq:
            r[6:] += body.inv.S1.T @ Ad
        new_rel = max(new_rel, float(np.abs(r).max()) / max(scale, 1e-300))
        new_t += r[:3]
        moves.append(d)
    return new_rel, new_t, moves


def balance_translation(
    balanced, ends, v_plus, theta_h: float, rel: float, res_t: np.ndarray, rtol: float
) -> tuple[float, np.ndarray]:
    """Take the moves of `balanced` (balanced_residuals of the accepted residual) into
    v_plus and the end states (r += theta h d) unless a row would leave rtol. Returns the
    new (relative residual, translational residual sum), or the given ones if not taken."""
    new_rel, new_t, moves = balanced
    if new_rel > max(rel, rtol):
        return rel, res_t
    for b, d in enumerate(moves):
        v_plus[b] = v_plus[b].copy()
        v_plus[b][:3] += d
        ends[b].r = ends[b].r + theta_h * d
    return new_rel, new_t
