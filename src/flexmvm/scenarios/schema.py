"""The scenario schema (pydantic v2): the tables of a scenario and their cross-references.

A scenario names the bodies (geometry, material, model kind, placement), the contacts between
them, the joints, the probes and the time settings; docs/scenario_format.md lists every key.
Everything is validated here that can be checked without meshing: types, ranges, units,
cross-references between sections, and the rod node sets / facet sets named in
docs/architecture.md. Node sets and surfaces of a ``mesh_file`` body are checked by the builder
after reading the mesh. Files and dicts are read by scenarios/load.py; problems are reported
as one ScenarioError line (scenarios/problems.py).

The option enums are the code's own, shared with the stages that act on them: ModelKind
(bodies.build), EndShape (mesh.rod), ContactKind (constraints.contact), JointType
(constraints.joints).

A Scenario is changed by typed copies, each validated again: ``with_model(body, model)``,
``with_models(model)``, ``with_kind(kind)``, ``with_time(...)``, ``with_material(body, m)``;
:func:`full`, :func:`mvm`, :func:`modal`, :func:`rigid` build the model blocks.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from annotated_types import Ge, Le
from pydantic import (
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

from flexmvm.bodies.build import ModelKind
from flexmvm.bodies.rotation import axis_angle
from flexmvm.constraints.contact import ContactKind
from flexmvm.constraints.joints import JointType
from flexmvm.errors import InputError
from flexmvm.integrate import DEFAULT_THETA
from flexmvm.materials import PRESETS, Material
from flexmvm.mesh.rod import EndShape, RodSpec
from flexmvm.scenarios.fields import (
    ROD_FACET_SETS,
    ROD_NODE_SETS,
    ZERO3,
    Count,
    Frozen,
    Name,
    Num,
    Positive,
    SetName,
    Vec3,
    check_rod_set,
)
from flexmvm.scenarios.problems import ScenarioError, format_error, problem

_SELECTION_RE = re.compile(r"^(\d+)-(\d+)$")


class MaterialSpec(Frozen):
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
                raise problem(str(err).split(": ", 1)[-1], toml_key) from None
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


class RodConfig(Frozen):
    """Rod along local +x, end A at x = 0 (docs/architecture.md); None = the RodSpec default."""

    length_m: Positive
    radius_m: Positive
    end_a: EndShape = EndShape.FLAT
    end_b: EndShape = EndShape.FLAT
    core_elements: Count | None = None
    core_half_width_m: Positive | None = None
    n_rings: Count | None = None
    first_element_m: Positive | None = None
    growth: Annotated[float, Strict(), Ge(1.0)] | None = None
    max_element_m: Positive | None = None
    cap_depth_m: Positive | None = None

    @model_validator(mode="after")
    def _check(self) -> RodConfig:
        n_caps = (self.end_a is EndShape.HEMISPHERE) + (self.end_b is EndShape.HEMISPHERE)
        if self.length_m <= n_caps * self.radius_m:
            raise problem(
                f"must exceed {n_caps} x radius_m = {n_caps * self.radius_m!r} for "
                f"{n_caps} hemispherical end(s), got {self.length_m!r}",
                "length_m",
            )
        if self.core_half_width_m is not None and self.core_half_width_m >= self.radius_m:
            raise problem(
                f"must be < radius_m = {self.radius_m!r}, got {self.core_half_width_m!r}",
                "core_half_width_m",
            )
        if (
            self.first_element_m is not None
            and self.max_element_m is not None
            and self.max_element_m < self.first_element_m
        ):
            raise problem(
                f"must be >= first_element_m = {self.first_element_m!r}, "
                f"got {self.max_element_m!r}",
                "max_element_m",
            )
        return self

    def spec(self) -> RodSpec:
        """The mesh.rod.RodSpec of this rod: the fields that are set, RodSpec's defaults for
        the others."""
        return RodSpec(**{k: v for k, v in self if v is not None})


class Ball(Frozen):
    centre_m: Vec3
    radius_m: Positive


class Box(Frozen):
    min_m: Vec3
    max_m: Vec3

    @model_validator(mode="after")
    def _check(self) -> Box:
        if any(lo >= hi for lo, hi in zip(self.min_m, self.max_m, strict=True)):
            raise problem(
                f"must exceed min_m {list(self.min_m)} in every component, got {list(self.max_m)}",
                "max_m",
            )
        return self


class RegionSpec(Frozen):
    """Retained nodes by node set, ball or box (body-local coordinates) or ids: exactly one."""

    node_set: SetName | None = None
    ball: Ball | None = None
    box: Box | None = None
    node_ids: tuple[Annotated[int, Strict(), Ge(0)], ...] | None = None

    @model_validator(mode="after")
    def _check(self) -> RegionSpec:
        given = [k for k in ("node_set", "ball", "box", "node_ids") if getattr(self, k) is not None]
        if len(given) != 1:
            raise problem(
                f"needs exactly one of node_set, ball, box, node_ids, got {given or 'none'}"
            )
        if self.node_ids is not None and (
            not self.node_ids or len(set(self.node_ids)) != len(self.node_ids)
        ):
            raise problem("must be a non-empty list of distinct node ids", "node_ids")
        return self


class ModelConfig(Frozen):
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
            raise problem(f"must be 'i-j' (layers-laps, both >= 1), got {value!r}")
        return value

    @model_validator(mode="after")
    def _check(self) -> ModelConfig:
        if self.selection is not None and self.region is not None:
            raise problem("give selection or region, not both", "region")
        kind = self.kind.value
        if self.kind.retains_nodes and self.retained is None:
            raise problem(f"kind {kind!r} needs selection = 'i-j' or a region", "selection")
        if self.kind.uses_modes and self.modes < 1:
            raise problem(f"must be >= 1 for kind {kind!r}, got {self.modes}", "modes")
        return self

    @property
    def label(self) -> str:
        """Short description: 'full', 'rigid', 'modal 20', 'mvm 1-3 + 25', 'mvm-seed 1-1 + 37'."""
        if not self.kind.uses_modes:
            return self.kind.value
        if not self.kind.retains_nodes:
            return f"{self.kind.value} {self.modes}"
        where = self.selection if self.selection is not None else "region"
        return f"{self.kind.value} {where} + {self.modes}"

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


class Rotation(Frozen):
    axis: Vec3 = (0.0, 0.0, 1.0)
    angle_deg: Num = 0.0

    @field_validator("axis")
    @classmethod
    def _nonzero(cls, axis: tuple[float, float, float]) -> tuple[float, float, float]:
        if math.hypot(*axis) == 0.0:
            raise problem(f"must be non-zero, got {list(axis)}")
        return axis

    def matrix(self) -> np.ndarray:
        """Rotation matrix (3, 3), body -> global."""
        return axis_angle(self.axis, math.radians(self.angle_deg))


class Placement(Frozen):
    position_m: Vec3 = ZERO3
    rotation: Rotation = Rotation()
    velocity_mps: Vec3 = ZERO3
    angular_velocity_radps: Vec3 = ZERO3

    def to_global(self, point_m: tuple[float, float, float]) -> np.ndarray:
        """Initial global position (3,) of a body-local point [m]."""
        return np.asarray(self.position_m) + self.rotation.matrix() @ np.asarray(point_m)


class BodyConfig(Frozen):
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
            raise problem(
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
            raise problem(f"no such mesh file {str(path)!r}")
        return path

    @model_validator(mode="after")
    def _check(self) -> BodyConfig:
        if (self.rod is None) == (self.mesh_file is None):
            raise problem("needs exactly one of [bodies.rod] or mesh_file", "rod")
        if self.rod is None and self.model.selection is not None:
            raise problem(
                "the i-j selection needs a [bodies.rod] body; use region for a mesh_file",
                "model.selection",
            )
        if self.rod is not None:
            region = self.model.region
            if region is not None and region.node_set is not None:
                check_rod_set(region.node_set, ROD_NODE_SETS, "model.region.node_set")
            check_rod_set(self.model.reference, ROD_NODE_SETS, "model.reference")
        return self

    def material_obj(self) -> Material:
        """The material as a flexmvm.materials.Material."""
        if isinstance(self.material, str):
            return PRESETS[self.material]
        m = self.material
        return Material(E=m.E_pa, nu=m.nu, rho=m.rho_kg_m3, name=m.name or self.name)


class ContactConfig(Frozen):
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


class JointConfig(Frozen):
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


class ProbeConfig(Frozen):
    name: Name
    body: Name
    node_set: SetName | None = None
    point_m: Vec3 | None = None

    @model_validator(mode="after")
    def _check(self) -> ProbeConfig:
        if (self.node_set is None) == (self.point_m is None):
            raise problem("needs exactly one of node_set or point_m", "node_set")
        return self


class TimeConfig(Frozen):
    """Step ``dt_s`` while a contact is active or near, up to ``dt_max_s`` in free flight."""

    t_end_s: Positive
    dt_s: Positive
    dt_max_s: Positive
    output_dt_s: Positive
    theta: Annotated[float, Strict(), Ge(0.5), Le(1.0)] = DEFAULT_THETA

    @model_validator(mode="before")
    @classmethod
    def _default_dt_max(cls, data: Any) -> Any:
        if isinstance(data, dict) and data.get("dt_max_s") is None and "dt_s" in data:
            return {**data, "dt_max_s": data["dt_s"]}
        return data

    @model_validator(mode="after")
    def _check(self) -> TimeConfig:
        if self.dt_max_s < self.dt_s:
            raise problem(f"must be >= dt_s = {self.dt_s!r}, got {self.dt_max_s!r}", "dt_max_s")
        if self.output_dt_s < self.dt_s:
            raise problem(f"must be >= dt_s = {self.dt_s!r}, got {self.output_dt_s!r}", "output_dt_s")
        if self.dt_s > self.t_end_s:
            raise problem(f"must be <= t_end_s = {self.t_end_s!r}, got {self.dt_s!r}", "dt_s")
        if self.output_dt_s > self.t_end_s:
            raise problem(
                f"must be <= t_end_s = {self.t_end_s!r}, got {self.output_dt_s!r}", "output_dt_s"
            )
        return self


class Scenario(Frozen):
    """A validated scenario (docs/scenario_format.md). Build one with :func:`load_scenario`."""

    name: Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9_.-]+$")]
    description: str = ""
    gravity_mps2: Vec3 = ZERO3
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
                    check_rod_set(surface, ROD_FACET_SETS, key)
            if c.slave_body == c.master_body:
                raise problem(
                    f"slave and master are both on body {c.slave_body!r}", f"contacts[{i}].master"
                )
        seen = [(c.slave, c.master) for c in self.contacts]
        _unique([f"{s} on {m}" for s, m in seen], "contacts", "contact", "")
        for i, j in enumerate(self.joints):
            _known_body(bodies, j.body, f"joints[{i}].body")
            if j.body2 is not None:
                _known_body(bodies, j.body2, f"joints[{i}].body2")
                if j.body2 == j.body:
                    raise problem(f"must differ from body {j.body!r}", f"joints[{i}].body2")
            if j.type is JointType.DISTANCE and j.length_m is None:
                _check_string_length(j, bodies, f"joints[{i}]")
        for i, p in enumerate(self.probes):
            _known_body(bodies, p.body, f"probes[{i}].body")
            if p.node_set is not None and bodies[p.body].rod is not None:
                check_rod_set(p.node_set, ROD_NODE_SETS, f"probes[{i}].node_set")
        return self

    def body(self, name: str) -> BodyConfig:
        """The body called ``name``; ScenarioError if there is none."""
        for b in self.bodies:
            if b.name == name:
                return b
        raise ScenarioError(
            f"{self._source}: no body {name!r} (bodies: {', '.join(b.name for b in self.bodies)})"
        )

    @property
    def source(self) -> str:
        """Where the scenario came from (a file path, or what made it): named in errors."""
        return self._source

    def _copy(self, what: str, **fields: Any) -> Scenario:
        """A copy with top-level ``fields`` replaced (model instances, not dumps), validated
        again as a whole: every cross-reference is checked; ScenarioError names ``what``."""
        source = f"{self._source} ({what})"
        return validate_scenario({**dict(self), **fields}, source, None, keep_source=self._source)

    def _replace_bodies(self, what: str, change: Mapping[str, Mapping[str, Any]]) -> Scenario:
        """Bodies named in ``change`` with their fields replaced, each body validated again."""
        for name in change:
            self.body(name)
        source = f"{self._source} ({what})"
        bodies = tuple(validate_part(BodyConfig, {**dict(b), **change[b.name]}, source,
                                     f"bodies[{k}]")
                       if b.name in change else b for k, b in enumerate(self.bodies))
        return self._copy(what, bodies=bodies)

    def with_model(self, body: str, model: ModelConfig) -> Scenario:
        """A copy with body ``body`` modelled by ``model`` (see :func:`mvm`, :func:`full`,
        :func:`modal`, :func:`rigid`)."""
        if not isinstance(model, ModelConfig):
            raise ScenarioError(f"{self._source}: with_model({body!r}, ...) received "
                                f"{type(model).__name__}, expected a ModelConfig (flexmvm.mvm(), "
                                "flexmvm.full(), ...)")
        return self._replace_bodies(f"body {body} as {model.label}", {body: {"model": model}})

    def with_models(self, model: ModelConfig, *, keep_rigid: bool = True) -> Scenario:
        """A copy with every body (rigid ones kept, unless ``keep_rigid`` is False) modelled
        by ``model``."""
        names = [b.name for b in self.bodies
                 if not (keep_rigid and b.model.kind is ModelKind.RIGID)]
        return self._replace_bodies(f"every body as {model.label}",
                                    {n: {"model": model} for n in names})

    def with_kind(self, kind: ModelKind | str) -> Scenario:
        """A copy with the model kind of every non-rigid body set to ``kind``, each keeping
        its selection, region, modes and reference (``flexmvm run --model``)."""
        try:
            kind = ModelKind(kind)
        except ValueError:
            raise ScenarioError(f"{self._source}: model kind {kind!r}; expected one of "
                                f"{', '.join(k.value for k in ModelKind)}") from None
        what = f"model kind {kind.value}"
        source = f"{self._source} ({what})"
        change = {b.name: {"model": validate_part(ModelConfig, {**dict(b.model), "kind": kind},
                                                  source, f"bodies[{k}].model")}
                  for k, b in enumerate(self.bodies) if b.model.kind is not ModelKind.RIGID}
        return self._replace_bodies(what, change)

    def with_time(self, *, t_end_s: float | None = None, dt_s: float | None = None,
                  dt_max_s: float | None = None, output_dt_s: float | None = None,
                  theta: float | None = None) -> Scenario:
        """A copy with the given time settings replaced [s]. A ``dt_s`` above ``dt_max_s``
        (and no ``dt_max_s`` given) lifts ``dt_max_s`` to it."""
        given = {"t_end_s": t_end_s, "dt_s": dt_s, "dt_max_s": dt_max_s,
                 "output_dt_s": output_dt_s, "theta": theta}
        given = {k: v for k, v in given.items() if v is not None}
        if dt_s is not None and dt_max_s is None:
            given["dt_max_s"] = max(self.time.dt_max_s, dt_s)
        what = ", ".join(f"{k}={v!r}" for k, v in given.items())
        time = validate_part(TimeConfig, {**dict(self.time), **given},
                             f"{self._source} ({what})", "time")
        return self._copy(what, time=time)

    def with_material(self, body: str, material: Material | str) -> Scenario:
        """A copy with body ``body`` made of ``material`` (a Material, or a preset name)."""
        if isinstance(material, Material):
            spec = MaterialSpec(E_pa=float(material.E), nu=float(material.nu),
                                rho_kg_m3=float(material.rho), name=material.name)
            label = material.name
        else:
            spec = label = material
        return self._replace_bodies(f"body {body} of {label}", {body: {"material": spec}})

    def with_overrides(self, model: ModelKind | str | None = None, t_end_s: float | None = None,
                       dt_s: float | None = None,
                       body_models: Mapping[str, ModelConfig] | None = None) -> Scenario:
        """The command line's overrides in one call: :meth:`with_kind` ``model``, then
        :meth:`with_model` for each of ``body_models``, then :meth:`with_time`."""
        sc = self
        if model is not None:
            sc = sc.with_kind(model)
        for name, cfg in (body_models or {}).items():
            sc = sc.with_model(name, cfg)
        if t_end_s is not None or dt_s is not None:
            sc = sc.with_time(t_end_s=t_end_s, dt_s=dt_s)
        return sc


def full(reference: str = "end_b") -> ModelConfig:
    """Full FE model: every nodal DOF but the reference condition's six."""
    return validate_part(ModelConfig, {"kind": ModelKind.FULL, "reference": reference}, "full()")


