"""The scenario's ``[[joints]]`` table (pydantic v2): which keys each joint type needs and
allows; scenarios/schema.py checks the cross-references (bodies, strings' lengths) and
docs/scenario_format.md lists the keys."""

from __future__ import annotations

import math

from pydantic import model_serializer, model_validator

from flexmvm.constraints.joints import JointType
from flexmvm.scenarios.drive_schema import DriveConfig, PathConfig
from flexmvm.scenarios.fields import Frozen, Name, Positive, SetName, Vec3, Velocity
from flexmvm.scenarios.problems import problem

_JOINT_FIELDS = (
    "point_m",
    "node_set",
    "ground_m",
    "body2",
    "point2_m",
    "axis",
    "length_m",
    "velocity_mps",
    "drive",
    "path",
)
# joints whose body point may be a node set's centroid (constraints.joints.NodeSetPoint)
_NODE_SET_JOINTS = (JointType.SPHERICAL, JointType.REVOLUTE, JointType.FIXED, JointType.PRISMATIC)


class JointConfig(Frozen):
    """A joint; points are body-local (the nearest node is used), ``ground_m`` is global.
    ``node_set`` instead of ``point_m`` (spherical, revolute, fixed joints): the joint holds
    the centroid of that node set of ``body`` (a pin in a hole: the hole face's nodes); to the
    ground, ``ground_m`` may then be left out: the centroid is held where it is at t = 0.
    ``drive`` (revolute; prescribed with ``axis``) and ``path`` (prescribed, instead of
    ``velocity_mps``): scenarios/drive_schema.py; ``name`` names the joint in outputs and
    errors (its drive torque) and in a body's ``rigid_motion.about_joint``."""

    name: Name | None = None

    type: JointType
    body: Name
    point_m: Vec3 | None = None
    node_set: SetName | None = None
    ground_m: Vec3 | None = None
    body2: Name | None = None
    point2_m: Vec3 | None = None
    axis: Vec3 | None = None
    length_m: Positive | None = None
    velocity_mps: Velocity | None = None
    drive: DriveConfig | None = None
    path: PathConfig | None = None

    @model_serializer(mode="wrap")
    def _dump(self, handler):
        # name, drive and path unset dump as before the keys existed (study keys and cache
        # identities hash these dumps)
        data = handler(self)
        if isinstance(data, dict):
            for key in ("name", "drive", "path"):
                if key in data and data[key] is None:
                    data.pop(key)
        return data

    @model_validator(mode="after")
    def _check(self) -> JointConfig:
        t = self.type
        need: set[str] = set()
        allowed: set[str] = set()
        if t is JointType.PRESCRIBED:
            need, allowed = _prescribed_keys(self)
        elif t is JointType.PRISMATIC:  # to the ground; ground_m: a point of the guide line
            need, allowed = {"point_m", "axis"}, {"point_m", "axis", "ground_m"}
        elif t is not JointType.GROUND:
            other = {"body2", "point2_m"} if self.body2 is not None else {"ground_m"}
            need = {"point_m"} | other | ({"axis"} if t is JointType.REVOLUTE else set())
            allowed = need | ({"length_m"} if t is JointType.DISTANCE else set())
            allowed |= {"drive"} if t is JointType.REVOLUTE else set()
        if self.node_set is not None and t not in _NODE_SET_JOINTS:
            raise problem(
                f"not used by a {t.value!r} joint (a node set's centroid is held by "
                "fixed, spherical, revolute and prismatic joints; give point_m)",
                "node_set",
            )
        if self.node_set is not None:
            # ground_m, point2_m optional: the centroid held where it is at t = 0
            need = need - {"point_m", "ground_m", "point2_m"}
            allowed = (allowed - {"point_m"}) | {"node_set"}
        for key in _JOINT_FIELDS:
            given = getattr(self, key) is not None
            if key in need and not given:
                raise problem(
                    f"required by a {t.value!r} joint"
                    + (" to ground" if key == "ground_m" else ""),
                    key,
                )
            if given and key not in allowed:
                between = key == "ground_m" and self.body2 is not None
                raise problem(
                    f"not used by a {t.value!r} joint" + (" between two bodies" if between else ""),
                    key,
                )
        if self.axis is not None and math.hypot(*self.axis) == 0.0:
            raise problem(f"must be non-zero, got {list(self.axis)}", "axis")
        return self


def _prescribed_keys(j: JointConfig) -> tuple[set[str], set[str]]:
    """(needed, allowed) keys of a prescribed joint: a point on a constant velocity or on a
    path; with ``axis`` and ``drive`` its body's frame turned about the axis too."""
    if j.velocity_mps is not None and j.path is not None:
        raise problem("give one of velocity_mps (constant) and path (a table), not both", "path")
    need = {"point_m", "path" if j.path is not None else "velocity_mps"}
    if j.axis is not None or j.drive is not None:
        need |= {"axis", "drive"}
    return need, set(need)


__all__ = ["JointConfig"]
