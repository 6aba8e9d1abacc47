"""Thick-walled cylinder under internal pressure in plane strain, von Mises material,
elastic-perfectly plastic (Hill 1950, *The Mathematical Theory of Plasticity*, ch. V;
Chakrabarty 2006, *Theory of Plasticity*, sect. 5.3).

Inner radius a, outer radius b [m], yield stress Y [Pa], Poisson ratio nu. Elastic (Lame):
sigma_r = A - B / r^2, sigma_theta = A + B / r^2, sigma_z = 2 nu A, with A = p a^2 /
(b^2 - a^2), B = A b^2, so that the von Mises stress is

    sigma_vm(r)^2 = 3 B^2 / r^4 + (1 - 2 nu)^2 A^2                      (exact, any nu)

and yield starts at the bore at p_y = Y (b^2 - a^2) / sqrt(3 b^4 + (1 - 2 nu)^2 a^4). With a
plastic zone a < r < c and the incompressible approximation sigma_z = (sigma_r +
sigma_theta) / 2 there (exact for nu = 1/2; Hill's closed form), sigma_theta - sigma_r =
2 Y / sqrt3 in the zone and

    p(c) = (2 Y / sqrt3) [ln(c / a) + (1 - c^2 / b^2) / 2]

up to the limit pressure p(b) = (2 Y / sqrt3) ln(b / a).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from flexmvm.errors import InputError
from flexmvm.theory.hertz import positive


def _radii(a: float, b: float) -> tuple[float, float]:
    a, b = positive("inner radius a", a), positive("outer radius b", b)
    if not a < b:
        raise InputError(f"thick cylinder: need inner radius a < outer radius b, got {a!r}, {b!r}")
    return a, b


def elastic_von_mises(r: float, p: float, a: float, b: float, nu: float) -> float:
    """Von Mises stress [Pa] at radius r of the elastic plane-strain cylinder at pressure p."""
    a, b = _radii(a, b)
    big_a = p * a * a / (b * b - a * a)
    big_b = big_a * b * b
    return math.sqrt(3.0 * big_b**2 / r**4 + ((1.0 - 2.0 * nu) * big_a) ** 2)


def first_yield_pressure(a: float, b: float, yield_pa: float, nu: float) -> float:
    """Pressure [Pa] at which the bore yields (exact for the elastic plane-strain cylinder)."""
    a, b = _radii(a, b)
    y = positive("yield_pa", yield_pa)
    return y * (b * b - a * a) / math.sqrt(3.0 * b**4 + ((1.0 - 2.0 * nu) * a * a) ** 2)


def hill_pressure(c: float, a: float, b: float, yield_pa: float) -> float:
    """Hill's pressure [Pa] for the elastic-plastic radius c in [a, b] (incompressible)."""
    a, b = _radii(a, b)
    y = positive("yield_pa", yield_pa)
    if not a <= c <= b:
        raise InputError(f"thick cylinder: plastic radius must be in [{a!r}, {b!r}] m, got {c!r}")
    return 2.0 * y / math.sqrt(3.0) * (math.log(c / a) + 0.5 * (1.0 - (c / b) ** 2))


def plastic_radius(p: float, a: float, b: float, yield_pa: float) -> float:
    """Hill's elastic-plastic radius c [m] at pressure p, between his first-yield pressure
    p(a) = Y (1 - a^2/b^2) / sqrt3 and the limit pressure p(b); InputError outside."""
    lo, hi = hill_pressure(a, a, b, yield_pa), hill_pressure(b, a, b, yield_pa)
    if not lo <= p <= hi:
        raise InputError(
            f"thick cylinder: pressure must be in [{lo:.6g}, {hi:.6g}] Pa for a plastic zone "
            f"inside the wall, got {p!r}"
        )
    return brentq(lambda c: hill_pressure(c, a, b, yield_pa) - p, a, b, xtol=1e-15 * b)


def radius_from_elastic_zone(r, von_mises, b: float, yield_pa: float, nu: float) -> float:
    """The elastic-plastic radius c [m] implied by the stresses of the elastic zone c < r < b.

    There the Lame form holds for any nu (traction-free at b: A = B / b^2), so each elastic
    point's von Mises stress gives B = sigma_vm / sqrt(3 / r^4 + (1 - 2 nu)^2 / b^4), and c is
    where that field reaches Y: c^4 = 3 B^2 / (Y^2 - (1 - 2 nu)^2 B^2 / b^4). r, von_mises:
    radii [m] and von Mises stresses [Pa] of points in the elastic zone (the median B is
    used). Raises InputError if no point is given.
    """
    r, vm = np.asarray(r, dtype=float), np.asarray(von_mises, dtype=float)
    if r.size == 0 or r.shape != vm.shape:
        raise InputError("thick cylinder: need radii and von Mises stresses of elastic points")
    big_b = float(np.median(vm / np.sqrt(3.0 / r**4 + (1.0 - 2.0 * nu) ** 2 / b**4)))
    y = positive("yield_pa", yield_pa)
    return (3.0 * big_b**2 / (y**2 - ((1.0 - 2.0 * nu) * big_b / b**2) ** 2)) ** 0.25
