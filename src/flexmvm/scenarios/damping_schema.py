"""The ``[bodies.damping]`` table (pydantic v2): a body's structural damping, in one of three
forms (bodies.damping forms c_hat from it):

- Rayleigh, ``alpha_per_s`` [1/s] and ``beta_s`` [s]: C = alpha M + beta K, every model kind
  (a reduced body's c_hat is the projection of the full body's);
- Rayleigh through two points of its ratio curve, ``rayleigh_ratios = [[f1_hz, zeta1],
  [f2_hz, zeta2]]`` (bodies.damping.rayleigh_from_ratios);
- ``modal_ratios``: damping ratios of a reduced body's modes, one for all or one per mode
  (ascending frequency); the retained coordinates undamped.

A table of the body, not of its model or material: it stays when a study or ``flexmvm run
--model`` swaps the body's model (a full-FE reference and its reduced copies are damped alike,
which is what makes Rayleigh damping consistent between them), and a material preset stays a
material. Modal ratios need modes: refused for full-FE and rigid bodies (BodyConfig).
"""

from __future__ import annotations

from typing import Annotated

from annotated_types import Ge
from pydantic import Strict, model_validator

from flexmvm.bodies.damping import (
    Damping,
    ModalDamping,
    RayleighDamping,
    rayleigh_from_ratios,
)
from flexmvm.errors import InputError
from flexmvm.scenarios.fields import Frozen, Positive
from flexmvm.scenarios.problems import problem

Ratio = Annotated[float, Strict(), Ge(0.0)]
NonNegative = Annotated[float, Strict(), Ge(0.0)]


class DampingConfig(Frozen):
    """Exactly one form: alpha_per_s and/or beta_s, rayleigh_ratios, or modal_ratios."""

    alpha_per_s: NonNegative | None = None
    beta_s: NonNegative | None = None
    rayleigh_ratios: tuple[tuple[Positive, Ratio], tuple[Positive, Ratio]] | None = None
    modal_ratios: tuple[Ratio, ...] | None = None

    @model_validator(mode="after")
    def _check(self) -> DampingConfig:
        rayleigh = self.alpha_per_s is not None or self.beta_s is not None
        given = [
            name
            for name, on in (
                ("alpha_per_s/beta_s", rayleigh),
                ("rayleigh_ratios", self.rayleigh_ratios is not None),
                ("modal_ratios", self.modal_ratios is not None),
            )
            if on
        ]
        if len(given) != 1:
            raise problem(
                "needs exactly one of alpha_per_s/beta_s, rayleigh_ratios, modal_ratios, "
                f"got {given or 'none'}"
            )
        if self.modal_ratios is not None and not self.modal_ratios:
            raise problem("must hold at least one ratio", "modal_ratios")
        if self.rayleigh_ratios is not None:
            try:
                self.damping()
            except InputError as exc:
                raise problem(str(exc).split(": ", 1)[-1], "rayleigh_ratios") from None
        return self

    @property
    def is_modal(self) -> bool:
        return self.modal_ratios is not None

    def damping(self) -> Damping:
        """The bodies.damping form of this table."""
        if self.modal_ratios is not None:
            return ModalDamping(tuple(self.modal_ratios))
        if self.rayleigh_ratios is not None:
            (f1, z1), (f2, z2) = self.rayleigh_ratios
            return rayleigh_from_ratios(f1, z1, f2, z2)
        return RayleighDamping(self.alpha_per_s or 0.0, self.beta_s or 0.0)


__all__ = ["DampingConfig"]
