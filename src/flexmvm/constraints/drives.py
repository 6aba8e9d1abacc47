"""Driven revolute joints: the relative rotation of body 1 about the joint axis follows a
prescribed angle history (time_functions): one more position-level row on top of the
revolute's five,

    phi = angle(t) - angle_p(t) = 0,

whose multiplier is the drive torque [N m] on body 1 about the axis (minus that on body 2):
an ordinary joint row, so the integrator, the recorded joint forces and any tally of the
joints' impulses see it as they see the others (a driving constraint: Haug 1989, Computer-Aided
Kinematics and Dynamics of Mechanical Systems; its multiplier the driving torque).

The angle. Reference directions perpendicular to the axis are fixed at the placement in both
frames (e_1 = A_1 u_1, e_2 = A_2 u_2; the ground's are global) and the axis a = A_2 a_2 turns
with body 2. The residual is taken against e_2 turned by angle_p(t) about a,
e_p = R(a, angle_p(t)) e_2:

    phi = atan2(s, c),   s = (e_p x e_1) . a,   c = e_p . e_1

the angle from e_p to e_1 about a, in (-pi, pi]. The constraint keeps phi near zero, so no
branch of atan2 is ever crossed however far the joint turns: the measured angle
angle_p(t) + phi is continuous (unwrapped) without any state kept between steps.

The row. With global angular velocities w_1, w_2 (e_1' = w_1 x e_1, e_p' = w_2 x e_p,
a' = w_2 x a at fixed t) and n = s^2 + c^2:

    d phi = g_1 . w_1 + g_2 . w_2 + (d phi / d t) dt
    g_1 = (c e_1 x (a x e_p) - s e_1 x e_p) / n
    g_2 = (c (e_p x (e_1 x a) + a x (e_p x e_1)) - s e_p x e_1) / n

(exact: with the axes aligned g_1 = a, g_2 = -a); the body-frame rows are A_i^T g_i, on the
frame's angular velocity only: the drive turns the floating frame, which the body's
reference condition ties to its material. d phi / d t at fixed configuration is
(c s_t - s c_t) / n with s_t = ((a x e_p) x e_1) . a angle_p', c_t = (a x e_p) . e_1 angle_p'
(-angle_p' with the axes aligned).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexmvm.bodies.rotation import cross3
from flexmvm.constraints.joints import Anchor, BodyPoint, Joint, NodeSetPoint, revolute_joint
from flexmvm.constraints.rows import Rows
from flexmvm.errors import InputError
from flexmvm.time_functions import TimeFunction

__all__ = ["DrivenAngle", "drive_torques", "driven_revolute_joint", "unit_axis"]

# |angle_p(0)| above this [rad] is a drive that does not start at its placement's angle
START_ANGLE_TOL_RAD = 1e-12


def unit_axis(axis, what: str = "axis") -> np.ndarray:
    """axis (3,) normalised; InputError when it is zero or not finite."""
    a = np.asarray(axis, float)
    n = float(np.linalg.norm(a))
    if not (n > 0 and math.isfinite(n)):
        raise InputError(f"{what}: expected a non-zero finite 3-vector, got {list(np.ravel(a))}")
    return a / n


def _no_elastic(body) -> tuple[np.ndarray, np.ndarray, int]:
    """Nodal selector entries of a row without elastic part (constraints.rows): none."""
    return np.zeros(0, np.int64), np.zeros(0), body.psi.shape[0] if body.nq else 0


def _perpendicular(a: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to the unit vector a."""
    b = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))])
    return b / np.linalg.norm(b)


def _turned(e: np.ndarray, a: np.ndarray, angle: float) -> np.ndarray:
    """e turned by angle [rad] about the unit axis a (Rodrigues)."""
    c, s = math.cos(angle), math.sin(angle)
    return e * c + cross3(a, e) * s + a * (a @ e) * (1.0 - c)