def rigid() -> ModelConfig:
    """Rigid body: no elastic coordinates."""
    return validate_part(ModelConfig, {"kind": ModelKind.RIGID}, "rigid()")


def modal(modes: int, reference: str = "end_b") -> ModelConfig:
    """The first ``modes`` modes of the body supported by its reference condition."""
    return validate_part(ModelConfig, {"kind": ModelKind.MODAL, "modes": modes,
                                       "reference": reference}, f"modal({modes!r})")


def mvm(selection: str | tuple[int, int] | None = None, modes: int = 0, *,
        region: RegionSpec | None = None, reference: str = "end_b",
        seed_eq4: bool = False) -> ModelConfig:
    """MVM model: the nodes of ``selection`` (the seed's layers-laps 'i-j' or (i, j)) or of
    ``region`` kept as nodal coordinates, plus ``modes`` modes: Craig-Bampton fixed-interface
    modes, or with ``seed_eq4`` the seed's eq. (4) block basis."""
    if isinstance(selection, tuple):
        selection = "-".join(str(int(v)) for v in selection)
    kind = ModelKind.MVM_SEED if seed_eq4 else ModelKind.MVM
    data = {"kind": kind, "selection": selection, "region": region, "modes": modes,
            "reference": reference}
    return validate_part(ModelConfig, data, f"mvm({selection!r}, modes={modes!r})")


