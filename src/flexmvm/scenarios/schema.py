"""Scenario files: the TOML schema (pydantic v2) and its loader.

A scenario names the bodies (geometry, material, model kind, placement), the contacts between
them, the joints, the probes and the time settings; docs/scenario_format.md lists every key.
Everything is validated here that can be checked without meshing: types, ranges, units,
cross-references between sections, and the rod node sets / facet sets named in
docs/architecture.md. Node sets and surfaces of a ``mesh_file`` body are checked by the builder
after reading the mesh.

Every problem reaches the user as one :class:`ScenarioError` line naming the file, the key path
and the problem, e.g. ``rod_impact.toml: contacts[0].master: unknown body 'b3' (bodies: b1, b2)``.
"""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Mapping
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from annotated_types import Ge, Gt, Le
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    PrivateAttr,
    Strict,
    StringConstraints,
    Tag,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from flexmvm.errors import InputError
from flexmvm.integrate import DEFAULT_THETA
from flexmvm.materials import PRESETS, Material

ROD_NODE_SETS = ("end_a", "end_b", "end_a_centre", "end_b_centre", "side")
ROD_FACET_SETS = ("end_a", "end_b", "side")
_ERROR_TYPE = "flexmvm_scenario"
_SELECTION_RE = re.compile(r"^(\d+)-(\d+)$")


class ScenarioError(InputError):
    """A scenario file that cannot be used: one line with file, key path and problem."""


def _fail(problem: str, key: str = "") -> PydanticCustomError:
    """Error for a validator; ``key`` is appended to the location pydantic reports."""
    return PydanticCustomError(_ERROR_TYPE, "{problem}", {"problem": problem, "key": key})


def _vec3(value: Any) -> tuple[float, float, float]:
    ok = isinstance(value, (list, tuple)) and len(value) == 3
    ok = ok and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in value)
    if not ok or not all(math.isfinite(c) for c in value):
        raise _fail(f"must be 3 finite numbers [x, y, z], got {value!r}")
    return (float(value[0]), float(value[1]), float(value[2]))


Num = Annotated[float, Strict()]
Positive = Annotated[float, Strict(), Gt(0)]
Count = Annotated[int, Strict(), Ge(1)]
Vec3 = Annotated[tuple[float, float, float], BeforeValidator(_vec3)]
Name = Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9_]+$")]
SetName = Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9_]+$")]
_ZERO3 = (0.0, 0.0, 0.0)


