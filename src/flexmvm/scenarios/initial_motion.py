"""A body's initial rigid motion given about a point (the table; the velocities it gives and
the check that they satisfy the joints: assembly/initial_velocities.py), and the check of the
impact speeds against the wave speed.

Rigid motion about a point P (a body's ``placement.rigid_motion``): angular velocity w
(global axes [rad/s]) and the velocity v_P of P (global [m/s], default 0); the frame's
velocities follow from the rigid-body velocity field (Euler's formula for the velocity of a
point of a rigid body; Shabana, Dynamics of Multibody Systems, ch. 2):

    v_O = v_P + w x (r_O - r_P),   omega (body frame) = A^T w

P is a global point (``about_m``) or a joint's pivot (``about_joint``: the position at t = 0 of
the joint's point on its first body).

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
from flexmvm.scenarios.fields import ZERO3, AngularVelocity, Frozen, Name, Vec3, Velocity
from flexmvm.scenarios.problems import problem

__all__ = [
    "MAX_IMPACT_FRACTION",
    "RigidMotionConfig",
    "check_impact_speeds",
    "check_motion_names",
]

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
