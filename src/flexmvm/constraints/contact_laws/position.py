"""The position law: the gap at the end of the step held (Signorini at t + h).

g + h (theta u_N+ + (1 - theta) u_N-) >= 0, i.e. u_N+ >= -(g + h (1 - theta) u_N-) / (theta h),
with theta the scheme's; the law of massless (mass-redistributed) contact nodes (Khenous,
Laborde and Renard 2008). Its rows are the pairs whose gap g is within gap_tol +
POSITION_REACH h u_reach (u_reach: the largest slave plus master node speed component),
whatever their u_N-: a massless node's end velocity flips sign from step to step and predicts
nothing (on the runs of docs/contact_law.md this wider set changed no result against
g + h u_N- <= gap_tol). Frictionless closed pairs are held on the geometry they closed with
(contact.pairs, contact.held_pairs), so the step adds no energy (theta = 1/2 conserves it,
theta > 1/2 damps). Not for bonded contact; no penetration recovery beta."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.constraints.contact_laws.spec import LawSpec, Theta

#: pairs are rows when g <= gap_tol + POSITION_REACH h u_reach
POSITION_REACH = 2.0


@dataclass(frozen=True)
class PositionLaw(LawSpec):
    bonded: bool = False
    needs_theta: bool = True
    massless_nodes: bool = True
    conserves_energy: bool = True
    holds_pairs: bool = True

    def row_window(self, h: float, gap_tol: float, speed: float) -> tuple[float, float]:
        """(0, gap_tol + POSITION_REACH h u_reach): g within reach, whatever u_N-."""
        return 0.0, gap_tol + POSITION_REACH * h * speed

    def lower(
        self, gaps: np.ndarray, u_n: np.ndarray, h: float, beta: float, theta: Theta
    ) -> np.ndarray:
        """-(g + h (1 - theta) u_N-) / (theta h): the end gap g + h (theta u_N+ + (1 - theta)
        u_N-) >= 0, theta the scheme's of the step size h (a number or a rule)."""
        th = theta(h) if callable(theta) else theta
        assert th is not None  # options_problem refused a missing theta
        return -(gaps + (h * (1.0 - th)) * u_n) / (th * h)

    def scenario_problem(
        self, bonded: bool, penetration_recovery: float | None
    ) -> tuple[str, str] | None:
        """Not bonded; no penetration_recovery (it is the velocity law's)."""
        problem = super().scenario_problem(bonded, penetration_recovery)
        if problem is None and penetration_recovery is not None:
            message = (
                "penetration_recovery is the velocity law's: the position law holds "
                "the end-of-step gap itself"
            )
            return message, "penetration_recovery"
        return problem


SPEC = PositionLaw("position")