class _Frozen(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class RodEnd(StrEnum):
    """Shape of a rod end (mesh/rod.py EndShape by value)."""

    FLAT = "flat"
    HEMISPHERE = "hemisphere"


class ModelKind(StrEnum):
    """How a body's deformation is represented (DESIGN.md, Bodies)."""

    FULL = "full"  # all nodal DOFs (reference solution)
    MVM = "mvm"  # Craig-Bampton: retained nodes + fixed-interface modes (default MVM)
    MVM_SEED = "mvm-seed"  # seed eq. (4): modes on region I, nodal DOFs on region II
    MODAL = "modal"  # first N modes of the reference-supported body
    RIGID = "rigid"  # no elastic coordinates


class ContactKind(StrEnum):
    FRICTIONLESS = "frictionless"  # normal gap >= 0 (default)
    BONDED = "bonded"  # seed eq. (7): all three relative components once closed


class JointType(StrEnum):
    GROUND = "ground"  # the body's floating frame fixed at its placement (6 constraints)
    FIXED = "fixed"  # weld at a point: 6 constraints
    SPHERICAL = "spherical"  # point coincidence: 3 constraints
    REVOLUTE = "revolute"  # point coincidence + axis: 5 constraints
    DISTANCE = "distance"  # constant distance between two points (a string): 1 constraint
    PRESCRIBED = "prescribed"  # a point moves with a constant global velocity: 3 constraints


class MaterialSpec(_Frozen):
    """Inline material table; ranges checked by :class:`flexmvm.materials.Material`."""

    E_pa: Num
    nu: Num
    rho_kg_m3: Num
    name: Name | None = None

    @model_validator(mode="after")
    def _check(self) -> MaterialSpec:
        values = {"E": self.E_pa, "nu": self.nu, "rho": self.rho_kg_m3}
        good = {"E": 1.0, "nu": 0.0, "rho": 1.0}
        for (key, val), toml_key in zip(values.items(), ("E_pa", "nu", "rho_kg_m3"), strict=True):
            try:
                Material(**(good | {key: val}), name="inline")
            except InputError as err:
                raise _fail(str(err).split(": ", 1)[-1], toml_key) from None
        return self


def _material_tag(value: Any) -> str | None:
    if isinstance(value, str):
        return "preset"
    return "inline" if isinstance(value, (dict, MaterialSpec)) else None


MaterialRef = Annotated[
    Annotated[str, Tag("preset")] | Annotated[MaterialSpec, Tag("inline")],
    Discriminator(
        _material_tag,
        custom_error_type="material_type",
        custom_error_message="must be a preset name or a table {E_pa, nu, rho_kg_m3}",
    ),
]


class RodConfig(_Frozen):
    """Rod along local +x, end A at x = 0 (docs/architecture.md); None = the RodSpec default."""

    length_m: Positive
    radius_m: Positive
    end_a: RodEnd = RodEnd.FLAT
    end_b: RodEnd = RodEnd.FLAT
    core_elements: Count | None = None
    core_half_width_m: Positive | None = None
    n_rings: Count | None = None
    first_element_m: Positive | None = None
    growth: Annotated[float, Strict(), Ge(1.0)] | None = None
    max_element_m: Positive | None = None
    cap_depth_m: Positive | None = None

    @model_validator(mode="after")
    def _check(self) -> RodConfig:
        n_caps = (self.end_a is RodEnd.HEMISPHERE) + (self.end_b is RodEnd.HEMISPHERE)
        if self.length_m <= n_caps * self.radius_m:
            raise _fail(
                f"must exceed {n_caps} x radius_m = {n_caps * self.radius_m!r} for "
                f"{n_caps} hemispherical end(s), got {self.length_m!r}",
                "length_m",
            )
        if self.core_half_width_m is not None and self.core_half_width_m >= self.radius_m:
            raise _fail(
                f"must be < radius_m = {self.radius_m!r}, got {self.core_half_width_m!r}",
                "core_half_width_m",
            )
        if (
            self.first_element_m is not None
            and self.max_element_m is not None
            and self.max_element_m < self.first_element_m
        ):
            raise _fail(
                f"must be >= first_element_m = {self.first_element_m!r}, "
                f"got {self.max_element_m!r}",
                "max_element_m",
            )
        return self

    def spec_kwargs(self) -> dict[str, Any]:
        """Keyword arguments for mesh.rod.RodSpec: the fields that are set; ends as strings."""
        return self.model_dump(exclude_none=True, mode="json")


class Ball(_Frozen):
    centre_m: Vec3
    radius_m: Positive


class Box(_Frozen):
    min_m: Vec3
    max_m: Vec3

    @model_validator(mode="after")
    def _check(self) -> Box:
        if any(lo >= hi for lo, hi in zip(self.min_m, self.max_m, strict=True)):
            raise _fail(
                f"must exceed min_m {list(self.min_m)} in every component, got {list(self.max_m)}",
                "max_m",
            )
        return self


class RegionSpec(_Frozen):
    """Retained nodes by node set, ball or box (body-local coordinates) or ids: exactly one."""

    node_set: SetName | None = None
    ball: Ball | None = None
    box: Box | None = None
    node_ids: tuple[Annotated[int, Strict(), Ge(0)], ...] | None = None

    @model_validator(mode="after")
    def _check(self) -> RegionSpec:
        given = [k for k in ("node_set", "ball", "box", "node_ids") if getattr(self, k) is not None]
        if len(given) != 1:
            raise _fail(
                f"needs exactly one of node_set, ball, box, node_ids, got {given or 'none'}"
            )
        if self.node_ids is not None and (
            not self.node_ids or len(set(self.node_ids)) != len(self.node_ids)
        ):
            raise _fail("must be a non-empty list of distinct node ids", "node_ids")
        return self


class ModelConfig(_Frozen):
    """Model of one body. ``selection``/``region``/``modes`` are ignored by kinds that do not
    use them (full, rigid; modal ignores selection/region) so that a kind override stays valid."""

    kind: ModelKind = ModelKind.FULL
    selection: str | None = None
    region: RegionSpec | None = None
    modes: Annotated[int, Strict(), Ge(0)] = 0
    reference: SetName = "end_b"

    @field_validator("selection")
    @classmethod
    def _check_selection(cls, value: str | None) -> str | None:
        match = _SELECTION_RE.match(value) if value is not None else None
        if value is not None and (match is None or min(map(int, match.groups())) < 1):
            raise _fail(f"must be 'i-j' (layers-laps, both >= 1), got {value!r}")
        return value

    @model_validator(mode="after")
    def _check(self) -> ModelConfig:
        if self.selection is not None and self.region is not None:
            raise _fail("give selection or region, not both", "region")
        kind = self.kind.value
        if self.kind in (ModelKind.MVM, ModelKind.MVM_SEED) and self.retained is None:
            raise _fail(f"kind {kind!r} needs selection = 'i-j' or a region", "selection")
        if self.kind in (ModelKind.MVM, ModelKind.MVM_SEED, ModelKind.MODAL) and self.modes < 1:
            raise _fail(f"must be >= 1 for kind {kind!r}, got {self.modes}", "modes")
        return self

    @property
    def retained(self) -> str | RegionSpec | None:
        return self.selection if self.selection is not None else self.region

    @property
    def selection_ij(self) -> tuple[int, int] | None:
        """(layers i, laps j) of the seed's i-j selection, or None."""
        if self.selection is None:
            return None
        i, j = self.selection.split("-")
        return int(i), int(j)


class Rotation(_Frozen):
    axis: Vec3 = (0.0, 0.0, 1.0)
    angle_deg: Num = 0.0

    @field_validator("axis")
    @classmethod
    def _nonzero(cls, axis: tuple[float, float, float]) -> tuple[float, float, float]:
        if math.hypot(*axis) == 0.0:
            raise _fail(f"must be non-zero, got {list(axis)}")
        return axis

    def matrix(self) -> np.ndarray:
        """Rotation matrix (3, 3), body -> global (Rodrigues' formula)."""
        n = np.asarray(self.axis) / np.linalg.norm(self.axis)
        a = math.radians(self.angle_deg)
        nx = np.array([[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]])
        return np.eye(3) + math.sin(a) * nx + (1.0 - math.cos(a)) * (nx @ nx)


class Placement(_Frozen):
    position_m: Vec3 = _ZERO3
    rotation: Rotation = Rotation()
    velocity_mps: Vec3 = _ZERO3
    angular_velocity_radps: Vec3 = _ZERO3
    # start in the quasi-static sag on the body's joints under gravity (at rest; scenarios/sag.py)
    sagged: Annotated[bool, Strict()] = False

    def to_global(self, point_m: tuple[float, float, float]) -> np.ndarray:
        """Initial global position (3,) of a body-local point [m]."""
        return np.asarray(self.position_m) + self.rotation.matrix() @ np.asarray(point_m)


class BodyConfig(_Frozen):
    name: Name
    material: MaterialRef
    rod: RodConfig | None = None
    mesh_file: Path | None = None
    model: ModelConfig = ModelConfig()
    placement: Placement = Placement()

    @field_validator("material")
    @classmethod
    def _known_preset(cls, value: str | MaterialSpec) -> str | MaterialSpec:
        if isinstance(value, str) and value not in PRESETS:
            raise _fail(
                f"unknown material preset {value!r} (presets: {', '.join(sorted(PRESETS))})"
            )
        return value

    @field_validator("mesh_file")
    @classmethod
    def _resolve(cls, value: Path | None, info: ValidationInfo) -> Path | None:
        if value is None:
            return None
        base = Path((info.context or {}).get("base_dir", "."))
        path = (base / value).resolve()
        if not path.is_file():
            raise _fail(f"no such mesh file {str(path)!r}")
        return path

    @model_validator(mode="after")
    def _check(self) -> BodyConfig:
        if (self.rod is None) == (self.mesh_file is None):
            raise _fail("needs exactly one of [bodies.rod] or mesh_file", "rod")
        if self.rod is None and self.model.selection is not None:
            raise _fail(
                "the i-j selection needs a [bodies.rod] body; use region for a mesh_file",
                "model.selection",
            )
        if self.rod is not None:
            region = self.model.region
            if region is not None and region.node_set is not None:
                _check_rod_set(region.node_set, ROD_NODE_SETS, "model.region.node_set")
            _check_rod_set(self.model.reference, ROD_NODE_SETS, "model.reference")
        return self

    def material_obj(self) -> Material:
        """The material as a flexmvm.materials.Material."""
        if isinstance(self.material, str):
            return PRESETS[self.material]
        m = self.material
        return Material(E=m.E_pa, nu=m.nu, rho=m.rho_kg_m3, name=m.name or self.name)


def _check_rod_set(name: str, known: tuple[str, ...], key: str) -> None:
    if name not in known:
        raise _fail(f"rods have no set {name!r} (rod sets: {', '.join(known)})", key)


class ContactConfig(_Frozen):
    """Slave nodes of ``slave`` ('body.surface') against the master facets of ``master``."""

    slave: Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9_]+\.[A-Za-z0-9_]+$")]
    master: Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9_]+\.[A-Za-z0-9_]+$")]
    kind: ContactKind = ContactKind.FRICTIONLESS
    search_radius_m: Positive | None = None

    @property
    def slave_body(self) -> str:
        return self.slave.split(".")[0]

    @property
    def slave_surface(self) -> str:
        return self.slave.split(".")[1]

    @property
    def master_body(self) -> str:
        return self.master.split(".")[0]

    @property
    def master_surface(self) -> str:
        return self.master.split(".")[1]


