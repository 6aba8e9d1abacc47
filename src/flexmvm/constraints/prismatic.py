"""Prismatic (translational) joint to the ground: a body point slides along a fixed global line
and the body does not turn (5 constraints; seed eq. 9-11, superscript J).

    phi_1 = (x_p - x_0) . b = 0,   phi_2 = (x_p - x_0) . c = 0      (on the line x_0 + s a)
    phi_3..5 = (A u_i) . w_i = 0                                  (no rotation, 3 pairs)

with a the guide's unit direction, b and c two unit vectors normal to it and to each other
(fixed in space), x_p the body point (a node, a frame point or a node set's centroid:
constraints.joints) and (u_i, w_i) the frame directions of constraints.joints.fixed_joint's
orientation lock at t = 0. The rows of phi_1,2 are b^T dx_p/dv and c^T dx_p/dv (the point's
own rows); the lock's rows are OrientationLock's (Haug, "Computer Aided Kinematics and Dynamics
of Mechanical Systems", 1989, sec. 9.3: the translational joint as two perpendicularity
conditions of the relative position plus the orientation conditions).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.constraints.joints import BodyPoint, Joint, NodeSetPoint, OrientationLock
from flexmvm.constraints.rows import Rows
from flexmvm.errors import InputError


@dataclass(frozen=True)
class LineLock(Joint):
    """A body point kept on the fixed global line through ``origin`` (3,) [m] normal to
    ``normals`` (two orthonormal (3,) vectors): (x_p - origin) . n_i = 0 (2 rows)."""

    p1: BodyPoint | NodeSetPoint
    origin: tuple[float, float, float]
    normals: tuple[tuple[float, float, float], tuple[float, float, float]]
    n_rows: int = 2

    @property
    def pivot(self) -> BodyPoint | NodeSetPoint:
        return self.p1

    def value(self, bodies, states, t):
        d = self.p1.position(bodies, states) - np.asarray(self.origin, float)
        return np.array([float(d @ np.asarray(n, float)) for n in self.normals])

    def evaluate(self, bodies, states, t):
        d = self.p1.position(bodies, states) - np.asarray(self.origin, float)
        rows = Rows(2)
        phi = np.zeros(2)
        for i, n in enumerate(self.normals):
            phi[i] = float(d @ np.asarray(n, float))
        self.p1.add_rows(rows, 0, self.normals, 1.0, bodies, states)
        return phi, rows


def _normals(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors normal to the unit vector a and to each other."""
    b = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))])
    b /= np.linalg.norm(b)
    return b, np.cross(a, b)


def prismatic_joint(
    p1: BodyPoint | NodeSetPoint, origin_m, axis_global, bodies, states
) -> list[Joint]:
    """The body of ``p1`` sliding along the global direction ``axis_global`` (3,) through
    ``origin_m`` (3,) [m] (None: the point's position at t = 0), without turning: a LineLock
    (2 rows) and the orientation lock of a weld to the ground (3 rows). InputError if the axis
    is zero or the given origin is off the line's start by more than 1e-9 m normal to it."""
    axis = np.asarray(axis_global, float)
    norm = float(np.linalg.norm(axis))
    if not norm > 0:
        raise InputError(f"prismatic joint axis must be non-zero, got {list(axis)}")
    b, c = _normals(axis / norm)
    x0 = p1.position(bodies, states)
    origin = x0 if origin_m is None else np.asarray(origin_m, float)
    off = float(np.hypot((x0 - origin) @ b, (x0 - origin) @ c))
    if off > 1e-9:
        raise InputError(
            f"prismatic joint: the point starts {off:.3g} m off its guide line through "
            f"ground_m {list(origin)} along {list(axis)}; expected it on the line"
        )
    A = states[p1.body].A
    e = np.eye(3)
    pairs = tuple((tuple(A.T @ e[i]), tuple(e[j])) for i, j in ((0, 1), (1, 2), (2, 0)))
    return [
        LineLock(p1, (float(origin[0]), float(origin[1]), float(origin[2])), (tuple(b), tuple(c))),
        OrientationLock(p1.body, None, pairs),
    ]


__all__ = ["LineLock", "prismatic_joint"]
