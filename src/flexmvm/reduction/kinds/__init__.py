"""The model kinds, one module each, and their registry (registry.py: ModelKind, KINDS,
register_kind, kind_spec; what a kind declares: spec.py ModelKindSpec).

A new kind is one new module here holding its spec object ``SPEC`` (a KindSpec subclass: its
name, properties, basis builder and hooks) and one line below registering it; nothing else
names it (docs/architecture.md, "Where a change goes")."""

from flexmvm.reduction.kinds import (
    full,
    interface,
    modal,
    mvm,
    mvm_moving,
    mvm_seed,
    mvm_seed_fixed,
    mvm_sparse,
    rigid,
)
from flexmvm.reduction.kinds.registry import (
    KINDS,
    ModelKind,
    kind_spec,
    register_kind,
    unregister_kind,
)
from flexmvm.reduction.kinds.spec import Basis, BasisRequest, KindSpec, ModelKindSpec

register_kind(full.SPEC)
register_kind(mvm.SPEC)
register_kind(mvm_sparse.SPEC)
register_kind(mvm_seed.SPEC)
register_kind(mvm_seed_fixed.SPEC)
register_kind(modal.SPEC)
register_kind(interface.SPEC)
register_kind(rigid.SPEC)
register_kind(mvm_moving.SPEC)

__all__ = [
    "KINDS",
    "Basis",
    "BasisRequest",
    "KindSpec",
    "ModelKind",
    "ModelKindSpec",
    "kind_spec",
    "register_kind",
    "unregister_kind",
]
