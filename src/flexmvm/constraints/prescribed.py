"""Prescribed motion by time histories: a body point on a path, and a body frame on a path
turning about a fixed axis (the generalization of constraints.joints.PrescribedMotion, a
point at constant velocity, which stays as it is).

A point on a path (3 rows): x(t) - (x_0 + d(t)) = 0, d a displacement history (d(0) = 0,
time_functions: a table of displacements, or the integral of a table of velocities),
Phi_v the point's rows, d phi / d t = -d'(t). A frame (6 rows): its point on a path, the
two orientation rows of a revolute joint to the ground about the axis (the axis held) and
the drive row of constraints.drives (the turn about the axis prescribed): the frame's
pose x_0 + d(t), R(axis, angle(t)) A_0 at every t.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.constraints.drives import DrivenAngle
from flexmvm.constraints.joints import BodyPoint, Joint, NodeSetPoint, revolute_joint
from flexmvm.constraints.rows import Rows
from flexmvm.errors import InputError
from flexmvm.time_functions import TimeFunction

__all__ = ["PrescribedPath", "prescribed_frame"]

# |d(0)| above this [m] is a path that does not start at the point's placement
START_TOL_M = 1e-12


@dataclass(frozen=True, eq=False)
class PrescribedPath(Joint):
    """Point p1 on the path x_0 + d(t) (global [m]; d: a TimeFunction of (3,) values with
    d(0) = 0): 3 rows."""

    p1: BodyPoint | NodeSetPoint
    x0: np.ndarray
    displacement: TimeFunction
    n_rows: int = 3

    @property
    def pivot(self) -> BodyPoint | NodeSetPoint:
        return self.p1

    def __post_init__(self) -> None:
        d0 = np.asarray(self.displacement.value(0.0), float)
        if d0.shape != (3,):
            raise InputError(f"a path's displacement must be a 3-vector, got shape {d0.shape}")
        if not float(np.abs(d0).max()) <= START_TOL_M:
            raise InputError(
                f"a path must start at the point's placement: displacement at t = 0 must be "
                f"[0, 0, 0] m, got {d0.tolist()}"
            )

    def value(self, bodies, states, t):
        target = self.x0 + np.asarray(self.displacement.value(t), float)
        return self.p1.position(bodies, states) - target

    def evaluate(self, bodies, states, t):
        phi = self.value(bodies, states, t)
        rows = Rows(3)
        self.p1.add_rows(rows, 0, np.eye(3), 1.0, bodies, states)
        return phi, rows

    def time_rate(self, bodies, states, t):
        return -np.asarray(self.displacement.rate(t), float)


def prescribed_frame(
    p1: BodyPoint | NodeSetPoint,
    displacement: TimeFunction,
    axis_global,
    angle: TimeFunction,
    states,
    bodies,
    name: str,
) -> list[Joint]:
    """The pose of p1's body prescribed: p1 on x_0 + d(t) (x_0 its position at the states),
    the body turned by angle(t) [rad] about the fixed global axis from its placement
    (6 rows; the last one's multiplier is the torque about the axis, named ``name``)."""
    x0 = np.asarray(p1.position(bodies, states), float)
    lock = revolute_joint(p1, x0, axis_global, states)[1]  # the revolute's 2 orientation rows
    return [
        PrescribedPath(p1, x0, displacement),
        lock,
        DrivenAngle.at_placement(name, p1.body, None, axis_global, states, angle),
    ]