_JOINT_FIELDS = ("point_m", "ground_m", "body2", "point2_m", "axis", "length_m", "velocity_mps")


class JointConfig(_Frozen):
    """A joint; points are body-local (the nearest node is used), ``ground_m`` is global."""

    type: JointType
    body: Name
    point_m: Vec3 | None = None
    ground_m: Vec3 | None = None
    body2: Name | None = None
    point2_m: Vec3 | None = None
    axis: Vec3 | None = None
    length_m: Positive | None = None
    velocity_mps: Vec3 | None = None

    @model_validator(mode="after")
    def _check(self) -> JointConfig:
        t = self.type
        need: set[str] = set()
        allowed: set[str] = set()
        if t is JointType.PRESCRIBED:
            need = allowed = {"point_m", "velocity_mps"}
        elif t is not JointType.GROUND:
            other = {"body2", "point2_m"} if self.body2 is not None else {"ground_m"}
            need = {"point_m"} | other | ({"axis"} if t is JointType.REVOLUTE else set())
            allowed = need | ({"length_m"} if t is JointType.DISTANCE else set())
        for key in _JOINT_FIELDS:
            given = getattr(self, key) is not None
            if key in need and not given:
                raise _fail(
                    f"required by a {t.value!r} joint"
                    + (" to ground" if key == "ground_m" else ""),
                    key,
                )
            if given and key not in allowed:
                between = key == "ground_m" and self.body2 is not None
                raise _fail(
                    f"not used by a {t.value!r} joint" + (" between two bodies" if between else ""),
                    key,
                )
        if self.axis is not None and math.hypot(*self.axis) == 0.0:
            raise _fail(f"must be non-zero, got {list(self.axis)}", "axis")
        return self


