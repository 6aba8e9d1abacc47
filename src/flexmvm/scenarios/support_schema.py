"""The scenario's ``[[supports]]`` table (pydantic v2): a body clamped on node sets, or held
on them in chosen directions (pinned, roller, symmetry plane, ``fixed`` axes) (reduction.clamp:
its frame fixed at its placement, the held nodal coordinates removed), and the checks of the
supports against the bodies and joints (called by schema.Scenario); and spring beds on facet
sets (fe/spring_bed.py: their stiffness added to K). Several supports of one body are merged
(a DOF held by two is held once). The builder's side is assembly/supports.py;
docs/scenario_format.md lists the keys."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from enum import StrEnum

from pydantic import model_serializer, model_validator

from flexmvm.bodies.build import ModelKind
from flexmvm.constraints.joints import JointType
from flexmvm.fe.spring_bed import BedDirection
from flexmvm.reduction.kinds import KINDS
from flexmvm.scenarios.fields import (
    ROD_FACET_SETS,
    ROD_NODE_SETS,
    Frozen,
    Name,
    Positive,
    SetName,
    check_rod_set,
)
from flexmvm.scenarios.plasticity_schema import plasticity_of
from flexmvm.scenarios.problems import problem


class SupportType(StrEnum):
    """The supports a scenario can declare (values: the scenario file's ``type``)."""

    CLAMP = "clamp"  # every DOF of a node set held and the frame fixed (a cantilever's root)
    # every translation held: the nodes of solid elements carry no rotation, so for them a
    # pinned set is a clamp (a pinned line holds a beam's end but lets it turn about the line)
    PINNED = "pinned"
    ROLLER = "roller"  # one direction held (``direction``), the nodes slide in the others
    SYMMETRY = "symmetry"  # a symmetry plane: the plane's ``normal`` held, in-plane free
    FIXED = "fixed"  # the chosen directions ``fixed`` held (["x", "z"])
    # springs on a facet set ``surface``: ``stiffness_n_per_m3`` [N/m^3] along ``direction``
    # (an axis or the facet normal), their stiffness added to K (a Winkler foundation, a pad)
    SPRING_BED = "spring_bed"


class Axis(StrEnum):
    """A direction a support holds: a body axis, or a global one (``frame``)."""

    X = "x"
    Y = "y"
    Z = "z"


class AxisFrame(StrEnum):
    """Where a support's directions are read: the body's axes, or the global axes at the
    body's placement (they must then lie along body axes: the held DOFs are nodal ones)."""

    BODY = "body"
    GLOBAL = "global"


#: The directions each type holds by itself (None: read from its own key).
_ALL = (Axis.X, Axis.Y, Axis.Z)
_TYPE_KEY = {
    SupportType.ROLLER: "direction",
    SupportType.SYMMETRY: "normal",
    SupportType.FIXED: "fixed",
    SupportType.SPRING_BED: "direction",
}


def clampable() -> tuple[ModelKind, ...]:
    """The model kinds that can be clamped (ModelKindSpec.clampable): those whose basis is
    built under a reference condition (the interface kind's free-free mode pool has no
    clamped form; a rigid body clamped is a ground joint)."""
    return tuple(k for k, spec in KINDS.items() if spec.clampable)


class SupportConfig(Frozen):
    """A support of ``body`` on its node set ``node_set`` (or a list of sets): clamp and
    pinned hold every direction, roller its ``direction``, symmetry its ``normal``, fixed the
    list ``fixed``; a spring bed springs of ``stiffness_n_per_m3`` on its facet set
    ``surface`` along ``direction``; directions are body axes, or global ones with
    ``frame = "global"``."""

    type: SupportType
    body: Name
    node_set: SetName | tuple[SetName, ...] | None = None
    surface: SetName | None = None
    stiffness_n_per_m3: Positive | None = None
    direction: BedDirection | None = None
    normal: Axis | None = None
    fixed: tuple[Axis, ...] | None = None
    frame: AxisFrame = AxisFrame.BODY
    # false: the clamp holds the set in the body's frame only, and the scenario's joints move
    # the frame (a cantilever clamped on a hub that a driven revolute joint turns: the
    # spin-up of docs/spin_up.md); true: the frame is also fixed at its placement
    ground_frame: bool = True

    @model_validator(mode="after")
    def _keys(self) -> SupportConfig:
        need = _TYPE_KEY.get(self.type)
        for key in ("direction", "normal", "fixed"):
            given = getattr(self, key) is not None
            if given and key != need:
                allowed = f"only {need!r}" if need else "none"
                raise problem(
                    f"a {self.type.value} support takes no {key!r} (direction keys: {allowed})",
                    key,
                )
            if not given and key == need:
                axes = "x, y, z or normal" if key == "direction" and self.surface else "x, y or z"
                raise problem(f"a {self.type.value} support needs {key!r} ({axes})", key)
        self._check_targets()
        if self.type is SupportType.ROLLER and self.direction is BedDirection.NORMAL:
            raise problem("a roller's direction must be x, y or z, got 'normal'", "direction")
        if self.fixed is not None and (not self.fixed or len(set(self.fixed)) < len(self.fixed)):
            raise problem(
                f"expected distinct directions among x, y, z, got {[a.value for a in self.fixed]}",
                "fixed",
            )
        if self.frame is AxisFrame.GLOBAL and not self.ground_frame:
            raise problem(
                "global directions need the frame fixed at its placement (ground_frame = true); "
                'expected frame = "body" for a moving frame',
                "frame",
            )
        return self

    def _check_targets(self) -> None:
        """A spring bed takes a surface and a stiffness, every other support node sets."""
        bed = self.type is SupportType.SPRING_BED
        for key, wanted in (("surface", bed), ("stiffness_n_per_m3", bed), ("node_set", not bed)):
            if (getattr(self, key) is not None) != wanted:
                verb = "needs" if wanted else "takes no"
                raise problem(f"a {self.type.value} support {verb} {key!r}", key)
        names = self.node_sets
        if not bed and (not names or len(set(names)) < len(names)):
            raise problem(f"expected distinct node set names, got {list(names)}", "node_set")

    @model_serializer(mode="wrap")
    def _dump(self, handler):  # a clamp dumps as before these keys existed (study keys)
        data = handler(self)
        if isinstance(data, dict):
            for key in ("direction", "normal", "fixed", "surface", "stiffness_n_per_m3"):
                if data.get(key) is None:
                    data.pop(key, None)
            if data.get("frame") == AxisFrame.BODY.value:
                data.pop("frame", None)
        return data

    @property
    def node_sets(self) -> tuple[str, ...]:
        """The names of the supported node sets (none for a spring bed)."""
        if self.node_set is None:
            return ()
        return (self.node_set,) if isinstance(self.node_set, str) else tuple(self.node_set)

    @property
    def axes(self) -> tuple[Axis, ...]:
        """The node sets' held directions (in ``frame``); none for a spring bed."""
        if self.type is SupportType.SPRING_BED:
            return ()
        key = _TYPE_KEY.get(self.type)
        if key is None:
            return _ALL
        value = getattr(self, key)
        return tuple(Axis(v.value) for v in (value if isinstance(value, tuple) else (value,)))


def check_supports(supports: Sequence[SupportConfig], bodies: Mapping, joints: Sequence) -> None:
    """Problems of the supports: an unknown body, a rod set a rod does not have, a model kind
    that cannot be clamped, two supports of one body that disagree on ground_frame, or a
    ground joint on a clamped body (its frame would be fixed twice: a singular constraint
    matrix). Several supports of one body are merged by the builder, not refused."""
    clamped: dict[str, int] = {}
    for i, s in enumerate(supports):
        key = f"supports[{i}]"
        if s.body not in bodies:
            raise problem(f"unknown body {s.body!r} (bodies: {', '.join(bodies)})", f"{key}.body")
        if s.body in clamped and supports[clamped[s.body]].ground_frame != s.ground_frame:
            raise problem(
                f"ground_frame = {str(s.ground_frame).lower()} on body {s.body!r}, but "
                f"supports[{clamped[s.body]}] says {str(not s.ground_frame).lower()}; expected "
                "one value for all supports of a body",
                f"{key}.ground_frame",
            )
        clamped.setdefault(s.body, i)
        body = bodies[s.body]
        if body.rod is not None:
            for name in s.node_sets:
                check_rod_set(name, ROD_NODE_SETS, f"{key}.node_set")
            if s.surface is not None:
                check_rod_set(s.surface, ROD_FACET_SETS, f"{key}.surface")
        if s.type is SupportType.SPRING_BED and plasticity_of(body) is not None:
            raise problem(
                f"body {s.body!r} is plastic; a spring bed is on elastic bodies only "
                "(the plastic internal force has no bed)",
                f"{key}.type",
            )
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


__all__ = [
    "Axis",
    "AxisFrame",
    "SupportConfig",
    "SupportType",
    "check_supports",
    "clampable",
    "without_empty",
]
