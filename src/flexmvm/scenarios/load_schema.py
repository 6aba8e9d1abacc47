"""The scenario's ``[[loads]]`` and ``[[springs]]`` tables (pydantic v2): applied forces, body
torques and motor torques (constant or a time table), linear spring-dampers between points and
rotational ones on revolute joints (flexmvm.loads). ``check_load_references`` checks the
cross-references (bodies, joints) from the Scenario; assembly/load_build.py builds them;
docs/scenario_format.md lists the keys."""

from __future__ import annotations

import math
from enum import StrEnum
from typing import Annotated, Any

from annotated_types import Ge
from pydantic import Strict, model_validator

from flexmvm.constraints.joints import JointType
from flexmvm.errors import InputError
from flexmvm.loads.history import TimeHistory
from flexmvm.scenarios.fields import Frozen, Name, SetName, Vec3
from flexmvm.scenarios.problems import problem

NonNegative = Annotated[float, Strict(), Ge(0.0)]
Index = Annotated[int, Strict(), Ge(0)]


class LoadType(StrEnum):
    """What a ``[[loads]]`` entry applies (values: the scenario file's ``type``)."""

    FORCE = "force"  # a force [N] at a point of a body
    TORQUE = "torque"  # a torque [N m] on a body's frame
    MOTOR = "motor"  # a torque [N m] about a revolute joint's axis, reaction on the other side


class LoadFrame(StrEnum):
    """Directions of a force or torque: fixed in space, or turning with the body's frame."""

    GLOBAL = "global"
    BODY = "body"


class SpringType(StrEnum):
    LINEAR = "linear"  # point to point, N/m
    ROTATIONAL = "rotational"  # on a revolute joint's relative angle, N m/rad


def _need_allow(obj, need: set[str], allowed: set[str], fields: tuple[str, ...], what: str):
    """problem() for a key in need that is missing, or one given outside allowed."""
    for key in fields:
        given = getattr(obj, key) is not None
        if key in need and not given:
            raise problem(f"required by a {what}", key)
        if given and key not in allowed:
            raise problem(f"not used by a {what}", key)


def history_of(value: Any, times_s: Any, width: int, key: str) -> TimeHistory:
    """The TimeHistory of a constant ``value`` or, with ``times_s``, a table of values (one
    per time); a problem() naming ``key`` otherwise, ``times_s`` when the times are wrong."""
    if times_s is not None:
        _check_times(times_s)
    try:
        if times_s is None:
            ok = (width == 1 and _number(value)) or (
                width == 3
                and isinstance(value, (list, tuple))
                and len(value) == 3
                and all(map(_number, value))
            )
            if not ok:
                shape = "a number" if width == 1 else "3 numbers [x, y, z]"
                raise InputError(f"must be {shape} (or a table with times_s), got {value!r}")
            return TimeHistory.constant(value, -math.inf, key)
        rows = value if isinstance(value, (list, tuple)) else [value]
        flat = [x for r in rows for x in (r if isinstance(r, (list, tuple)) else [r])]
        if not all(map(_number, flat)):
            raise InputError(f"must hold numbers only, got {value!r}")
        bad = next((x for x in flat if not math.isfinite(x)), None)
        if bad is not None:
            raise InputError(f"expected finite values, got {bad!r} in {value!r}")
        return TimeHistory.table(times_s, value, width, "table")
    except (InputError, ValueError) as exc:
        raise problem(str(exc).removeprefix(f"{key}: ").removeprefix("table: "), key) from None


def _check_times(times_s: Any) -> None:
    """A problem() naming ``times_s`` unless it is a list of finite numbers increasing
    strictly; the offending entries shown as written (a Python float, not a numpy repr)."""
    if not (isinstance(times_s, (list, tuple)) and times_s and all(map(_number, times_s))):
        raise problem(f"expected a list of numbers [s], got {times_s!r}", "times_s")
    for i, t in enumerate(times_s):
        if not math.isfinite(t):
            raise problem(f"expected finite times [s], got {t!r} at index {i}", "times_s")
    for i in range(len(times_s) - 1):
        if not times_s[i + 1] > times_s[i]:
            raise problem(
                f"times must increase strictly, got {times_s[i]!r} then {times_s[i + 1]!r} s "
                f"(indices {i}, {i + 1})",
                "times_s",
            )


def _number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


_LOAD_FIELDS = ("body", "point_m", "node_set", "joint")


