"""Restitution of an elastic-perfectly plastic sphere striking a flat: Thornton's model
(C. Thornton, "Coefficient of restitution for collinear collisions of elastic-perfectly
plastic spheres", J. Appl. Mech. 64 (1997) 383-386).

With the Hertz contact of a sphere of radius R on a flat (contact modulus E*, effective mass
m*, approach alpha, contact radius a^2 = R alpha, peak pressure p0 = 2 E* a / (pi R)):

- Loading is Hertz, F = 4/3 E* sqrt(R) alpha^(3/2), until p0 reaches the limiting contact
  pressure p_y (at alpha_y, a_y, F_y = 2/3 pi p_y a_y^2); Thornton takes p_y = 1.61 Y for
  the onset of yield (ONSET_PRESSURE_RATIO; theory.hertz_yield computes the von Mises onset
  on the axis, 1.613 Y at nu = 0.3 and 1.649 Y at nu = 0.33, which Johnson 1985 rounds to
  1.60 Y: v_y scales as p_y^(5/2), so those give v_y times (1.613 / 1.61)^(5/2) = 1.004 and
  (1.649 / 1.61)^(5/2) = 1.062). The impact speed that just reaches it, from
  1/2 m* v_y^2 = 8/15 E* sqrt(R) alpha_y^(5/2), is the yield velocity

      v_y = sqrt(pi^5 / 30) (p_y^5 R^3 / (E*^4 m*))^(1/2) = 3.194 (...)^(1/2).

- Past it the Hertz pressure is cut at p_y, so that F = pi p_y a^2 - pi p_y a_y^2 / 3 =
  F_y + pi p_y R (alpha - alpha_y): linear in alpha. The energy balance at the largest
  force F* gives F* / F_y = sqrt(6/5 (v / v_y)^2 - 1/5).
- Unloading is Hertz again from the contact radius a_p of F*, a_p^2 = (2 F* + F_y) /
  (2 pi p_y), with the flattened radius R_p = 4 E* a_p^3 / (3 F*) (the curvature that gives
  F* at a_p); it returns 2/5 F* a_p^2 / R_p of work, so

      e = (6 sqrt3 / 5)^(1/2) [1 - (v_y/v)^2 / 6]^(1/2)
          [ (v_y/v) / ((v_y/v) + 2 sqrt(6/5 - (v_y/v)^2 / 5)) ]^(1/4)         (v > v_y)

  and e = 1 for v <= v_y. It is continuous at v_y (e = 3^(1/4) 3^(-1/4) = 1), decreases
  monotonically and tends to e ~ ASYMPTOTE (v_y / v)^(1/4), ASYMPTOTE = (6 sqrt3 / 5)^(1/2)
  (2 sqrt(6/5))^(-1/4) = 1.18499 (Thornton's 1.185).

Equation numbers of the paper are not quoted: no copy of it was at hand when this was
written, so every step is derived above and tests/test_thornton.py recomputes e by
quadrature of the force-approach law instead of trusting the closed form.
"""

from __future__ import annotations

import math

import numpy as np

from flexmvm.errors import InputError
from flexmvm.theory.hertz import positive

#: Thornton's limiting contact pressure at the onset of yield, p_y / Y [-].
ONSET_PRESSURE_RATIO = 1.61
#: e (v / v_y)^(1/4) as v / v_y -> inf: (6 sqrt3 / 5)^(1/2) (2 sqrt(6/5))^(-1/4) [-].
ASYMPTOTE = math.sqrt(6.0 * math.sqrt(3.0) / 5.0) * (2.0 * math.sqrt(1.2)) ** -0.25


def yield_velocity(
    radius_m: float,
    e_star_pa: float,
    m_star_kg: float,
    yield_pa: float,
    pressure_ratio: float = ONSET_PRESSURE_RATIO,
) -> float:
    """v_y [m/s] (module doc): the impact speed at which the Hertz peak pressure of a sphere
    of radius R [m] with contact modulus E* [Pa] and effective mass m* [kg] reaches
    p_y = pressure_ratio Y, Y [Pa] the yield stress. InputError for a non-positive input."""
    r = positive("radius_m", radius_m)
    e_star = positive("e_star_pa", e_star_pa)
    m = positive("m_star_kg", m_star_kg)
    p_y = positive("pressure_ratio", pressure_ratio) * positive("yield_pa", yield_pa)
    return math.sqrt(math.pi**5 / 30.0 * p_y**5 * r**3 / (e_star**4 * m))


def _speed_ratio(speed_ratio) -> np.ndarray:
    s = np.asarray(speed_ratio, dtype=float)
    if not np.all(np.isfinite(s) & (s > 0.0)):
        raise InputError(
            f"thornton: speed ratio v / v_y must be finite and > 0, got {speed_ratio!r}"
        )
    return s


def peak_force_ratio(speed_ratio):
    """F* / F_y [-] at impact speed v / v_y (module doc): (v / v_y)^(6/5) up to v_y (Hertz),
    sqrt(6/5 (v / v_y)^2 - 1/5) past it. Scalar or array; InputError unless finite > 0."""
    s = _speed_ratio(speed_ratio)
    out = np.where(s <= 1.0, s**1.2, np.sqrt(1.2 * np.maximum(s, 1.0) ** 2 - 0.2))
    return out if out.ndim else float(out)


def restitution(speed_ratio):
    """Coefficient of restitution e [-] at impact speed v / v_y (module doc): 1 up to v_y,
    Thornton's closed form past it. Scalar or array; InputError unless finite and > 0."""
    s = np.maximum(_speed_ratio(speed_ratio), 1.0)
    r = 1.0 / s  # v_y / v
    root = np.sqrt(1.2 - 0.2 * r * r)
    e = math.sqrt(6.0 * math.sqrt(3.0) / 5.0) * np.sqrt(1.0 - r * r / 6.0)
    e = e * (r / (r + 2.0 * root)) ** 0.25
    e = np.where(s <= 1.0, 1.0, e)
    return e if e.ndim else float(e)


__all__ = ["ASYMPTOTE", "ONSET_PRESSURE_RATIO", "peak_force_ratio", "restitution", "yield_velocity"]
