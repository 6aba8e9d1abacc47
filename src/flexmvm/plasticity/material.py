"""The plastic part of a J2 (von Mises) material with linear hardening (SI units).

The elastic constants stay in :class:`flexmvm.materials.Material`; this adds the yield
stress and the two linear hardening moduli of Simo and Hughes (1998, *Computational
Inelasticity*, sect. 2.3 and box 3.2):

    f(sigma, alpha, beta) = ||dev sigma - beta|| - sqrt(2/3) (Y + H_iso alpha)
    beta_dot = 2/3 H_kin gamma_dot n,        alpha_dot = sqrt(2/3) gamma_dot

so that in uniaxial tension the plastic modulus is H = H_iso + H_kin and the tangent slope
past yield is E H / (E + H).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from flexmvm.errors import InputError


@dataclass(frozen=True)
class J2Plasticity:
    """Yield stress and linear hardening of a von Mises material.

    yield_pa: initial uniaxial yield stress Y [Pa], > 0; hardening_pa: isotropic hardening
    modulus H_iso [Pa], >= 0 (0: perfectly plastic); kinematic_hardening_pa: linear
    kinematic (Prager) modulus H_kin [Pa], >= 0. Raises InputError otherwise.
    """

    yield_pa: float
    hardening_pa: float = 0.0
    kinematic_hardening_pa: float = 0.0

    def __post_init__(self) -> None:
        for key, val in (
            ("yield_pa", self.yield_pa),
            ("hardening_pa", self.hardening_pa),
            ("kinematic_hardening_pa", self.kinematic_hardening_pa),
        ):
            if isinstance(val, bool) or not isinstance(val, (int, float)):
                raise InputError(f"plasticity: {key} must be a number [Pa], got {val!r}")
            if not math.isfinite(val):
                raise InputError(f"plasticity: {key} must be finite [Pa], got {val!r}")
        if self.yield_pa <= 0:
            raise InputError(f"plasticity: yield_pa must be > 0 Pa, got {self.yield_pa!r}")
        if self.hardening_pa < 0:
            raise InputError(f"plasticity: hardening_pa must be >= 0 Pa, got {self.hardening_pa!r}")
        if self.kinematic_hardening_pa < 0:
            raise InputError(
                "plasticity: kinematic_hardening_pa must be >= 0 Pa, "
                f"got {self.kinematic_hardening_pa!r}"
            )

    @property
    def plastic_modulus(self) -> float:
        """H = H_iso + H_kin [Pa]: the uniaxial plastic modulus d sigma / d eps_p."""
        return self.hardening_pa + self.kinematic_hardening_pa
