"""Torques on a revolute joint's relative rotation: rotational spring-dampers and motor
torques (a torque history), equal and opposite on the joint's two bodies (on the ground side
nothing).

The relative angle phi of body 1 against body 2 (or the ground) about the joint axis a comes
from the frames' rotation matrices: a reference direction b perpendicular to a at t = 0 is
stored in both frames (p1 = A1^T b, p2 = A2^T b), and

    phi = atan2(a . (e2 x e1), e2 . e1),   e1 = A1 p1, e2 = A2 p2, a = A1 u1

(zero at t = 0; u1 = A1^T a the axis in body 1's frame, which the joint keeps along body 2's).
atan2 gives phi in (-pi, pi]: it is unwrapped continuously against the last value evaluated
(any two evaluations are a fraction of a step apart, far below pi). Its rate is
phi_dot = a . (A1 omega1 - A2 omega2) (omega in the body frames), and a torque tau [N m] about a
has the generalized forces tau u1 on body 1's omega rows and -tau A2^T a on body 2's
(power tau phi_dot).

Rotational spring-damper: tau = -k (phi - phi0) - c phi_dot, energy k (phi - phi0)^2 / 2,
dissipation c phi_dot^2. Newton: as for loads.spring, these enter the residual only, which
converges for k << J_eff / (theta h)^2 (J_eff the smaller moment of inertia about the axis).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from flexmvm.bodies.rotation import cross3
from flexmvm.errors import InputError
from flexmvm.loads.history import TimeHistory
from flexmvm.loads.spring import nonnegative


@dataclass(frozen=True, eq=False)
class RevoluteAxis:
    """The relative rotation of a revolute joint between body1 and body2 (None: the ground)
    about an axis: u1 (body 1 frame), p1, p2 (reference directions in body 1's and body 2's
    frame, the latter global for the ground). Made by :meth:`of`; ``last`` holds the last angle
    evaluated (the unwrapping, module doc)."""

    body1: int
    body2: int | None
    u1: np.ndarray
    p1: np.ndarray
    p2: np.ndarray
    last: list = field(default_factory=lambda: [0.0])

    @classmethod
    def of(cls, body1: int, body2: int | None, axis_global, states) -> RevoluteAxis:
        """The joint's axis from its global direction at the states (t = 0)."""
        a = np.asarray(axis_global, float)
        if a.shape != (3,) or not np.linalg.norm(a) > 0:
            raise InputError(f"revolute axis must be a non-zero 3-vector, got {axis_global!r}")
        a = a / np.linalg.norm(a)
        t = np.eye(3)[int(np.argmin(np.abs(a)))]
        b = np.cross(a, t)
        b /= np.linalg.norm(b)
        A1 = states[body1].A
        A2 = states[body2].A if body2 is not None else np.eye(3)
        return cls(body1, body2, A1.T @ a, A1.T @ b, A2.T @ b)

    @property
    def bodies(self) -> frozenset[int]:
        """The bodies the axis joins (body 2 None: the ground, not a body)."""
        return frozenset(b for b in (self.body1, self.body2) if b is not None)

    def reset(self) -> None:
        """Start a run: the angle is unwrapped from (-pi, pi] again (loads.applied.start_run)."""
        self.last[0] = 0.0

    def _frames(self, states) -> tuple[np.ndarray, np.ndarray]:
        A1 = states[self.body1].A
        A2 = states[self.body2].A if self.body2 is not None else np.eye(3)
        return A1, A2

    def angle(self, states) -> float:
        """phi [rad], unwrapped (module doc)."""
        A1, A2 = self._frames(states)
        a, e1, e2 = A1 @ self.u1, A1 @ self.p1, A2 @ self.p2
        raw = math.atan2(float(a @ cross3(e2, e1)), float(e2 @ e1))
        last = self.last[0]
        phi = raw + 2.0 * math.pi * round((last - raw) / (2.0 * math.pi))
        self.last[0] = phi
        return phi

    def rate(self, states) -> float:
        """phi_dot [rad/s] at the states' velocities."""
        A1, A2 = self._frames(states)
        w = A1 @ states[self.body1].v[3:6]
        if self.body2 is not None:
            w = w - A2 @ states[self.body2].v[3:6]
        return float((A1 @ self.u1) @ w)

    def torque_forces(self, tau: float, bodies, states) -> dict[int, np.ndarray]:
        """{body: generalized force} of a torque tau [N m] about the axis on body 1, -tau on
        body 2."""
        A1, A2 = self._frames(states)
        out = {self.body1: np.zeros(bodies[self.body1].nv)}
        out[self.body1][3:6] = tau * self.u1
        if self.body2 is not None:
            out[self.body2] = np.zeros(bodies[self.body2].nv)
            out[self.body2][3:6] = -tau * (A2.T @ (A1 @ self.u1))
        return out


@dataclass(frozen=True)
class RotationalSpring:
    """A rotational spring-damper on a revolute joint's relative angle: stiffness_nm_per_rad k,
    damping_nms_per_rad c, rest_angle_rad phi0 (relative to the angle at t = 0)."""

    axis: RevoluteAxis
    stiffness_nm_per_rad: float
    damping_nms_per_rad: float = 0.0
    rest_angle_rad: float = 0.0
    name: str = ""

    def __post_init__(self) -> None:
        what = f"rotational spring {self.name!r}"
        nonnegative(self.stiffness_nm_per_rad, f"{what}: stiffness [N m/rad]")
        nonnegative(self.damping_nms_per_rad, f"{what}: damping [N m s/rad]")
        if not math.isfinite(self.rest_angle_rad):
            raise InputError(f"{what}: rest angle must be finite, got {self.rest_angle_rad!r}")

    external = False
    state_independent = False

    @property
    def acted_on(self) -> frozenset[int]:
        return self.axis.bodies

    def reset(self) -> None:
        self.axis.reset()

    def torque(self, states) -> float:
        phi, rate = self.axis.angle(states), self.axis.rate(states)
        k, c = self.stiffness_nm_per_rad, self.damping_nms_per_rad
        return -k * (phi - self.rest_angle_rad) - c * rate

    def forces(self, bodies, states, t: float) -> dict[int, np.ndarray]:
        return self.axis.torque_forces(self.torque(states), bodies, states)

    def energy(self, bodies, states) -> float:
        """k (phi - phi0)^2 / 2 [J]."""
        return (
            0.5 * self.stiffness_nm_per_rad * (self.axis.angle(states) - self.rest_angle_rad) ** 2
        )

    def dissipation_rate(self, bodies, states) -> float:
        """c phi_dot^2 [W]."""
        return self.damping_nms_per_rad * self.axis.rate(states) ** 2


@dataclass(frozen=True)
class MotorTorque:
    """A motor torque history torque_nm(t) [N m] (1 component) about a revolute joint's axis,
    on body 1 and its reaction on body 2 (module doc)."""

    axis: RevoluteAxis
    torque_nm: TimeHistory
    name: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.torque_nm, TimeHistory) or self.torque_nm.width != 1:
            raise InputError(f"motor torque {self.name!r}: expected a 1-component TimeHistory")

    external = False
    state_independent = False

    @property
    def acted_on(self) -> frozenset[int]:
        return self.axis.bodies

    def reset(self) -> None:
        self.axis.reset()

    def forces(self, bodies, states, t: float) -> dict[int, np.ndarray]:
        return self.axis.torque_forces(float(self.torque_nm.at(t)[0]), bodies, states)
