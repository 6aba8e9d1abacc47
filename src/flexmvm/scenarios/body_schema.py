"""Scenario tables of one body: material, rod geometry, the model of its deformation (its
constructors fm.full(), fm.mvm(), ...: model_constructors.py), its retained region and its
placement. The scenario as a whole, its contacts, joints, probes and time settings
are in schema.py."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from annotated_types import Ge
from pydantic import (
    Discriminator,
    Strict,
    Tag,
    ValidationInfo,
    field_validator,
    model_serializer,
    model_validator,
)

from flexmvm.bodies.build import ModelKind
from flexmvm.bodies.rotation import axis_angle
from flexmvm.errors import InputError
from flexmvm.materials import PRESETS, Material
from flexmvm.mesh.rod import EndShape, RodSpec
from flexmvm.reduction.interface import InterfaceSpec, ModeChoice
from flexmvm.scenarios.damping_schema import DampingConfig
from flexmvm.scenarios.fields import (
    ROD_FACET_SETS,
    ROD_NODE_SETS,
    ZERO3,
    AngularVelocity,
    Count,
    Frozen,
    Name,
    Num,
    Positive,
    SetName,
    Vec3,
    Velocity,
    check_rod_set,
)
from flexmvm.scenarios.initial_motion import RigidMotionConfig
from flexmvm.scenarios.moving_schema import MovingKey
from flexmvm.scenarios.plasticity_schema import (
    PlasticitySpec,
    PlasticOutside,
    PlasticOutsideKey,
    PlasticTangentKey,
)
from flexmvm.scenarios.problems import problem
from flexmvm.scenarios.stiffening_schema import StiffeningKey

_SELECTION_RE = re.compile(r"^(\d+)-(\d+)$")

#: ``model.reference`` of a mesh_file body that names no set: the builder chooses a 3-2-1
#: support far from the body's contact surfaces (reduction.reference.far_reference).
AUTO_REFERENCE = "auto"


class MaterialSpec(Frozen):
    """Inline material table; ranges checked by :class:`flexmvm.materials.Material`."""

    E_pa: Num
    nu: Num
    rho_kg_m3: Num
    name: Name | None = None
    # J2 plasticity (scenarios/plasticity_schema.py); None: linear elastic
    plasticity: PlasticitySpec | None = None

    @model_serializer(mode="wrap")
    def _dump(self, handler):
        # an elastic material dumps as before the key existed (cache and study keys hash it)
        data = handler(self)
        if isinstance(data, dict) and data.get("plasticity", 0) is None:
            data.pop("plasticity")
        return data

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
    use them (full, rigid; modal ignores selection/region) so that a kind override stays valid.
    The ``patch_*``/``mode_*`` keys are the interface kind's (reduction/interface.py): Hertz
    patch radii [m] (one static patch vector each) about the expected contact point
    (``patch_centre_m``, default the centre of facet set ``patch_surface``), and how its
    ``modes`` are chosen from a pool of free-free modes; the other kinds ignore them."""

    kind: ModelKind = ModelKind.FULL
    selection: str | None = None
    region: RegionSpec | None = None
    modes: Annotated[int, Strict(), Ge(0)] = 0
    reference: SetName = "end_b"
    patch_radii_m: tuple[Positive, ...] = ()
    patch_surface: SetName = "end_a"
    patch_centre_m: Vec3 | None = None
    mode_choice: ModeChoice = ModeChoice.PARTICIPATION
    mode_pool: Count | None = None
    # build a reduced body even when its dense matrices would take more memory than the
    # full-FE body's sparse ones (assembly.cost; refused by default)
    allow_costly: bool = False
    geometric_stiffening: StiffeningKey = None  # stiffening_schema.py; a rigid kind ignores it
    # a plastic body (material.plasticity): its Newton matrix while it yields, the elastic W
    # (False) or the consistent tangent W_t (True; integrate/moreau_jean/plastic_tangent.py), and what a
    # reduced body does when cells outside its retained region reach yield: "warn" (the run
    # goes on, elastic there, and says so) or "stop" (the run fails there, keeping what it
    # computed); an elastic body ignores both
    plastic_tangent: PlasticTangentKey = False
    plastic_outside: PlasticOutsideKey = PlasticOutside.WARN
    # the windows of a moving region (kind mvm-moving; scenarios/moving_schema.py)
    moving: MovingKey = None

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
        if self.kind.retains_nodes and self.retained is None and not self.moves:
            raise problem(f"kind {kind!r} needs selection = 'i-j' or a region", "selection")
        if self.kind.uses_modes and self.modes < 1:
            raise problem(f"must be >= 1 for kind {kind!r}, got {self.modes}", "modes")
        if self.kind.spec.uses_patches:
            radii = self.patch_radii_m
            if self.modes + len(radii) < 1:
                raise problem(
                    f"kind {kind!r} needs modes >= 1 or at least one patch radius",
                    "patch_radii_m",
                )
            if len(set(radii)) != len(radii):
                raise problem(f"must be distinct radii [m], got {list(radii)}", "patch_radii_m")
            if self.mode_pool is not None and self.mode_pool < self.modes:
                raise problem(f"must be >= modes = {self.modes}, got {self.mode_pool}", "mode_pool")
        return self

    @property
    def moves(self) -> bool:
        """A moving region: kind mvm-moving with its windows (``moving``) given."""
        return self.kind.value == "mvm-moving" and self.moving is not None

    def interface_spec(self) -> InterfaceSpec:
        """The reduction.interface.InterfaceSpec of the interface kind's keys."""
        return InterfaceSpec(
            self.patch_surface,
            self.patch_centre_m,
            tuple(float(a) for a in self.patch_radii_m),
            ModeChoice(self.mode_choice),
            self.mode_pool,
        )

    @property
    def label(self) -> str:
        """Short description: 'full', 'rigid', 'modal 20', 'mvm 1-3 + 25', 'mvm-seed 1-1 + 37'."""
        if self.kind.spec.uses_patches:
            radii = ", ".join(f"{1e3 * a:g}" for a in self.patch_radii_m)
            patch = f" patch [{radii}] mm" if radii else ""
            return f"{self.kind.value}{patch} + {self.modes} {ModeChoice(self.mode_choice).value}"
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
    velocity_mps: Velocity = ZERO3
    angular_velocity_radps: AngularVelocity = ZERO3
    # start in the quasi-static sag on the body's joints under gravity (at rest; assembly/sag.py)
    sagged: Annotated[bool, Strict()] = False
    # the initial motion about a point instead (scenarios/initial_motion.py)
    rigid_motion: RigidMotionConfig | None = None

    @model_serializer(mode="wrap")
    def _dump(self, handler):
        # without rigid_motion a dump is as before the key existed (study keys and cache
        # identities hash these dumps)
        data = handler(self)
        if isinstance(data, dict) and data.get("rigid_motion") is None:
            data.pop("rigid_motion", None)
        return data

    @model_validator(mode="after")
    def _one_motion(self) -> Placement:
        # non-zero ones only: a dump of the placement carries both at their defaults
        given = {k for k in ("velocity_mps", "angular_velocity_radps") if any(getattr(self, k))}
        if self.rigid_motion is not None and given:
            raise problem(f"give the motion by rigid_motion or by {min(given)}, not both")
        return self

    def to_global(self, point_m: tuple[float, float, float]) -> np.ndarray:
        """Initial global position (3,) of a body-local point [m]."""
        return np.asarray(self.position_m) + self.rotation.matrix() @ np.asarray(point_m)


