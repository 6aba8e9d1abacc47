"""Isotropic linear-elastic materials (SI units)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from flexmvm.errors import InputError


@dataclass(frozen=True)
class Material:
    """Isotropic linear-elastic material.

    E: Young's modulus [Pa], nu: Poisson ratio [-], rho: density [kg/m^3].
    Raises InputError unless E > 0, rho > 0 and -1 < nu < 0.5.
    """

    E: float
    nu: float
    rho: float
    name: str = "material"

    def __post_init__(self) -> None:
        for key, val in (("E", self.E), ("nu", self.nu), ("rho", self.rho)):
            if not isinstance(val, (int, float)) or not math.isfinite(val):
                raise InputError(
                    f"material {self.name!r}: {key} must be a finite number, got {val!r}"
                )
        if self.E <= 0:
            raise InputError(
                f"material {self.name!r}: Young's modulus E must be > 0 Pa, got {self.E!r}"
            )
        if self.rho <= 0:
            raise InputError(
                f"material {self.name!r}: density rho must be > 0 kg/m^3, got {self.rho!r}"
            )
        if not -1.0 < self.nu < 0.5:
            raise InputError(
                f"material {self.name!r}: Poisson ratio nu must be in (-1, 0.5), got {self.nu!r}"
            )

    @property
    def bar_wave_speed(self) -> float:
        """Longitudinal bar wave speed c = sqrt(E / rho) [m/s]."""
        return math.sqrt(self.E / self.rho)

    @property
    def lame(self) -> tuple[float, float]:
        """Lame parameters (lambda, mu) [Pa]."""
        lam = self.E * self.nu / ((1 + self.nu) * (1 - 2 * self.nu))
        mu = self.E / (2 * (1 + self.nu))
        return lam, mu


# Seed table 1 and table 2 (Wang, Hong, Liu 2014).
BRASS = Material(E=96.5e9, nu=0.36, rho=8390.0, name="brass")
ALUMINIUM = Material(E=72.71e9, nu=0.33, rho=2700.0, name="aluminium")
TUNGSTEN = Material(E=344.70e9, nu=0.28, rho=19250.0, name="tungsten")
COPPER = Material(E=96.50e9, nu=0.36, rho=8390.0, name="copper")
PA6 = Material(E=2.32e9, nu=0.34, rho=1140.0, name="pa6")

PRESETS: dict[str, Material] = {m.name: m for m in (BRASS, ALUMINIUM, TUNGSTEN, COPPER, PA6)} | {
    "al": ALUMINIUM,
    "cu": COPPER,
    "w": TUNGSTEN,
}
