"""Onset of yield under a Hertz contact of a sphere on a flat (Johnson 1985, *Contact
Mechanics*, sect. 3.4 and 6.2): the von Mises stress on the axis below the centre,

    sigma_r = sigma_theta = -p0 [(1 + nu) (1 - (z/a) arctan(a/z)) - 1 / (2 (1 + z^2/a^2))]
    sigma_z = -p0 / (1 + z^2/a^2)                                  (Johnson eq. 3.45)
    sigma_vm = |sigma_z - sigma_r|

peaks below the surface (z ~ 0.48 a for nu = 0.3), so that yield starts when the peak
pressure p0 reaches Y / max(sigma_vm / p0), about 1.60 Y (von Mises, nu = 0.3). With
p0 = 2 E* a / (pi R) and a^2 = R delta this gives the approach, force and contact radius at
first yield.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from flexmvm.errors import InputError
from flexmvm.theory.hertz import positive


@dataclass(frozen=True)
class YieldOnset:
    """First yield of a Hertz contact: p0_over_y = p0 / Y [-] at onset, depth_over_a = z / a
    of the first yielding point, and for a given sphere the contact radius_m [m], approach
    delta_m [m] and force_n [N] at onset."""

    p0_over_y: float
    depth_over_a: float
    radius_m: float
    delta_m: float
    force_n: float


def axis_von_mises(z_over_a, nu: float) -> np.ndarray:
    """sigma_vm / p0 on the axis at depths z / a > 0 (Johnson eq. 3.45)."""
    s = np.asarray(z_over_a, dtype=float)
    radial = (1.0 + nu) * (1.0 - s * np.arctan(1.0 / s)) - 0.5 / (1.0 + s * s)
    return np.abs(-1.0 / (1.0 + s * s) + radial)


def yield_onset(yield_pa: float, e_star_pa: float, radius_m: float, nu: float) -> YieldOnset:
    """First yield (von Mises) of a sphere of radius R pressed on a flat of Poisson ratio nu
    with contact modulus E* [Pa]. Raises InputError for non-positive inputs or nu outside
    (-1, 0.5)."""
    y, e_star, r = (
        positive("yield_pa", yield_pa),
        positive("e_star_pa", e_star_pa),
        positive("radius_m", radius_m),
    )
    if not -1.0 < nu < 0.5:
        raise InputError(f"yield_onset: nu must be in (-1, 0.5), got {nu!r}")
    best = minimize_scalar(
        lambda s: -float(axis_von_mises(s, nu)),
        bounds=(0.05, 3.0),
        method="bounded",
        options={"xatol": 1e-10},
    )
    p0 = y / float(axis_von_mises(best.x, nu))
    a = math.pi * p0 * r / (2.0 * e_star)
    delta = a * a / r
    force = 4.0 / 3.0 * e_star * math.sqrt(r) * delta**1.5
    return YieldOnset(p0 / y, float(best.x), a, delta, force)
