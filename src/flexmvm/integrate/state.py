"""State of a body during integration: frame position r, rotation A, elastic q, velocity v."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.bodies.rotation import expm_so3


@dataclass
class BodyState:
    """r (3,) [m], A (3,3) body->global, q (nq,), v = [r_dot, omega (body), q_dot] (6+nq,)."""

    r: np.ndarray
    A: np.ndarray
    q: np.ndarray
    v: np.ndarray

    def copy(self) -> BodyState:
        return BodyState(self.r.copy(), self.A.copy(), self.q.copy(), self.v.copy())

    def advanced(self, v_mean: np.ndarray, dt: float) -> BodyState:
        """Configuration after moving with velocity v_mean for dt (Lie-group update of A)."""
        return BodyState(
            self.r + dt * v_mean[:3],
            self.A @ expm_so3(dt * v_mean[3:6]),
            self.q + dt * v_mean[6:],
            v_mean,
        )
