"""The ``plasticity`` table of an inline material (J2, von Mises: flexmvm.plasticity) and the
one-line refusal of a dynamic run whose bodies carry it (static solves only, for now)."""

from __future__ import annotations

from typing import Annotated

from annotated_types import Ge

from flexmvm.errors import InputError
from flexmvm.plasticity.material import J2Plasticity
from flexmvm.scenarios.fields import Frozen, Num, Positive

NonNegative = Annotated[Num, Ge(0.0)]


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
    spec = getattr(body.material, "plasticity", None)
    return None if spec is None else spec.obj()


def refuse_dynamic(scenario) -> None:
    """InputError (one line) if a body of ``scenario`` is plastic: the time stepping carries
    the elastic stiffness only; the static solver (flexmvm.plasticity.solve_static) is the one
    that takes plasticity so far."""
    plastic = [b.name for b in scenario.bodies if plasticity_of(b) is not None]
    if plastic:
        raise InputError(
            f"{'body' if len(plastic) == 1 else 'bodies'} {', '.join(repr(n) for n in plastic)}: "
            "material.plasticity is not "
            "supported by the dynamic run yet (static solves only: flexmvm.plasticity."
            "solve_static); remove the plasticity table to run the elastic model"
        )
