"""Build a scenario's [[loads]] and [[springs]] (load_schema.py) into flexmvm.loads objects,
once its bodies, their initial states and mesh lookups exist (assembly/build.py)."""

from __future__ import annotations

import math

import numpy as np

from flexmvm.assembly.mesh_lookup import body_point
from flexmvm.constraints.joints import BodyPoint, NodeSetPoint
from flexmvm.errors import InputError, MeshError
from flexmvm.loads import (
    BodyTorque,
    MotorTorque,
    PointForce,
    PointSpring,
    RevoluteAxis,
    RotationalSpring,
)
from flexmvm.scenarios.load_schema import LoadFrame, LoadType, SpringType


def _point(b, bodies, infos, point_m, node_set, where):
    """A point of body b: body_point at point_m, or the centroid of node set node_set."""
    if node_set is None:
        return body_point(b, bodies[b], infos[b].mesh, point_m, f"{where}.point_m")
    try:
        ids = infos[b].mesh.node_set(node_set)
    except MeshError as exc:
        raise InputError(f"{where}.node_set: {exc}") from None
    return NodeSetPoint.of(b, bodies[b], ids)


def _axis(sc, k: int, index, states) -> RevoluteAxis:
    """The relative rotation of revolute joints[k] (its body against body2 or the ground)
    about the joint's axis, taken as the joint takes it (build._joint: revolute_joint)."""
    j = sc.joints[k]
    body2 = index[j.body2] if j.body2 is not None else None
    return RevoluteAxis.of(index[j.body], body2, j.axis, states)


def build_loads(sc, bodies, infos, index, states) -> tuple:
    """The loads and springs of scenario sc, in that order (System.loads)."""
    out: list = []  # PointForce, BodyTorque, MotorTorque, PointSpring, RotationalSpring
    for k, c in enumerate(sc.loads):
        where = f"loads[{k}]"
        name = c.name or f"{where} {c.type.value}"  # the key of its work in summary.json
        history = c.history()
        follower = c.frame is LoadFrame.BODY
        if c.type is LoadType.FORCE:
            b = index[c.body]
            p = _point(b, bodies, infos, c.point_m, c.node_set, where)
            out.append(PointForce(p, history, follower, name))
        elif c.type is LoadType.TORQUE:
            out.append(BodyTorque(index[c.body], history, follower, name))
        else:
            out.append(MotorTorque(_axis(sc, c.joint, index, states), history, name))
    for k, c in enumerate(sc.springs):
        where = f"springs[{k}]"
        name = c.name or f"{where} {c.type.value}"
        if c.type is SpringType.ROTATIONAL:
            axis = _axis(sc, c.joint, index, states)
            rest = math.radians(c.rest_angle_deg or 0.0)
            damping = c.damping_nms_per_rad or 0.0
            out.append(RotationalSpring(axis, c.stiffness_nm_per_rad, damping, rest, name))
            continue
        b = index[c.body]
        p1 = _point(b, bodies, infos, c.point_m, c.node_set, where)
        p2: BodyPoint | tuple[float, ...]
        if c.body2 is not None:
            b2 = index[c.body2]
            point2 = body_point(b2, bodies[b2], infos[b2].mesh, c.point2_m, f"{where}.point2_m")
            p2, x2 = point2, point2.position(bodies, states)
        else:
            p2 = tuple(float(x) for x in c.ground_m)
            x2 = np.asarray(p2)
        rest = c.rest_length_m
        if rest is None:  # the initial distance: the spring starts unstressed
            rest = float(np.linalg.norm(p1.position(bodies, states) - x2))
        damping = c.damping_n_s_per_m or 0.0
        out.append(PointSpring(p1, p2, c.stiffness_n_per_m, damping, rest, name))
    return tuple(out)
