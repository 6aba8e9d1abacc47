"""The model kinds: the one ModelKind enum and the registry KINDS of their specs.

Each kind is one object (a ModelKindSpec, kinds/spec.py) that holds everything about it: its
properties (retains nodes, uses modes, ...), how it builds its basis, its cost estimate, its
cache-key and damping hooks and its study text. Code that needs a property of a kind asks
``kind_spec(kind)`` instead of comparing kinds. The built-in kinds are registered by
reduction/kinds/__init__.py, one line each; ``register_kind(spec)`` adds another (a new member
of ModelKind is made for a new name).
"""

from __future__ import annotations

from enum import StrEnum
from typing import TYPE_CHECKING

from flexmvm.enum_registry import member_of, register, unregister
from flexmvm.errors import InputError

if TYPE_CHECKING:
    from flexmvm.reduction.kinds.spec import ModelKindSpec


class ModelKind(StrEnum):
    """How a body's deformation is represented (DESIGN.md, Bodies); values: the scenario
    file's ``model.kind``, ``flexmvm run --model`` and the setup cache's keys. The names
    CRAIG_BAMPTON, SEED_BLOCK and SEED_FIXED are aliases of MVM, MVM_SEED and MVM_SEED_FIXED
    (the former BasisKind's names; BasisKind: the kinds with a basis)."""

    FULL = "full"  # all nodal DOFs (reference solution)
    MVM = "mvm"  # Craig-Bampton: retained nodes + fixed-interface modes (default MVM)
    MVM_SEED = "mvm-seed"  # seed eq. (4): modes on region I, nodal DOFs on region II
    MVM_SEED_FIXED = "mvm-seed-fixed"  # seed eq. (4) with region-I modes of region II held
    MODAL = "modal"  # first N modes of the reference-supported body
    INTERFACE = "interface"  # Hertz contact-patch Ritz vectors + modes by participation
    RIGID = "rigid"  # no elastic coordinates
    CRAIG_BAMPTON = "mvm"
    SEED_BLOCK = "mvm-seed"
    SEED_FIXED = "mvm-seed-fixed"

    @property
    def spec(self) -> ModelKindSpec:
        """This kind's registered spec (KINDS)."""
        return KINDS[self]

    @property
    def basis(self) -> ModelKind | None:
        """The kind of this model's basis: itself (None: rigid, no elastic coordinates)."""
        return self if KINDS[self].has_basis else None

    @property
    def retains_nodes(self) -> bool:
        """Keeps a node selection (region II) beside its modes: the MVM kinds."""
        return KINDS[self].retains_nodes

    @property
    def reduced(self) -> bool:
        """Elastic and not full FE: a body whose run a full-FE reference checks."""
        spec = KINDS[self]
        return spec.has_basis and not spec.nodal

    @property
    def uses_modes(self) -> bool:
        """Has a mode count (>= 1): the MVM kinds and the modal model."""
        return KINDS[self].uses_modes


#: The registered kinds, in registration order (the built-in ones: reduction/kinds/__init__.py).
KINDS: dict[ModelKind, ModelKindSpec] = {}


def register_kind(spec: ModelKindSpec) -> ModelKind:
    """Register ``spec`` under its name (``spec.name``, the scenario file's ``model.kind``)
    and return its ModelKind, made for a name not in ModelKind yet (its member name: the
    name in upper case, dashes as underscores). InputError for a name already registered."""
    return register(ModelKind, KINDS, spec, "model kind")


def unregister_kind(name: str) -> None:
    """Remove a kind registered by register_kind that is not built in (a test's toy kind):
    its spec and its ModelKind member."""
    unregister(ModelKind, KINDS, name, _BUILT_IN, "model kind")


_BUILT_IN = frozenset(k.value for k in ModelKind)


class _KindsWithBasis(type):
    """BasisKind's class behaviour: ModelKind's members by name (aliases included), iterated
    and tested over the registered kinds that have a basis (every kind but rigid)."""

    def __getattr__(cls, name: str) -> ModelKind:
        try:
            return ModelKind[name]
        except KeyError:
            raise AttributeError(name) from None

    def __iter__(cls):
        return iter([k for k, spec in KINDS.items() if spec.has_basis])

    def __len__(cls) -> int:
        return len(list(iter(cls)))

    def __instancecheck__(cls, obj) -> bool:
        return isinstance(obj, ModelKind) and obj in KINDS and KINDS[obj].has_basis

    def __call__(cls, value) -> ModelKind:
        kind = ModelKind(value)
        if kind not in cls:
            raise ValueError(f"{value!r} is not a basis kind")
        return kind

    def __contains__(cls, obj) -> bool:
        return isinstance(obj, cls)


class BasisKind(metaclass=_KindsWithBasis):
    """The kinds that have a reduction basis: ModelKind's members but RIGID (BasisKind.MVM is
    ModelKind.MVM, BasisKind.CRAIG_BAMPTON its alias), not an enum of their own."""


def kind_spec(kind: ModelKind | str) -> ModelKindSpec:
    """The spec of ``kind`` (a ModelKind or its name); InputError naming the kinds for an
    unknown one."""
    spec = KINDS.get(member_of(ModelKind, kind))  # type: ignore[arg-type]
    if spec is None:
        known = ", ".join(k.value for k in KINDS)
        raise InputError(f"model kind {kind!r}: expected one of {known}")
    return spec