class ProbeConfig(_Frozen):
    name: Name
    body: Name
    node_set: SetName | None = None
    point_m: Vec3 | None = None

    @model_validator(mode="after")
    def _check(self) -> ProbeConfig:
        if (self.node_set is None) == (self.point_m is None):
            raise _fail("needs exactly one of node_set or point_m", "node_set")
        return self


class TimeConfig(_Frozen):
    """Step ``dt_s`` while a contact is active or near, up to ``dt_max_s`` in free flight."""

    t_end_s: Positive
    dt_s: Positive
    dt_max_s: Positive
    output_dt_s: Positive
    theta: Annotated[float, Strict(), Ge(0.5), Le(1.0)] = DEFAULT_THETA
    # extra outputs this often while the step is dt_s (contact active or near); None: none
    output_contact_dt_s: Positive | None = None

    @model_validator(mode="before")
    @classmethod
    def _default_dt_max(cls, data: Any) -> Any:
        if isinstance(data, dict) and data.get("dt_max_s") is None and "dt_s" in data:
            return {**data, "dt_max_s": data["dt_s"]}
        return data

    @model_validator(mode="after")
    def _check(self) -> TimeConfig:
        if self.dt_max_s < self.dt_s:
            raise _fail(f"must be >= dt_s = {self.dt_s!r}, got {self.dt_max_s!r}", "dt_max_s")
        if self.output_dt_s < self.dt_s:
            raise _fail(f"must be >= dt_s = {self.dt_s!r}, got {self.output_dt_s!r}", "output_dt_s")
        if self.output_contact_dt_s is not None and self.output_contact_dt_s < self.dt_s:
            raise _fail(f"must be >= dt_s = {self.dt_s!r}, got {self.output_contact_dt_s!r}",
                        "output_contact_dt_s")
        if self.dt_s > self.t_end_s:
            raise _fail(f"must be <= t_end_s = {self.t_end_s!r}, got {self.dt_s!r}", "dt_s")
        if self.output_dt_s > self.t_end_s:
            raise _fail(
                f"must be <= t_end_s = {self.t_end_s!r}, got {self.output_dt_s!r}", "output_dt_s"
            )
        return self


