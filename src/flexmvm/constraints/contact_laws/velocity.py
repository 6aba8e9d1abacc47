"""The velocity law (default): Moreau's impact law with a capped penetration recovery.

u_N+ >= min(beta max(0, -g) / h, max(0, -u_N-)) (restitution 0, with a Baumgarte-like recovery
of a penetration capped by the pair's closing speed u_N-, so that it adds no restitution); the
rows are the pairs predicted to close within the step, g + h u_N- <= gap_tol. For contact nodes
with mass, and for bonded contact."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.constraints.contact_laws.spec import LawSpec, Theta


@dataclass(frozen=True)
class VelocityLaw(LawSpec):
    def lower(
        self, gaps: np.ndarray, u_n: np.ndarray, h: float, beta: float, theta: Theta
    ) -> np.ndarray:
        """min(beta max(0, -g) / h, max(0, -u_N-)): a pair leaves a penetration no faster
        than it arrived, and one at rest relative to its master (u_N- >= 0, the step after
        its impact) is held, not pushed out. Uncapped, the recovery turned the impact's own
        penetration h (1 - theta) |u_N-| into a separation velocity beta (1 - theta) |u_N-|
        the next step: restitution 0.09 between rigid bodies at theta = 0.55 instead of 0,
        and energy fed into reduced contact faces (the PA6 chatter of docs/studies.md)."""
        return np.minimum(beta * np.maximum(0.0, -gaps) / h, np.maximum(0.0, -u_n))


SPEC = VelocityLaw("velocity")
