"""The constraint objects of a scenario joint with a ``drive`` or a ``path``
(scenarios/drive_schema.py): a driven revolute joint (constraints.drives), a point on a path
or a frame on a path turning about an axis (constraints.prescribed)."""

from __future__ import annotations

import numpy as np

from flexmvm.constraints.drives import driven_revolute_joint
from flexmvm.constraints.joints import Joint, PrescribedMotion, revolute_joint
from flexmvm.constraints.prescribed import PrescribedPath, prescribed_frame
from flexmvm.time_functions import Constant, Integral

__all__ = ["joint_label", "joint_name", "prescribed_joints", "revolute_joints"]


def joint_name(j, k: int) -> str:
    """The name of joints[k] in outputs: its ``name``, or joint<k>."""
    return j.name if j.name is not None else f"joint{k}"


def joint_label(j, k: int) -> str:
    """joints[k], with its name when it has one (for errors)."""
    return f"joints[{k}]" + (f" ({j.name})" if j.name is not None else "")


def revolute_joints(j, name: str, p1, p2, states) -> list[Joint]:
    """A revolute joint's objects: driven (its ``drive``) or not."""
    if j.drive is None:
        return revolute_joint(p1, p2, j.axis, states)
    return driven_revolute_joint(p1, p2, j.axis, states, j.drive.angle(), name)


def prescribed_joints(j, name: str, p1, bodies, states) -> list[Joint]:
    """A prescribed joint's objects: its point at constant velocity (``velocity_mps``) or on
    a ``path``; with a ``drive`` its body's frame turned about ``axis`` too."""
    x0 = np.asarray(p1.position(bodies, states), float)
    if j.path is None and j.drive is None:
        return [PrescribedMotion(p1, tuple(x0), tuple(j.velocity_mps))]
    d = j.path.displacement() if j.path is not None else Integral(Constant(j.velocity_mps))
    if j.drive is None:
        return [PrescribedPath(p1, x0, d)]
    return prescribed_frame(p1, d, j.axis, j.drive.angle(), states, bodies, name)
