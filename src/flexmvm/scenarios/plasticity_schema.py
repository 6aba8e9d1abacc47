"""The ``plasticity`` table of an inline material (J2, von Mises: flexmvm.plasticity) and the
one-line refusal of the bodies the dynamic run cannot make plastic yet (reduced, modal, rigid).
The plastic parts of a built scenario: assembly/plastic_parts.py."""

from __future__ import annotations

from enum import StrEnum
from typing import Annotated

from annotated_types import Ge
from pydantic import Field

from flexmvm.errors import InputError
from flexmvm.plasticity.material import J2Plasticity
from flexmvm.scenarios.fields import Frozen, Num, Positive

NonNegative = Annotated[Num, Ge(0.0)]


class PlasticOutside(StrEnum):
    """A reduced plastic body whose cells outside its retained region reach yield
    (``plastic_outside``): the run says so and goes on, or fails there."""

    WARN = "warn"
    STOP = "stop"


# [bodies.model] keys of a plastic body, left out of a dump at their defaults: the dumps (and the
# cache and study keys that hash them) are those of before the keys existed
PlasticTangentKey = Annotated[bool, Field(exclude_if=lambda value: value is False)]
PlasticOutsideKey = Annotated[
    PlasticOutside, Field(exclude_if=lambda value: value is PlasticOutside.WARN)
]


class PlasticitySpec(Frozen):
    """``plasticity = {yield_pa = ..., hardening_pa = ..., kinematic_hardening_pa = ...}``:
    initial yield stress Y > 0 [Pa], linear isotropic hardening modulus H_iso >= 0 [Pa]
    (default 0: perfectly plastic), linear kinematic modulus H_kin >= 0 [Pa] (default 0)."""

    yield_pa: Positive
    hardening_pa: NonNegative = 0.0
    kinematic_hardening_pa: NonNegative = 0.0

    def obj(self) -> J2Plasticity:
        """The plastic part as a flexmvm.plasticity.J2Plasticity."""
        return J2Plasticity(self.yield_pa, self.hardening_pa, self.kinematic_hardening_pa)


def plasticity_of(body) -> J2Plasticity | None:
    """The plasticity of a scenario body (a BodyConfig), None for an elastic one."""
    material = body.material  # a preset's name (elastic) or an inline MaterialSpec
    spec = None if isinstance(material, str) else material.plasticity
    return None if spec is None else spec.obj()


def refuse_dynamic(scenario) -> None:
    """InputError (one line) if a plastic body of ``scenario`` is neither full FE nor of a
    kind that retains nodes (MVM: plastic in its retained region; interface, modal and rigid
    bodies carry the elastic stiffness only) or has redistributed contact mass."""
    plastic = [b for b in scenario.bodies if plasticity_of(b) is not None]
    other = [b.name for b in plastic if not (b.model.kind.spec.nodal or b.model.kind.retains_nodes)]
    if other:
        raise InputError(
            f"{'body' if len(other) == 1 else 'bodies'} {', '.join(repr(n) for n in other)}: "
            'material.plasticity is supported by the dynamic run for model.kind = "full" '
            "and the MVM kinds only (static solves: flexmvm.plasticity.solve_static); use one "
            "of them or remove the plasticity table"
        )
    names = {b.name for b in plastic}
    for k, c in enumerate(scenario.contacts):
        if c.redistribute_mass and names & {c.slave_body, c.master_body}:
            raise InputError(
                f"contacts[{k}]: redistribute_mass cannot be used with a plastic body "
                f"({', '.join(sorted(names & {c.slave_body, c.master_body}))})"
            )