class LoadConfig(Frozen):
    """An applied load: ``force_n`` on a point (``point_m`` or a ``node_set``'s centroid) of
    ``body``, ``torque_nm`` on ``body``'s frame, or (motor) ``torque_nm`` about the axis of
    revolute joint ``joint`` (its index in [[joints]]). A constant, or a table with
    ``times_s`` (piecewise linear, the end values outside it)."""

    type: LoadType
    name: Name | None = None
    body: Name | None = None
    point_m: Vec3 | None = None
    node_set: SetName | None = None
    joint: Index | None = None
    frame: LoadFrame = LoadFrame.GLOBAL
    force_n: Any = None
    torque_nm: Any = None
    times_s: Any = None

    @model_validator(mode="after")
    def _check(self) -> LoadConfig:
        t = self.type
        what = f"{t.value!r} load"
        if t is LoadType.FORCE:
            point = {"node_set"} if self.node_set is not None else {"point_m"}
            _need_allow(self, {"body"} | point, {"body"} | point, _LOAD_FIELDS, what)
        elif t is LoadType.TORQUE:
            _need_allow(self, {"body"}, {"body"}, _LOAD_FIELDS, what)
        else:
            _need_allow(self, {"joint"}, {"joint"}, _LOAD_FIELDS, what)
            if self.frame is not LoadFrame.GLOBAL:
                raise problem("a motor acts about its joint's axis: no frame", "frame")
        key = "force_n" if t is LoadType.FORCE else "torque_nm"
        other = "torque_nm" if t is LoadType.FORCE else "force_n"
        if getattr(self, other) is not None:
            raise problem(f"not used by a {what} (give {key})", other)
        if getattr(self, key) is None:
            raise problem(f"required by a {what}", key)
        self.history()
        return self

    def history(self) -> TimeHistory:
        """The load's TimeHistory (3 components, or 1 for a motor)."""
        key = "force_n" if self.type is LoadType.FORCE else "torque_nm"
        width = 1 if self.type is LoadType.MOTOR else 3
        return history_of(getattr(self, key), self.times_s, width, key)


_SPRING_FIELDS = (
    "body",
    "point_m",
    "node_set",
    "body2",
    "point2_m",
    "ground_m",
    "joint",
    "stiffness_n_per_m",
    "damping_n_s_per_m",
    "rest_length_m",
    "stiffness_nm_per_rad",
    "damping_nms_per_rad",
    "rest_angle_deg",
)


class SpringConfig(Frozen):
    """A spring-damper: ``linear`` between a point of ``body`` (``point_m`` or ``node_set``)
    and a point of ``body2`` (``point2_m``) or a ground point (``ground_m``); ``rotational``
    on the relative angle of revolute joint ``joint`` (its index in [[joints]])."""

    type: SpringType = SpringType.LINEAR
    name: Name | None = None
    body: Name | None = None
    point_m: Vec3 | None = None
    node_set: SetName | None = None
    body2: Name | None = None
    point2_m: Vec3 | None = None
    ground_m: Vec3 | None = None
    joint: Index | None = None
    stiffness_n_per_m: NonNegative | None = None
    damping_n_s_per_m: NonNegative | None = None
    rest_length_m: NonNegative | None = None
    stiffness_nm_per_rad: NonNegative | None = None
    damping_nms_per_rad: NonNegative | None = None
    rest_angle_deg: Annotated[float, Strict()] | None = None

    @model_validator(mode="after")
    def _check(self) -> SpringConfig:
        what = f"{self.type.value!r} spring"
        if self.type is SpringType.ROTATIONAL:
            need = {"joint", "stiffness_nm_per_rad"}
            allowed = need | {"damping_nms_per_rad", "rest_angle_deg"}
        else:
            point = {"node_set"} if self.node_set is not None else {"point_m"}
            other = {"body2", "point2_m"} if self.body2 is not None else {"ground_m"}
            need = {"body", "stiffness_n_per_m"} | point | other
            allowed = need | {"damping_n_s_per_m", "rest_length_m"}
        _need_allow(self, need, allowed, _SPRING_FIELDS, what)
        return self


def check_load_references(loads, springs, joints, bodies, known_body) -> None:
    """Cross-references of [[loads]] and [[springs]]: bodies exist (known_body(bodies, name,
    key)), body2 differs from body, ``joint`` is the index of a revolute [[joints]] entry."""
    for section, entries in (("loads", loads), ("springs", springs)):
        for i, e in enumerate(entries):
            body2 = e.body2 if isinstance(e, SpringConfig) else None  # a load has no body2
            for key, name in (("body", e.body), ("body2", body2)):
                if name is not None:
                    known_body(bodies, name, f"{section}[{i}].{key}")
            if body2 is not None and body2 == e.body:
                raise problem(f"must differ from body {e.body!r}", f"{section}[{i}].body2")
            if e.joint is not None:
                if e.joint >= len(joints):
                    raise problem(
                        f"no joints[{e.joint}] ({len(joints)} joint(s))", f"{section}[{i}].joint"
                    )
                if joints[e.joint].type is not JointType.REVOLUTE:
                    raise problem(
                        f"joints[{e.joint}] is a {joints[e.joint].type.value!r} joint, expected "
                        "a 'revolute' one",
                        f"{section}[{i}].joint",
                    )


def drop_empty_tables(data: Any) -> Any:
    """A scenario's dump without empty [[loads]] and [[springs]]: as before the keys existed
    (study case keys and cache identities hash these dumps)."""
    if isinstance(data, dict):
        for key in ("loads", "springs"):
            if key in data and not data[key]:
                data.pop(key)
    return data