def _unique(names: list[str], section: str, what: str, suffix: str) -> None:
    for i, name in enumerate(names):
        if name in names[:i]:
            raise problem(
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
        raise problem("the two points coincide at t = 0; give length_m or move a point", key)


def _known_body(bodies: Mapping[str, BodyConfig], name: str, key: str) -> None:
    if name not in bodies:
        raise problem(f"unknown body {name!r} (bodies: {', '.join(bodies)})", key)


def validate_part(cls: type[Frozen], data: Mapping[str, Any], source: str, key: str = ""):
    """``cls`` validated from ``data`` (values or model instances); ScenarioError (one line:
    source, key path, problem) otherwise."""
    try:
        return cls.model_validate(dict(data))
    except ValidationError as exc:
        errors = exc.errors()
        more = f" (and {len(errors) - 1} more problem(s))" if len(errors) > 1 else ""
        line = format_error(errors[0])
        if key:
            top = "(top level)"
            line = key + (line[len(top):] if line.startswith(top) else f".{line}")
        raise ScenarioError(f"{source}: {line}{more}") from None


def validate_scenario(data: Any, source: str, base_dir: Path | None, *,
                      keep_source: str | None = None) -> Scenario:
    """Validate ``data`` (a dict, or field values that may be model instances) as a Scenario;
    ScenarioError names ``source``. The scenario remembers ``keep_source`` (default
    ``source``) as where it came from. ``mesh_file`` paths resolve against ``base_dir``."""
    try:
        scenario = Scenario.model_validate(data, context={"base_dir": base_dir or Path(".")})
    except ValidationError as exc:
        errors = exc.errors()
        more = f" (and {len(errors) - 1} more problem(s))" if len(errors) > 1 else ""
        raise ScenarioError(f"{source}: {format_error(errors[0])}{more}") from None
    scenario._source = keep_source or source
    return scenario


