"""The scenario schema (pydantic v2): the scenario, its contacts, joints, probes and time
settings, and their cross-references (the tables of one body: body_schema.py).

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
``with_models(model)``, ``with_kind(kind)``, ``with_time(...)``, ``with_material(body, m)``,
``with_rod(body, ...)``, ``with_tables(**tables)``; model_constructors' full, mvm, modal, rigid
build the model blocks.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from pydantic import (
    Field,
    PrivateAttr,
    StringConstraints,
    ValidationError,
    model_serializer,
    model_validator,
)

from flexmvm.bodies.build import ModelKind
from flexmvm.constraints.contact_laws import massless_laws
from flexmvm.constraints.joints import JointType
from flexmvm.errors import InputError
from flexmvm.materials import Material
from flexmvm.scenarios.body_schema import (
    BodyConfig,
    MaterialSpec,
    ModelConfig,
    RodConfig,
)
from flexmvm.scenarios.contact_schema import ContactConfig, ProbeConfig
from flexmvm.scenarios.fields import (
    ROD_FACET_SETS,
    ROD_NODE_SETS,
    ZERO3,
    Acceleration,
    Frozen,
    check_rod_set,
)
from flexmvm.scenarios.initial_motion import check_impact_speeds, check_motion_names
from flexmvm.scenarios.joint_schema import JointConfig
from flexmvm.scenarios.load_schema import (
    LoadConfig,
    SpringConfig,
    check_load_references,
    drop_empty_tables,
)
from flexmvm.scenarios.problems import ScenarioError, format_error, problem, validate_part
from flexmvm.scenarios.support_schema import SupportConfig, check_supports, without_empty
from flexmvm.scenarios.time_schema import CompareConfig, TimeConfig


class Scenario(Frozen):
    """A validated scenario (docs/scenario_format.md). Build one with :func:`load_scenario`."""

    name: Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9_.-]+$")]
    description: str = ""
    gravity_mps2: Acceleration = ZERO3
    time: TimeConfig
    bodies: tuple[BodyConfig, ...] = Field(min_length=1)
    contacts: tuple[ContactConfig, ...] = ()
    joints: tuple[JointConfig, ...] = ()
    supports: tuple[SupportConfig, ...] = ()
    probes: tuple[ProbeConfig, ...] = ()
    compare: CompareConfig = CompareConfig()
    loads: tuple[LoadConfig, ...] = ()  # applied forces and torques (load_schema.py)
    springs: tuple[SpringConfig, ...] = ()
    _source: str = PrivateAttr(default="scenario")

    @model_serializer(mode="wrap")
    def _dump(self, handler):  # without empty tables: as before the keys existed (study keys)
        return drop_empty_tables(without_empty(handler(self), "supports"))

    @model_validator(mode="before")
    @classmethod
    def _auto_damping(cls, data: Any) -> Any:
        return with_rod_contact_duration(data)

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
            if c.redistribute_mass and not c.law.spec.massless_nodes:
                # a massless node has no velocity of its own (integrate.moreau_jean.massless): under the
                # velocity law its end velocity flips every step, each flip an inelastic
                # impact (-10 % energy at theta = 1/2, -3 % at 0.55: docs/contact_law.md)
                laws = " or ".join(f'law = "{law}"' for law in massless_laws())
                raise problem(
                    f"mass redistribution needs {laws} (a massless "
                    "contact node has no velocity of its own: docs/contact_law.md)",
                    f"contacts[{i}].redistribute_mass",
                )
        _unique_pairs(self.contacts)
        for i, j in enumerate(self.joints):
            _known_body(bodies, j.body, f"joints[{i}].body")
            if j.body2 is not None:
                _known_body(bodies, j.body2, f"joints[{i}].body2")
                if j.body2 == j.body:
                    raise problem(f"must differ from body {j.body!r}", f"joints[{i}].body2")
            if j.type is JointType.DISTANCE and j.length_m is None:
                _check_string_length(j, bodies, f"joints[{i}]")
        check_motion_names(self.joints, self.bodies)
        check_impact_speeds(self.contacts, self.bodies)
        check_supports(self.supports, bodies, self.joints)
        check_load_references(self.loads, self.springs, self.joints, bodies, _known_body)
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
        """Where the scenario came from (a file path, or what made it), named in errors."""
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
        bodies = tuple(
            validate_part(BodyConfig, {**dict(b), **change[b.name]}, source, f"bodies[{k}]")
            if b.name in change
            else b
            for k, b in enumerate(self.bodies)
        )
        return self._copy(what, bodies=bodies)

    def with_model(self, body: str, model: ModelConfig) -> Scenario:
        """A copy with body ``body`` modelled by ``model`` (see :func:`mvm`, :func:`full`,
        :func:`modal`, :func:`rigid`)."""
        if not isinstance(model, ModelConfig):
            raise ScenarioError(
                f"{self._source}: with_model({body!r}, ...) received "
                f"{type(model).__name__}, expected a ModelConfig (flexmvm.mvm(), "
                "flexmvm.full(), ...)"
            )
        return self._replace_bodies(f"body {body} as {model.label}", {body: {"model": model}})

    def with_models(self, model: ModelConfig, *, keep_rigid: bool = True) -> Scenario:
        """A copy with every body (rigid ones kept, unless ``keep_rigid`` is False) modelled
        by ``model``."""
        names = [
            b.name for b in self.bodies if not (keep_rigid and not b.model.kind.spec.has_basis)
        ]
        return self._replace_bodies(
            f"every body as {model.label}", {n: {"model": model} for n in names}
        )

    def with_kind(self, kind: ModelKind | str) -> Scenario:
        """A copy with the model kind of every non-rigid body set to ``kind``, each keeping
        its selection, region, modes and reference (``flexmvm run --model``)."""
        try:
            kind = ModelKind(kind)
        except ValueError:
            raise ScenarioError(
                f"{self._source}: model kind {kind!r}; expected one of "
                f"{', '.join(k.value for k in ModelKind)}"
            ) from None
        what = f"model kind {kind.value}"
        source = f"{self._source} ({what})"
        change = {
            b.name: {
                "model": validate_part(
                    ModelConfig, {**dict(b.model), "kind": kind}, source, f"bodies[{k}].model"
                )
            }
            for k, b in enumerate(self.bodies)
            if b.model.kind.spec.has_basis
        }
        return self._replace_bodies(what, change)

    def with_time(
        self,
        *,
        t_end_s: float | None = None,
        dt_s: float | None = None,
        dt_max_s: float | None = None,
        output_dt_s: float | None = None,
        theta: float | None = None,
        output_contact_dt_s: float | None = None,
        field_output_dt_s: float | None = None,
    ) -> Scenario:
        """A copy with the given time settings replaced [s]. A ``dt_s`` above ``dt_max_s``
        (and no ``dt_max_s`` given) lifts ``dt_max_s`` to it."""
        given = {
            "t_end_s": t_end_s,
            "dt_s": dt_s,
            "dt_max_s": dt_max_s,
            "output_dt_s": output_dt_s,
            "theta": theta,
            "output_contact_dt_s": output_contact_dt_s,
            "field_output_dt_s": field_output_dt_s,
        }
        given = {k: v for k, v in given.items() if v is not None}
        base = dict(self.time)
        if theta is not None:  # a theta given replaces a damping time
            base.pop("hf_damping_time_s", None)
        elif base.get("hf_damping_time_s") is not None:
            base.pop("theta")  # derived again from the (new) dt_s
        if dt_s is not None and dt_max_s is None:
            given["dt_max_s"] = max(self.time.dt_max_s, dt_s)
        what = ", ".join(f"{k}={v!r}" for k, v in given.items())
        time = validate_part(TimeConfig, {**base, **given}, f"{self._source} ({what})", "time")
        return self._copy(what, time=time)

    def with_material(self, body: str, material: Material | str) -> Scenario:
        """A copy with body ``body`` made of ``material`` (a Material, or a preset name)."""
        spec: MaterialSpec | str
        if isinstance(material, Material):
            spec = MaterialSpec(
                E_pa=float(material.E),
                nu=float(material.nu),
                rho_kg_m3=float(material.rho),
                name=material.name,
            )
            label = material.name
        else:
            spec, label = material, material
        return self._replace_bodies(f"body {body} of {label}", {body: {"material": spec}})

    def with_rod(self, body: str, **fields: Any) -> Scenario:
        """A copy with the [bodies.rod] ``fields`` of rod body ``body`` replaced (geometry or
        mesh grading, e.g. ``first_element_m=1.5e-4``)."""
        cfg = self.body(body)
        what = f"body {body} rod {fields}"
        if cfg.rod is None:
            raise ScenarioError(f"{self._source} ({what}): body {body!r} is not a rod")
        rod = validate_part(
            RodConfig,
            {**dict(cfg.rod), **fields},
            f"{self._source} ({what})",
            f"bodies[{self.bodies.index(cfg)}].rod",
        )
        return self._replace_bodies(what, {body: {"rod": rod}})

    def with_tables(self, **tables: Any) -> Scenario:
        """A copy with the given top-level tables replaced (``joints``, ``supports``,
        ``loads``, ``springs``, ``contacts``, ``probes``, ``gravity_mps2``, ...), each given as
        a file gives it or as the tables ``fm.joint``, ``fm.clamp``, ``fm.spring``, ... make;
        validated again as a whole."""
        return self._copy(f"with {', '.join(tables)}", **tables)

    def with_overrides(
        self,
        model: ModelKind | str | None = None,
        t_end_s: float | None = None,
        dt_s: float | None = None,
        body_models: Mapping[str, ModelConfig] | None = None,
    ) -> Scenario:
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


def with_rod_contact_duration(data: Any) -> Any:
    """``data`` with time.contact_duration_s set, for hf_damping_time_s = "auto" without it, to
    the contact duration of the 1D wave-Hertz pulse (theory.scenario.theory_pulse) when the
    scenario is two rods in end impact; unchanged otherwise (TimeConfig then says what is
    missing, or the scenario's own problems are reported)."""
    time = data.get("time") if isinstance(data, dict) else None
    if not isinstance(time, dict) or time.get("hf_damping_time_s") != "auto":
        return data
    if time.get("contact_duration_s") is not None:
        return data
    from flexmvm.theory.scenario import theory_pulse

    plain = {**time}
    plain.pop("hf_damping_time_s")
    try:
        sc = Scenario.model_validate({**data, "time": plain})
        duration = theory_pulse(sc, None)["contact_duration_s"]
    except (ValidationError, InputError):
        return data
    return {**data, "time": {**time, "contact_duration_s": float(duration)}}


def _unique_pairs(contacts) -> None:
    """Each (slave, master) pair built once: a table's own, and its reverse when two_pass."""
    seen: dict[tuple[str, str], str] = {}
    for i, c in enumerate(contacts):
        for k, pair in enumerate(c.pairs):
            where = f"contacts[{i}]" + (" (its two_pass reverse)" if k else "")
            if pair in seen:
                raise problem(
                    f"duplicate contact '{pair[0]} on {pair[1]}' (also {seen[pair]})",
                    f"contacts[{i}]",
                )
            seen[pair] = where


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


def validate_scenario(
    data: Any, source: str, base_dir: Path | None, *, keep_source: str | None = None
) -> Scenario:
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
