"""The rigid body (kind ``rigid``): no elastic coordinates, no basis, no reference condition;
its body carries the FE model's mass distribution (bodies.build.rigid_body_from_fe)."""

from __future__ import annotations

from dataclasses import dataclass

from flexmvm.reduction.kinds.registry import ModelKind
from flexmvm.reduction.kinds.spec import KindSpec


@dataclass(frozen=True)
class Rigid(KindSpec):
    name: str = ModelKind.RIGID.value
    has_basis: bool = False
    clampable: bool = False


SPEC = Rigid()
