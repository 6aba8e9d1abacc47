"""Point forces and body torques: given over time (loads.history), fixed in space (a global
direction) or following the body (a direction fixed in the body's frame).

A point is a node, a node with a body-frame offset or a node set's centroid
(constraints.joints.BodyPoint, NodeSetPoint), as the joints' points are. The generalized force
of a force f [N] at point x(v) is J^T f with J = dx/dv the point's velocity Jacobian
(Shabana, *Dynamics of Multibody Systems*, 3rd ed., eq. 5.138: Q = (dx/dq)^T f), the same row
a joint builds (BodyPoint.add_row with direction f). A torque tau [N m] on a body acts on its
frame's rotation: power tau . (A omega), so its generalized force is A^T tau on the omega rows
(omega in the body frame, integrate.state). On a flexible body that is a torque on the floating
frame, carried into the elastic coordinates only through the inertia coupling; a torque on a
region of the body is a set of point forces.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexmvm.constraints.joints import BodyPoint, NodeSetPoint
from flexmvm.constraints.rows import Rows
from flexmvm.errors import InputError
from flexmvm.loads.history import TimeHistory


def _check_width(history: TimeHistory, width: int, what: str) -> None:
    if not isinstance(history, TimeHistory):
        raise InputError(f"{what}: expected a TimeHistory, got {type(history).__name__}")
    if history.width != width:
        raise InputError(f"{what}: expected {width} component(s), got {history.width}")


def point_generalized_force(point, direction, bodies, states) -> np.ndarray:
    """J^T d (6 + nq,) on point's body for a global vector d at the point (module doc)."""
    rows = Rows(1)
    point.add_row(rows, 0, direction, 1.0, bodies, states)
    frame, elastic = rows.blocks[point.body]
    return np.concatenate([frame[0], elastic[0]])


@dataclass(frozen=True)
class PointForce:
    """A force [N] (3,) at ``point`` of its body: ``force_n(t)`` global, or body-frame when
    ``follower`` (turned with the frame A, not with the material's local elastic rotation)."""

    point: BodyPoint | NodeSetPoint
    force_n: TimeHistory
    follower: bool = False
    name: str = ""

    def __post_init__(self) -> None:
        _check_width(self.force_n, 3, f"point force {self.name!r}")

    @classmethod
    def on_node(
        cls, body: int, node: int, force_n, t_start_s: float = 0.0, name: str = ""
    ) -> PointForce:
        """A constant global force [N] on node ``node`` of body ``body`` from t_start_s on."""
        history = TimeHistory.constant(force_n, t_start_s, f"point force {name!r}")
        return cls(BodyPoint(body, node=node), history, name=name)

    @property
    def external(self) -> bool:
        """The force comes from outside the system: linear momentum is not conserved."""
        return True

    @property
    def state_independent(self) -> bool:
        """Fixed in space: the force does not turn with the body (the linear step of
        integrate.moreau_jean.nonrotating may take it)."""
        return not self.follower

    @property
    def acted_on(self) -> frozenset[int]:
        return frozenset({self.point.body})

    def reset(self) -> None:
        """Nothing kept between evaluations."""

    def forces(self, bodies, states, t: float) -> dict[int, np.ndarray]:
        """{body: generalized force (6 + nq,)} at the states (with their velocities) and t."""
        f = self.force_n.at(t)
        if not f.any():
            return {}
        if self.follower:
            f = states[self.point.body].A @ f
        return {self.point.body: point_generalized_force(self.point, f, bodies, states)}


@dataclass(frozen=True)
class BodyTorque:
    """A torque [N m] (3,) on the frame of body ``body``: ``torque_nm(t)`` global, or
    body-frame when ``follower`` (module doc)."""

    body: int
    torque_nm: TimeHistory
    follower: bool = False
    name: str = ""

    def __post_init__(self) -> None:
        _check_width(self.torque_nm, 3, f"body torque {self.name!r}")

    @property
    def external(self) -> bool:
        """A pure torque: no resultant force, linear momentum is conserved."""
        return False

    @property
    def state_independent(self) -> bool:
        return not self.follower

    @property
    def acted_on(self) -> frozenset[int]:
        return frozenset({self.body})

    def reset(self) -> None:
        """Nothing kept between evaluations."""

    def forces(self, bodies, states, t: float) -> dict[int, np.ndarray]:
        """{body: generalized force (6 + nq,)}: A^T tau (or tau) on the omega rows."""
        tau = self.torque_nm.at(t)
        if not tau.any():
            return {}
        out = np.zeros(bodies[self.body].nv)
        out[3:6] = tau if self.follower else states[self.body].A.T @ tau
        return {self.body: out}


def constant_or_table(value, times_s, values, width: int, what: str) -> TimeHistory:
    """A TimeHistory from a scenario's ``value`` (constant) or ``times_s`` + ``values``."""
    if value is not None:
        return TimeHistory.constant(value, -math.inf, what)
    return TimeHistory.table(times_s, values, width, what)
