"""The constructors of a body's model block: :func:`full`, :func:`rigid`, :func:`modal`,
:func:`interface` and :func:`mvm` (fm.full(), fm.mvm("1-3", 25), ...), each a validated
ModelConfig (scenarios/body_schema.py)."""

from __future__ import annotations

from flexmvm.bodies.build import ModelKind
from flexmvm.scenarios.body_schema import ModelConfig, RegionSpec
from flexmvm.scenarios.problems import validate_part


def _given(reference: str | None) -> dict[str, str]:
    """The reference key of a constructor: none when not given, so that the body decides
    (end_b for a rod, auto for a mesh_file body: BodyConfig._default_reference)."""
    return {} if reference is None else {"reference": reference}


def full(reference: str | None = None) -> ModelConfig:
    """Full FE model: every nodal DOF but the reference condition's six."""
    return validate_part(ModelConfig, {"kind": ModelKind.FULL, **_given(reference)}, "full()")


def rigid() -> ModelConfig:
    """Rigid body: no elastic coordinates."""
    return validate_part(ModelConfig, {"kind": ModelKind.RIGID}, "rigid()")


def modal(modes: int, reference: str | None = None) -> ModelConfig:
    """The first ``modes`` modes of the body supported by its reference condition."""
    return validate_part(
        ModelConfig,
        {"kind": ModelKind.MODAL, "modes": modes, **_given(reference)},
        f"modal({modes!r})",
    )


def interface(
    patch_radii_m=(),
    modes: int = 0,
    *,
    mode_choice: str = "participation",
    patch_surface: str = "end_a",
    patch_centre_m=None,
    mode_pool: int | None = None,
    reference: str | None = None,
) -> ModelConfig:
    """Interface model (reduction/interface.py): one static Hertz-patch vector per radius in
    ``patch_radii_m`` [m] about the centre of ``patch_surface`` (or ``patch_centre_m``), plus
    ``modes`` free-free modes chosen by ``mode_choice`` (participation or frequency)."""
    data = {
        "kind": ModelKind.INTERFACE,
        "patch_radii_m": tuple(patch_radii_m),
        "modes": modes,
        "mode_choice": mode_choice,
        "patch_surface": patch_surface,
        "patch_centre_m": patch_centre_m,
        "mode_pool": mode_pool,
        **_given(reference),
    }
    return validate_part(ModelConfig, data, f"interface({list(patch_radii_m)!r}, modes={modes!r})")


def mvm(
    selection: str | tuple[int, int] | None = None,
    modes: int = 0,
    *,
    region: RegionSpec | None = None,
    reference: str | None = None,
    seed_eq4: bool = False,
    kind: ModelKind | None = None,
) -> ModelConfig:
    """MVM model: the nodes of ``selection`` (the seed's layers-laps 'i-j' or (i, j)) or of
    ``region`` kept as nodal coordinates, plus ``modes`` modes: Craig-Bampton fixed-interface
    modes, or with ``seed_eq4`` the seed's eq. (4) block basis; ``kind`` names any model kind
    that retains nodes (mvm, mvm-seed, mvm-seed-fixed) instead."""
    if isinstance(selection, tuple):
        selection = "-".join(str(int(v)) for v in selection)
    if kind is None:
        kind = ModelKind.MVM_SEED if seed_eq4 else ModelKind.MVM
    data = {
        "kind": kind,
        "selection": selection,
        "region": region,
        "modes": modes,
        **_given(reference),
    }
    return validate_part(ModelConfig, data, f"mvm({selection!r}, modes={modes!r})")
