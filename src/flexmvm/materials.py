"""Isotropic linear-elastic materials (SI units)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from flexmvm.errors import InputError

#: Largest Poisson ratio accepted. flexmvm's elements (tet4, tet10, hex8, wedge6, hex27) are
#: displacement-based, with no mixed u-p formulation: as nu -> 0.5 the bulk modulus grows
#: without bound against the shear modulus (K/G = 2(1 + nu) / (3(1 - 2 nu)): 8.3 at 0.4,
#: 49.7 at 0.49, 5000 at 0.4999) and the elements lock volumetrically, linear tet4 worst
#: (issue 48: nu = 0.4999 changed a tet4 block's contact force by 58 %). 0.49 keeps the
#: plastic thick-cylinder check's value (tests/test_plastic_cylinder.py, hex27).
MAX_NU = 0.49


@dataclass(frozen=True)
class Material:
    """Isotropic linear-elastic material.

    E: Young's modulus [Pa], nu: Poisson ratio [-], rho: density [kg/m^3].
    Raises InputError unless E > 0, rho > 0 and -1 < nu <= MAX_NU = 0.49 (a Poisson ratio
    in (0.49, 0.5) is physical but locks the displacement-based elements: see MAX_NU).
    """

    E: float
    nu: float
    rho: float
    name: str = "material"

    def __post_init__(self) -> None:
        for key, val in (("E", self.E), ("nu", self.nu), ("rho", self.rho)):
            if isinstance(val, bool) or not isinstance(val, (int, float)) or not math.isfinite(val):
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
        if self.nu > MAX_NU:
            ratio = 2 * (1 + self.nu) / (3 * (1 - 2 * self.nu))
            raise InputError(
                f"material {self.name!r}: Poisson ratio nu = {self.nu!r} is nearly "
                f"incompressible (bulk/shear modulus {ratio:.0f}); expected nu <= {MAX_NU}: the "
                f"displacement-based elements lock (tet4 worst), so the forces would be wrong"
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
