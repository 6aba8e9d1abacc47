"""Quasi-static Hertz impact of a sphere on a body (Johnson, *Contact Mechanics*, 1985,
sect. 11.4): the closed-form peak force, approach, contact radius and duration that size a
reduced region before any FE run.

With 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2, 1/m* = 1/m1 + 1/m2 (m2 = inf: a grounded or
heavy target) and the sphere's radius R [m], an impact at speed v [m/s] reaches

    delta_max = (15 m* v^2 / (16 E* sqrt R))^(2/5)        the largest approach [m]
    F_max     = 4/3 E* sqrt(R) delta_max^(3/2)            the peak force [N]
    a_max     = sqrt(R delta_max)                          the contact radius [m]
    T_c       = 2.94328 delta_max / v                       the contact duration [s]

(Johnson eq. 11.24; the duration's 2.94328 = 2 int_0^1 dx / sqrt(1 - x^(5/2)), his 2.94). It ignores the waves and the
vibration of the bodies: on a free beam the first impact ends earlier and others follow; it
is the scale of the contact, what a region is sized by, not a prediction of the history.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from flexmvm.errors import InputError

#: Contact duration of a quasi-static Hertz impact per delta_max / v: 2 int_0^1 dx /
#: sqrt(1 - x^(5/2)) (Johnson eq. 11.24 gives 2.94).
DURATION_FACTOR = 2.94328


@dataclass(frozen=True)
class HertzImpact:
    """A Hertz impact's scales: e_star_pa [Pa], m_star_kg [kg], delta_max_m, force_max_n [N],
    contact_radius_m [m] and duration_s [s]."""

    e_star_pa: float
    m_star_kg: float
    delta_max_m: float
    force_max_n: float
    contact_radius_m: float
    duration_s: float


def positive(name: str, x: float) -> float:
    """x as a float; InputError naming ``name`` unless it is finite and > 0."""
    x = float(x)
    if not (math.isfinite(x) and x > 0):
        raise InputError(f"{name}: expected a finite number > 0, got {x!r}")
    return x


def effective_modulus(E1: float, nu1: float, E2: float, nu2: float) -> float:
    """E* [Pa] of two elastic bodies: 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2."""
    return 1.0 / ((1.0 - nu1**2) / positive("E1", E1) + (1.0 - nu2**2) / positive("E2", E2))


def hertz_impact(
    radius_m: float, speed_mps: float, e_star_pa: float, m1_kg: float, m2_kg: float = math.inf
) -> HertzImpact:
    """The scales of the impact (module doc) of a sphere of radius ``radius_m`` at
    ``speed_mps`` with effective modulus ``e_star_pa``, masses m1 and m2 [kg] (m2 = inf: a
    target that does not recoil). InputError for a non-positive input."""
    R = positive("radius_m", radius_m)
    v = positive("speed_mps", speed_mps)
    E = positive("e_star_pa", e_star_pa)
    m1 = positive("m1_kg", m1_kg)
    m2 = math.inf if m2_kg == math.inf else positive("m2_kg", m2_kg)
    m_star = m1 if m2 == math.inf else m1 * m2 / (m1 + m2)
    delta = (15.0 * m_star * v * v / (16.0 * E * math.sqrt(R))) ** 0.4
    force = 4.0 / 3.0 * E * math.sqrt(R) * delta**1.5
    return HertzImpact(E, m_star, delta, force, math.sqrt(R * delta), DURATION_FACTOR * delta / v)


__all__ = ["DURATION_FACTOR", "HertzImpact", "effective_modulus", "hertz_impact", "positive"]