class Scenario(_Frozen):
    """A validated scenario (docs/scenario_format.md). Build one with :func:`load_scenario`."""

    name: Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9_.-]+$")]
    description: str = ""
    gravity_mps2: Vec3 = _ZERO3
    time: TimeConfig
    bodies: tuple[BodyConfig, ...] = Field(min_length=1)
    contacts: tuple[ContactConfig, ...] = ()
    joints: tuple[JointConfig, ...] = ()
    probes: tuple[ProbeConfig, ...] = ()
    _source: str = PrivateAttr(default="scenario")

    @model_validator(mode="after")
    def _cross_references(self) -> Scenario:
        _unique([b.name for b in self.bodies], "bodies", "body", ".name")
        _unique([p.name for p in self.probes], "probes", "probe", ".name")
        bodies = {b.name: b for b in self.bodies}
        for i, c in enumerate(self.contacts):
            for role in ("slave", "master"):
                body_name, surface = getattr(c, role).split(".")
                key = f"contacts[{i}].{role}"
                _known_body(bodies, body_name, key)
                if bodies[body_name].rod is not None:
                    _check_rod_set(surface, ROD_FACET_SETS, key)
            if c.slave_body == c.master_body:
                raise _fail(
                    f"slave and master are both on body {c.slave_body!r}", f"contacts[{i}].master"
                )
        seen = [(c.slave, c.master) for c in self.contacts]
        _unique([f"{s} on {m}" for s, m in seen], "contacts", "contact", "")
        for i, j in enumerate(self.joints):
            _known_body(bodies, j.body, f"joints[{i}].body")
            if j.body2 is not None:
                _known_body(bodies, j.body2, f"joints[{i}].body2")
                if j.body2 == j.body:
                    raise _fail(f"must differ from body {j.body!r}", f"joints[{i}].body2")
            if j.type is JointType.DISTANCE and j.length_m is None:
                _check_string_length(j, bodies, f"joints[{i}]")
        for i, p in enumerate(self.probes):
            _known_body(bodies, p.body, f"probes[{i}].body")
            if p.node_set is not None and bodies[p.body].rod is not None:
                _check_rod_set(p.node_set, ROD_NODE_SETS, f"probes[{i}].node_set")
        return self

    def body(self, name: str) -> BodyConfig:
        """The body called ``name``; ScenarioError if there is none."""
        for b in self.bodies:
            if b.name == name:
                return b
        raise ScenarioError(
            f"{self._source}: no body {name!r} (bodies: {', '.join(b.name for b in self.bodies)})"
        )

    def with_overrides(
        self,
        model: ModelKind | str | None = None,
        t_end_s: float | None = None,
        dt_s: float | None = None,
        body_models: Mapping[str, ModelConfig] | None = None,
    ) -> Scenario:
        """A copy with the model kind of every non-rigid body set to ``model``, whole model
        blocks replaced per body by ``body_models`` (applied after ``model``), and the end time
        or contact step replaced. A ``dt_s`` above ``dt_max_s`` lifts ``dt_max_s`` to it.
        Everything is validated again; ScenarioError names the override on failure."""
        data = self.model_dump(mode="json")
        if model is not None:
            kind = model.value if isinstance(model, ModelKind) else model
            for b in data["bodies"]:
                if b["model"]["kind"] != ModelKind.RIGID.value:
                    b["model"]["kind"] = kind
        for name, cfg in (body_models or {}).items():
            self.body(name)
            for b in data["bodies"]:
                if b["name"] == name:
                    b["model"] = cfg.model_dump(mode="json")
        if t_end_s is not None:
            data["time"]["t_end_s"] = t_end_s
        if dt_s is not None:
            data["time"]["dt_s"] = dt_s
            data["time"]["dt_max_s"] = max(data["time"]["dt_max_s"], dt_s)
        given = {"model": model, "t_end_s": t_end_s, "dt_s": dt_s, "body_models": body_models}
        what = ", ".join(f"{k}={v!r}" for k, v in given.items() if v is not None)
        return _validate(data, f"{self._source} (with overrides {what})", None)