@dataclass(frozen=True, eq=False)
class DrivenAngle(Joint):
    """The drive row of a driven revolute joint (module docstring): body1's rotation about
    the axis relative to body2 (None: the ground) follows ``angle`` [rad] from its placement.
    axis2, ref2: the axis and the reference direction in body 2's frame (global for the
    ground); ref1: the reference direction in body 1's frame; name: the drive's name in the
    outputs (drive_torques). Made at the placement by :meth:`at_placement`."""

    name: str
    body1: int
    body2: int | None
    axis2: np.ndarray
    ref1: np.ndarray
    ref2: np.ndarray
    angle: TimeFunction
    n_rows: int = 1

    @classmethod
    def at_placement(
        cls, name: str, body1: int, body2: int | None, axis_global, states, angle: TimeFunction
    ) -> DrivenAngle:
        """The drive of body1 about axis_global (global, at the states' placement) relative
        to body2; InputError unless angle(0) = 0 (the joint starts at its placement)."""
        a = unit_axis(axis_global, f"drive {name!r} axis")
        start = float(angle.value(0.0))
        if not abs(start) <= START_ANGLE_TOL_RAD:
            raise InputError(
                f"drive {name!r}: the prescribed angle must be 0 rad at t = 0 (the joint's "
                f"placement), got {start!r} rad"
            )
        b = _perpendicular(a)
        A1 = states[body1].A
        A2 = states[body2].A if body2 is not None else np.eye(3)
        return cls(name, body1, body2, A2.T @ a, A1.T @ b, A2.T @ b, angle)

    def _directions(self, states, t: float):
        """(A1, A2, a, e_1, e_p) at time t."""
        A1 = states[self.body1].A
        A2 = states[self.body2].A if self.body2 is not None else np.eye(3)
        a = A2 @ self.axis2
        e_p = _turned(A2 @ self.ref2, a, float(self.angle.value(t)))
        return A1, A2, a, A1 @ self.ref1, e_p

    def value(self, bodies, states, t):
        _, _, a, e1, ep = self._directions(states, t)
        return np.array([math.atan2(float(cross3(ep, e1) @ a), float(ep @ e1))])

    def evaluate(self, bodies, states, t):
        A1, A2, a, e1, ep = self._directions(states, t)
        x = cross3(ep, e1)
        s, c = float(x @ a), float(ep @ e1)
        n = s * s + c * c
        g1 = (c * cross3(e1, cross3(a, ep)) + s * x) / n
        g2 = (c * (cross3(ep, cross3(e1, a)) + cross3(a, x)) - s * x) / n
        rows = Rows(1)
        for b, A, g in ((self.body1, A1, g1), (self.body2, A2, g2)):
            if b is not None:  # frame rows only; an empty selector keeps the nodal columns
                nq = bodies[b].nq
                fr = np.concatenate([np.zeros(3), A.T @ g])
                rows.add(0, b, fr, np.zeros(nq), nq, _no_elastic(bodies[b]))
        return np.array([math.atan2(s, c)]), rows

    def time_rate(self, bodies, states, t):
        _, _, a, e1, ep = self._directions(states, t)
        w = float(self.angle.rate(t))
        x, y = cross3(ep, e1), cross3(a, ep)
        s, c = float(x @ a), float(ep @ e1)
        s_t, c_t = float(cross3(y, e1) @ a) * w, float(y @ e1) * w
        return np.array([(c * s_t - s * c_t) / (s * s + c * c)])

    def relative_angle(self, states, t: float) -> float:
        """The joint's rotation from its placement [rad], unwrapped: angle_p(t) + phi."""
        _, _, a, e1, ep = self._directions(states, t)
        return float(self.angle.value(t)) + math.atan2(float(cross3(ep, e1) @ a), float(ep @ e1))


def driven_revolute_joint(
    p1: BodyPoint | NodeSetPoint, p2: Anchor, axis_global, states, angle: TimeFunction, name: str
) -> list[Joint]:
    """A revolute joint (constraints.joints.revolute_joint: 5 rows) whose rotation about
    axis_global follows ``angle`` [rad] (one more row, its multiplier the drive torque)."""
    joints = revolute_joint(p1, p2, axis_global, states)
    body2 = p2.body if isinstance(p2, (BodyPoint, NodeSetPoint)) else None
    return [*joints, DrivenAngle.at_placement(name, p1.body, body2, axis_global, states, angle)]


def drive_torques(joints, joint_force: np.ndarray) -> dict[str, np.ndarray]:
    """{drive name: its torque history [N m] on body 1 about the axis} from the recorded
    joint forces (n_out, n_joint_rows) of the system's joints (in order): each DrivenAngle's
    column (its multiplier, an impulse averaged over the output interval)."""
    out: dict[str, np.ndarray] = {}
    col = 0
    force = np.asarray(joint_force, float)
    for joint in joints:
        if isinstance(joint, DrivenAngle):
            out[joint.name] = force[:, col].copy()
        col += joint.n_rows
    return out
