"""The scenario's ``[[supports]]`` table (pydantic v2): a body clamped on one of its node sets
(reduction.clamp: its frame fixed at its placement, the set's nodal coordinates removed), and
the checks of the supports against the bodies and joints (called by schema.Scenario). The
builder's side is scenarios/supports.py; docs/scenario_format.md lists the keys."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from enum import StrEnum

from flexmvm.bodies.build import ModelKind
from flexmvm.constraints.joints import JointType
from flexmvm.reduction.kinds import KINDS
from flexmvm.scenarios.fields import ROD_NODE_SETS, Frozen, Name, SetName, check_rod_set
from flexmvm.scenarios.problems import problem


class SupportType(StrEnum):
    """The supports a scenario can declare (values: the scenario file's ``type``)."""

    CLAMP = "clamp"  # every DOF of a node set held and the frame fixed (a cantilever's root)


def clampable() -> tuple[ModelKind, ...]:
    """The model kinds that can be clamped (ModelKindSpec.clampable): those whose basis is
    built under a reference condition (the interface kind's free-free mode pool has no
    clamped form; a rigid body clamped is a ground joint)."""
    return tuple(k for k, spec in KINDS.items() if spec.clampable)


class SupportConfig(Frozen):
    """A support of ``body`` on its node set ``node_set``."""

    type: SupportType
    body: Name
    node_set: SetName
    # false: the clamp holds the set in the body's frame only, and the scenario's joints move
    # the frame (a cantilever clamped on a hub that a driven revolute joint turns: the
    # spin-up of docs/spin_up.md); true: the frame is also fixed at its placement
    ground_frame: bool = True


def check_supports(supports: Sequence[SupportConfig], bodies: Mapping, joints: Sequence) -> None:
    """Problems of the supports: an unknown body, a rod set a rod does not have, a body
    clamped twice, a model kind that cannot be clamped, or a ground joint on a clamped body
    (its frame would be fixed twice: a singular constraint matrix)."""
    clamped: dict[str, int] = {}
    for i, s in enumerate(supports):
        key = f"supports[{i}]"
        if s.body not in bodies:
            raise problem(f"unknown body {s.body!r} (bodies: {', '.join(bodies)})", f"{key}.body")
        if s.body in clamped:
            raise problem(
                f"body {s.body!r} is clamped twice (also supports[{clamped[s.body]}])",
                f"{key}.body",
            )
        clamped[s.body] = i
        body = bodies[s.body]
        if body.rod is not None:
            check_rod_set(s.node_set, ROD_NODE_SETS, f"{key}.node_set")
        if not body.model.kind.spec.clampable:
            raise problem(
                f"body {s.body!r} of kind {body.model.kind.value!r} cannot be clamped; "
                f"expected one of {', '.join(k.value for k in clampable())}",
                f"{key}.body",
            )
    for i, j in enumerate(joints):
        if (
            j.type is JointType.GROUND
            and j.body in clamped
            and supports[clamped[j.body]].ground_frame
        ):
            raise problem(
                f"body {j.body!r} is clamped by supports[{clamped[j.body]}], which fixes its "
                "frame already; remove the ground joint",
                f"joints[{i}].type",
            )


def without_empty(data, key: str):
    """A scenario's dump without ``key`` when it is empty, so that scenarios without supports
    dump as before the key existed (study case keys and cache identities hash the dumps)."""
    if isinstance(data, dict) and not data.get(key):
        data.pop(key, None)
    return data


__all__ = ["SupportConfig", "SupportType", "check_supports", "clampable", "without_empty"]