def _unique(names: list[str], section: str, what: str, suffix: str) -> None:
    for i, name in enumerate(names):
        if name in names[:i]:
            raise _fail(
                f"duplicate {what} {name!r} (also {section}[{names.index(name)}])",
                f"{section}[{i}]{suffix}",
            )


def _check_string_length(j: JointConfig, bodies: Mapping[str, BodyConfig], key: str) -> None:
    """A distance joint without length_m takes the initial distance: it must not be zero."""
    assert j.point_m is not None
    a = bodies[j.body].placement.to_global(j.point_m)
    if j.body2 is not None and j.point2_m is not None:
        b = bodies[j.body2].placement.to_global(j.point2_m)
    else:
        b = np.asarray(j.ground_m)
    if np.linalg.norm(a - b) == 0.0:
        raise _fail("the two points coincide at t = 0; give length_m or move a point", key)


def _known_body(bodies: Mapping[str, BodyConfig], name: str, key: str) -> None:
    if name not in bodies:
        raise _fail(f"unknown body {name!r} (bodies: {', '.join(bodies)})", key)


def _format_loc(loc: tuple[int | str, ...], extra: str) -> str:
    out = ""
    for k, part in enumerate(loc):
        if isinstance(part, int):
            out += f"[{part}]"
        elif part in ("preset", "inline") and k > 0 and loc[k - 1] == "material":
            continue
        else:
            out += f".{part}" if out else str(part)
    if extra:
        out += extra if extra.startswith("[") or not out else f".{extra}"
    return out or "(top level)"


_BOUNDS = {
    "greater_than": ("gt", ">"),
    "greater_than_equal": ("ge", ">="),
    "less_than": ("lt", "<"),
    "less_than_equal": ("le", "<="),
}


def _format_error(err: Any) -> str:
    """One line 'key.path: problem' from one pydantic error dict."""
    ctx = err.get("ctx") or {}
    if err["type"] == _ERROR_TYPE:
        return f"{_format_loc(err['loc'], ctx.get('key', ''))}: {ctx['problem']}"
    where = _format_loc(err["loc"], "")
    if err["type"] == "extra_forbidden":
        return f"{where}: unknown key"
    if err["type"] == "missing":
        return f"{where}: missing required key"
    if err["type"] in _BOUNDS:
        name, op = _BOUNDS[err["type"]]
        bound = ctx[name]
        msg = (
            f"must be {op} {bound:g}"
            if isinstance(bound, (int, float))
            else f"must be {op} {bound}"
        )
    elif err["type"] == "too_short":
        msg = f"needs at least {ctx.get('min_length', 1)} entry"
    else:
        msg = err["msg"][:1].lower() + err["msg"][1:]
    shown = repr(err["input"])
    shown = shown if len(shown) <= 60 else shown[:57] + "..."
    return f"{where}: {msg}, got {shown}".replace("\n", " ")


def scenario_from_dict(
    data: Mapping[str, Any], source: str = "scenario", base_dir: str | Path | None = None
) -> Scenario:
    """Validate a scenario given as the dict a TOML file parses to (docs/scenario_format.md).

    ``source`` names it in errors; ``mesh_file`` paths are resolved against ``base_dir``
    (default: the working directory). Raises ScenarioError (one line: source, key path, problem).
    """
    return _validate(data, source, Path(base_dir) if base_dir is not None else None)


def _validate(data: Any, source: str, base_dir: Path | None) -> Scenario:
    try:
        scenario = Scenario.model_validate(data, context={"base_dir": base_dir or Path(".")})
    except ValidationError as exc:
        errors = exc.errors()
        more = f" (and {len(errors) - 1} more problem(s))" if len(errors) > 1 else ""
        raise ScenarioError(f"{source}: {_format_error(errors[0])}{more}") from None
    scenario._source = source
    return scenario


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario TOML file (docs/scenario_format.md).

    ``mesh_file`` paths are resolved relative to the file. Raises ScenarioError (one line:
    file, key path, problem) for a missing file, a TOML syntax error or any invalid value.
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise ScenarioError(f"{path}: cannot read scenario file ({exc.strerror})") from None
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"{path}: not UTF-8 text (byte {exc.start})") from None
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{path}: invalid TOML: {exc}") from None
    return _validate(data, str(path), path.parent)
