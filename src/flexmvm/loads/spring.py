"""Point-to-point linear spring-dampers between two body points, or a body point and a ground
point (constraints.joints.BodyPoint, NodeSetPoint; a ground point is a global (3,) [m]).

With d = x1 - x2, length l = |d|, unit e = d / l and elongation rate l_dot = e . (x1_dot -
x2_dot) = J v (J the row of the joints' DistanceJoint), the tension

    f = k (l - l0) + c l_dot        [N]

pulls the points together: the generalized force is -f J^T (Shabana, *Dynamics of Multibody
Systems*, 3rd ed., sect. 3.7, "spring-damper-actuator elements"). Its stored energy is
k (l - l0)^2 / 2, its damper dissipates c l_dot^2 [W].

Newton (integrate.moreau_jean): the force enters the residual only; the iteration matrix
W = M + theta^2 h^2 K stays the bodies' own. The modified Newton iteration then contracts
with the factor ~ theta^2 h^2 k / m_eff per iterate for a spring between masses m_eff (and
theta h c / m_eff for its damper): it converges in the default iteration limit while these
are well below 1, i.e. for a spring far softer than the body (k << m_eff / (theta h)^2) and a
step that resolves the spring's own period (h << 2 pi sqrt(m_eff / k)), as any accurate run
has (measurements: docs/notes/2026-11-27-loads-and-energy-ledger.md; the driven rod of
tests/test_loads_scenario.py converges at every step).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.constraints.joints import BodyPoint, NodeSetPoint
from flexmvm.constraints.rows import Rows
from flexmvm.errors import InputError


def nonnegative(value: float, what: str) -> float:
    v = float(value)
    if not (np.isfinite(v) and v >= 0.0):
        raise InputError(f"{what} must be a finite number >= 0, got {value!r}")
    return v


@dataclass(frozen=True)
class PointSpring:
    """A linear spring-damper: stiffness_n_per_m k, damping_n_s_per_m c, rest_length_m l0
    between point p1 and p2 (a point of another body, or a ground point (3,) [m])."""

    p1: BodyPoint | NodeSetPoint
    p2: BodyPoint | NodeSetPoint | tuple
    stiffness_n_per_m: float
    damping_n_s_per_m: float = 0.0
    rest_length_m: float = 0.0
    name: str = ""

    def __post_init__(self) -> None:
        what = f"spring {self.name!r}"
        nonnegative(self.stiffness_n_per_m, f"{what}: stiffness [N/m]")
        nonnegative(self.damping_n_s_per_m, f"{what}: damping [N s/m]")
        nonnegative(self.rest_length_m, f"{what}: rest length [m]")
        if not isinstance(self.p2, (BodyPoint, NodeSetPoint)) and np.shape(self.p2) != (3,):
            raise InputError(f"{what}: a ground point must be 3 numbers [m], got {self.p2!r}")

    @property
    def _p2_on_body(self) -> bool:
        return isinstance(self.p2, (BodyPoint, NodeSetPoint))

    @property
    def external(self) -> bool:
        """A spring to the ground exchanges momentum with it."""
        return not self._p2_on_body

    @property
    def state_independent(self) -> bool:
        return False

    @property
    def acted_on(self) -> frozenset[int]:
        ends = (self.p1, self.p2)
        return frozenset(p.body for p in ends if isinstance(p, (BodyPoint, NodeSetPoint)))

    def reset(self) -> None:
        """Nothing kept between evaluations."""

    def _geometry(self, bodies, states) -> tuple[float, np.ndarray, Rows]:
        """(length l [m], unit e (3,), the row J of l)."""
        p2 = self.p2
        if isinstance(p2, (BodyPoint, NodeSetPoint)):
            x2 = p2.position(bodies, states)
        else:
            x2 = np.asarray(p2, float)
        d = self.p1.position(bodies, states) - x2
        length = float(np.linalg.norm(d))
        # at zero length (possible with l0 = 0 only) the force k (l - l0) e vanishes with d
        e = d / length if length > 0.0 else np.zeros(3)
        rows = Rows(1)
        self.p1.add_row(rows, 0, e, 1.0, bodies, states)
        if isinstance(p2, (BodyPoint, NodeSetPoint)):
            p2.add_row(rows, 0, e, -1.0, bodies, states)
        return length, e, rows

    def length_rate(self, bodies, states) -> tuple[float, float]:
        """(l [m], l_dot [m/s]) at the states (their velocities v)."""
        length, _, rows = self._geometry(bodies, states)
        return length, float(rows.times([st.v for st in states])[0])

    def forces(self, bodies, states, t: float) -> dict[int, np.ndarray]:
        """{body: -f J^T (6 + nq,)} at the states and their velocities (module doc)."""
        length, _, rows = self._geometry(bodies, states)
        rate = float(rows.times([st.v for st in states])[0])
        f = self.stiffness_n_per_m * (length - self.rest_length_m) + self.damping_n_s_per_m * rate
        return {b: -f * np.concatenate([bf[0], bq[0]]) for b, (bf, bq) in rows.blocks.items()}

    def energy(self, bodies, states) -> float:
        """Stored energy k (l - l0)^2 / 2 [J]."""
        length, _, _ = self._geometry(bodies, states)
        return 0.5 * self.stiffness_n_per_m * (length - self.rest_length_m) ** 2

    def dissipation_rate(self, bodies, states) -> float:
        """Power dissipated by the damper, c l_dot^2 [W]."""
        if not self.damping_n_s_per_m:
            return 0.0
        return self.damping_n_s_per_m * self.length_rate(bodies, states)[1] ** 2
