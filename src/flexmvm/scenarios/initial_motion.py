"""A body's initial rigid motion given about a point, and the check that the initial
velocities satisfy the joints.

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

Impact speed against the wave speed (check_impact_speeds): a bar struck at speed v0 carries
the strain v0 / c (c = sqrt(E / rho), the bar wave speed; 1D wave theory, sigma = rho c v),
so v0 / c is the strain scale of an impact. The model is small-strain linear elasticity (and
J2 plasticity on small strains): above MAX_IMPACT_FRACTION = 0.1 of c the impact strains
the body by 10 % or more, two orders beyond the yield strain of any metal (~1e-3) and where
small-strain kinematics no longer hold; such a start is refused in one line naming the body,
the key and c (1e6 m/s onto aluminium gave NaN at the first step). The seed's 0.21 m/s is
4e-5 of aluminium's c.
"""

from __future__ import annotations

import numpy as np
from pydantic import model_validator

from flexmvm.bodies.build import ModelKind
from flexmvm.errors import InputError
from flexmvm.integrate.state import BodyState
from flexmvm.scenarios.fields import ZERO3, AngularVelocity, Frozen, Name, Vec3, Velocity
from flexmvm.scenarios.problems import problem

__all__ = [
    "MAX_IMPACT_FRACTION",
    "VELOCITY_TOL",
    "RigidMotionConfig",
    "check_impact_speeds",
    "check_joint_velocities",
    "with_rigid_motion",
]

VELOCITY_TOL = 1e-2  # a joint row's |Phi_v v + phi_t| over the bodies' speed (docstring)
MAX_IMPACT_FRACTION = 0.1  # the largest impact speed over the bar wave speed (docstring)


class RigidMotionConfig(Frozen):
    """A body's initial rigid motion about a point: ``angular_velocity_radps`` (global axes),
    ``velocity_mps`` of the point (global), the point ``about_m`` (global [m]) or the pivot of
    the joint named ``about_joint``; neither: the body's frame origin."""

    angular_velocity_radps: AngularVelocity = ZERO3
    velocity_mps: Velocity = ZERO3
    about_m: Vec3 | None = None
    about_joint: Name | None = None

    @model_validator(mode="after")
    def _one_point(self) -> RigidMotionConfig:
        if self.about_m is not None and self.about_joint is not None:
            raise problem("give one of about_m and about_joint, not both", "about_joint")
        return self


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
    point = getattr(first, "p1", None)
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


def check_motion_names(joints, bodies) -> None:
    """Scenario cross-references of the motions: joint names unique, every
    ``rigid_motion.about_joint`` a named joint (problems for the scenario validator)."""
    names = [j.name for j in joints]
    for i, name in enumerate(names):
        if name is not None and name in names[:i]:
            raise problem(
                f"duplicate joint name {name!r} (also joints[{names.index(name)}])",
                f"joints[{i}].name",
            )
    known = [n for n in names if n is not None]
    for i, b in enumerate(bodies):
        motion = b.placement.rigid_motion
        about = motion.about_joint if motion is not None else None
        if about is not None and about not in known:
            raise problem(
                f"unknown joint {about!r} (named joints: {', '.join(known) or 'none'})",
                f"bodies[{i}].placement.rigid_motion.about_joint",
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


def _initial_velocity(body) -> tuple[str, np.ndarray]:
    """The key (below ``placement``) and value (3,) [m/s] of a body's initial velocity: its
    frame's, or the velocity of the point of its rigid_motion."""
    motion = body.placement.rigid_motion
    if motion is not None:
        return "rigid_motion.velocity_mps", np.asarray(motion.velocity_mps, float)
    return "velocity_mps", np.asarray(body.placement.velocity_mps, float)


def check_impact_speeds(contacts, bodies) -> None:
    """A problem naming the faster body's velocity key when two bodies in contact approach at
    more than MAX_IMPACT_FRACTION of the bar wave speed c = sqrt(E / rho) of either elastic
    one (module docstring: v0 / c is the impact's strain scale). Rigid bodies have no c.
    The speed is that of the initial velocities given (frame or rigid_motion point);
    a spin's share needs the mesh and is not counted here."""
    index = {b.name: i for i, b in enumerate(bodies)}
    for c in contacts:
        pair = [index[c.slave_body], index[c.master_body]]
        (key_a, v_a), (key_b, v_b) = (_initial_velocity(bodies[i]) for i in pair)
        speed = float(np.linalg.norm(v_a - v_b))
        elastic = [i for i in pair if bodies[i].model.kind is not ModelKind.RIGID]
        if not elastic or speed == 0.0:
            continue
        soft = min(elastic, key=lambda i: bodies[i].material_obj().bar_wave_speed)
        wave = bodies[soft].material_obj().bar_wave_speed
        if speed <= MAX_IMPACT_FRACTION * wave:
            continue
        fast, key, v = (
            (pair[0], key_a, v_a)
            if np.linalg.norm(v_a) >= np.linalg.norm(v_b)
            else (pair[1], key_b, v_b)
        )
        other = pair[1] if fast == pair[0] else pair[0]
        soft_body = bodies[soft]
        raise problem(
            f"[{', '.join(f'{x:g}' for x in v)}] m/s: body {bodies[fast].name!r} meets body "
            f"{bodies[other].name!r} at {speed:g} m/s, {speed / wave:.3g} of the bar wave "
            f"speed c = sqrt(E/rho) = {wave:.4g} m/s of body {soft_body.name!r} "
            f"({soft_body.material_obj().name}); expected at most {MAX_IMPACT_FRACTION:g} c = "
            f"{MAX_IMPACT_FRACTION * wave:.4g} m/s (v0/c is the impact's strain scale; the "
            "model is small-strain elasticity)",
            f"bodies[{fast}].placement.{key}",
        )