class BodyConfig(Frozen):
    name: Name
    material: MaterialRef
    rod: RodConfig | None = None
    mesh_file: Path | None = None
    # merge the mesh file's coincident nodes (mesh/connectivity.py) instead of refusing them
    merge_nodes: bool = False
    model: ModelConfig = ModelConfig()
    placement: Placement = Placement()
    # structural damping (damping_schema.py); None: undamped
    damping: DampingConfig | None = None

    @model_serializer(mode="wrap")
    def _dump(self, handler):
        # an undamped body dumps as before the key existed (study keys hash these dumps);
        # so does one whose mesh nodes are not merged
        data = handler(self)
        if isinstance(data, dict) and data.get("damping") is None:
            data.pop("damping", None)
        if isinstance(data, dict) and data.get("merge_nodes") is False:
            data.pop("merge_nodes", None)
        return data

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

    @model_validator(mode="before")
    @classmethod
    def _default_reference(cls, data: Any) -> Any:
        """A mesh_file body's model without a ``reference`` gets AUTO_REFERENCE (a 3-2-1
        support far from its contacts, chosen by the builder); a rod's keeps ModelConfig's
        default, end_b (so the dumps, and the study keys made of them, of rod scenarios do not
        change)."""
        if (
            not isinstance(data, dict)
            or data.get("mesh_file") is None
            or data.get("rod") is not None
        ):
            return data
        model = data.get("model")
        if model is None:
            return {**data, "model": {"reference": AUTO_REFERENCE}}
        if isinstance(model, dict) and "reference" not in model:
            return {**data, "model": {**model, "reference": AUTO_REFERENCE}}
        if isinstance(model, ModelConfig) and "reference" not in model.model_fields_set:
            return {**data, "model": model.model_copy(update={"reference": AUTO_REFERENCE})}
        return data

    @model_validator(mode="after")
    def _check(self) -> BodyConfig:
        if (self.rod is None) == (self.mesh_file is None):
            raise problem("needs exactly one of [bodies.rod] or mesh_file", "rod")
        if self.merge_nodes and self.mesh_file is None:
            raise problem("merge_nodes applies to a mesh_file body's mesh", "merge_nodes")
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
            if self.model.kind.spec.uses_patches:
                check_rod_set(self.model.patch_surface, ROD_FACET_SETS, "model.patch_surface")
        kind = self.model.kind
        if self.damping is not None and not kind.spec.has_basis:
            raise problem("a rigid body has no elastic coordinates to damp", "damping")
        if self.damping is not None and self.damping.is_modal and not kind.spec.reads_modes:
            raise problem(
                f"modal ratios need a reduced body (kind {kind.value} has no modes): give "
                "alpha_per_s/beta_s or rayleigh_ratios",
                "damping.modal_ratios",
            )
        n = len(self.damping.modal_ratios or ()) if self.damping is not None else 0
        if n > 1 and n != self.model.modes:
            raise problem(
                f"{n} ratios for {self.model.modes} modes; expected one or one per mode",
                "damping.modal_ratios",
            )
        return self

    def damping_obj(self):
        """The bodies.damping form of the damping table, or None (undamped)."""
        return None if self.damping is None else self.damping.damping()

    def material_obj(self) -> Material:
        """The material as a flexmvm.materials.Material."""
        if isinstance(self.material, str):
            return PRESETS[self.material]
        m = self.material
        return Material(E=m.E_pa, nu=m.nu, rho=m.rho_kg_m3, name=m.name or self.name)
