"""A scenario joint (``[[joints]]``) as constraint objects: its points on the bodies (a node
set's centroid or a body point) and its rows by joint type (drives and prescribed paths:
assembly/drive_build.py)."""

from __future__ import annotations

import numpy as np

from flexmvm.assembly.body_build import BodyInfo
from flexmvm.assembly.drive_build import joint_name, prescribed_joints, revolute_joints
from flexmvm.assembly.mesh_lookup import body_point
from flexmvm.bodies.body import FlexibleBody
from flexmvm.constraints.joints import (
    BodyPoint,
    DistanceJoint,
    JointType,
    NodeSetPoint,
    SphericalJoint,
    fixed_joint,
    ground_joint,
)
from flexmvm.constraints.prismatic import prismatic_joint
from flexmvm.errors import InputError, MeshError


def node_set_point(
    index, body: FlexibleBody, info: BodyInfo, name: str, where: str
) -> NodeSetPoint:
    """The centroid of node set `name` of the body (constraints.joints.NodeSetPoint)."""
    try:
        ids = info.mesh.node_set(name)
    except MeshError as exc:
        raise InputError(f"{where}: {exc}") from None
    return NodeSetPoint.of(index, body, ids)


def joint_constraints(j, k, bodies, infos, index, states):
    where, name = f"joints[{k}]", joint_name(j, k)
    b = index[j.body]
    t = j.type
    if t is JointType.GROUND:
        return ground_joint(b, states)
    if j.node_set is not None:
        p1 = node_set_point(b, bodies[b], infos[b], j.node_set, f"{where}.node_set")
    else:
        p1 = body_point(b, bodies[b], infos[b].mesh, j.point_m, f"{where}.point_m")
    if t is JointType.PRESCRIBED:
        return prescribed_joints(j, name, p1, bodies, states)
    if t is JointType.PRISMATIC:
        return prismatic_joint(p1, j.ground_m, j.axis, bodies, states)
    if j.body2 is not None:
        b2 = index[j.body2]
        at = j.point2_m
        if at is None:  # body2's point where the node set's centroid is at t = 0
            at = states[b2].A.T @ (p1.position(bodies, states) - states[b2].r)
        p2 = body_point(b2, bodies[b2], infos[b2].mesh, at, f"{where}.point2_m")
    elif j.ground_m is not None:
        p2 = np.asarray(j.ground_m, float)
    else:  # a node set's centroid, held where it starts (schema.JointConfig)
        p2 = p1.position(bodies, states)
    if t is JointType.DISTANCE:
        x1 = p1.position(bodies, states)
        x2 = p2.position(bodies, states) if isinstance(p2, BodyPoint) else p2
        length = j.length_m if j.length_m is not None else float(np.linalg.norm(x1 - x2))
        return [DistanceJoint(p1, p2, length)]
    if t is JointType.SPHERICAL:
        return [SphericalJoint(p1, p2)]
    if t is JointType.REVOLUTE:
        return revolute_joints(j, name, p1, p2, states)
    return fixed_joint(p1, p2, states)
