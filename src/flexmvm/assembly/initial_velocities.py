"""The initial velocities of a built scenario: every body's ``placement.rigid_motion``
(scenarios/initial_motion.py) applied to its state, and the check that the velocities
satisfy the joints.

Rigid motion about a point P (a body's ``placement.rigid_motion``): angular velocity w
(global axes [rad/s]) and the velocity v_P of P (global [m/s], default 0); the frame's
velocities follow from the rigid-body velocity field (Euler's formula for the velocity of a
point of a rigid body; Shabana, Dynamics of Multibody Systems, ch. 2):

    v_O = v_P + w x (r_O - r_P),   omega (body frame) = A^T w

P is a global point (``about_m``) or a joint's pivot (``about_joint``: the position at t = 0 of
the joint's point on its first body).

The joints at velocity level: a motion that keeps phi = 0 has d phi / d t = Phi_v v +
phi_t = 0 (phi_t the explicit time derivative of a prescribed motion or drive). A start that
violates it is closed by the first step's joint impulse, the M-orthogonal projection of the
velocities onto the joints' (Pythagoras in the mass metric): it removes the kinetic energy
of the violating part, a fraction eps^2 of the motion's for a violation eps relative to the
bodies' speed. Each row's violation |Phi_v v + phi_t| is measured against that speed: for a
row on positions (m/s) the bodies' |r_dot| + |omega| R (R the largest distance of a node from
the frame origin) plus |phi_t|, for a row on angles (rad/s) their |omega| plus |phi_t|.
Above VELOCITY_TOL = 1e-2 the start is an InputError naming the joint: at 1e-2 the first step
changes the energy by at most 1e-4 of the motion's, a tenth of the 0.1 % energy balance the
showcases close, while a motion given about the wrong point (the frame origin instead of
the pivot) is off by order one. Below it sit meshes whose pivot is not quite on the axis (a
coarse tet4 hole face's centroid 0.3 mm off it: 1e-3 of the arm's tip speed).
"""

from __future__ import annotations

import numpy as np

from flexmvm.errors import InputError
from flexmvm.integrate.state import BodyState
from flexmvm.scenarios.initial_motion import RigidMotionConfig

__all__ = ["VELOCITY_TOL", "check_joint_velocities", "with_rigid_motion", "with_rigid_motions"]

VELOCITY_TOL = 1e-2  # a joint row's |Phi_v v + phi_t| over the bodies' speed (docstring)


def with_rigid_motion(state: BodyState, motion: RigidMotionConfig, pivot) -> BodyState:
    """``state`` with the frame velocities of ``motion`` about ``pivot`` (global (3,) [m];
    None: about the frame origin): v_O = v_P + w x (r_O - r_P), omega = A^T w."""
    w = np.asarray(motion.angular_velocity_radps, float)
    p = state.r if pivot is None else np.asarray(pivot, float)
    out = state.copy()
    out.v[:3] = np.asarray(motion.velocity_mps, float) + np.cross(w, state.r - p)
    out.v[3:6] = state.A.T @ w
    return out


def joint_pivot(group, bodies, states) -> np.ndarray:
    """The pivot of a scenario joint (its list of constraint objects): the position of its
    point on its first body (the first object's p1)."""
    first = group[0]
    point = first.pivot
    if point is None:
        raise InputError(f"a {type(first).__name__} has no pivot point to turn about")
    return np.asarray(point.position(bodies, states), float)


def _speed_scale(rows, bodies, states) -> np.ndarray:
    """Per row the speed its violation is measured against (module docstring), (m,)."""
    on_points = np.zeros(rows.m, bool)
    for bf, _ in rows.blocks.values():
        on_points |= np.abs(bf[:, :3]).max(axis=1) > 0
    out = np.zeros(rows.m)
    for b, (_, bq) in rows.blocks.items():
        v = states[b].v
        w = float(np.linalg.norm(v[3:6]))
        radius = float(np.linalg.norm(bodies[b].X, axis=1).max())
        point = float(np.linalg.norm(v[:3])) + w * radius
        out += np.where(on_points, point, w)
        if bq.shape[1]:
            out += np.abs(bq) @ np.abs(v[6:])
    return out


def check_joint_velocities(bodies, states, groups, labels, t0: float = 0.0) -> None:
    """InputError naming the first joint (labels[i] for the constraint objects groups[i])
    whose rows the initial velocities violate beyond VELOCITY_TOL (module docstring)."""
    v = [st.v for st in states]
    for label, group in zip(labels, groups, strict=True):
        for joint in group:
            _, rows = joint.evaluate(bodies, states, t0)
            rate_t = np.asarray(joint.time_rate(bodies, states, t0), float)
            rate = np.abs(rows.times(v) + rate_t)
            scale = _speed_scale(rows, bodies, states) + np.abs(rate_t)
            bad = rate > VELOCITY_TOL * scale
            if bad.any():
                i = int(np.argmax(np.where(bad, rate / np.maximum(scale, 1e-300), 0.0)))
                raise InputError(
                    f"{label}: the initial velocities violate the joint: |d phi / d t| = "
                    f"{rate[i]:.3g} on one of its rows, {rate[i] / scale[i]:.2g} of the bodies' "
                    f"speed (tolerance {VELOCITY_TOL:g}); give the body's initial motion about "
                    "the joint's pivot (placement.rigid_motion), or start a drive at its speed"
                )


def with_rigid_motions(sc, bodies, states, groups) -> list[BodyState]:
    """The initial states with every body's ``placement.rigid_motion`` applied (the others as
    they are); groups: the constraint objects of each of sc.joints, for ``about_joint``."""
    by_name = {j.name: g for j, g in zip(sc.joints, groups, strict=True) if j.name is not None}
    out = list(states)
    for k, cfg in enumerate(sc.bodies):
        motion = cfg.placement.rigid_motion
        if motion is None:
            continue
        pivot = motion.about_m
        if motion.about_joint is not None:
            pivot = joint_pivot(by_name[motion.about_joint], bodies, states)
        out[k] = with_rigid_motion(states[k], motion, pivot)
    return out
