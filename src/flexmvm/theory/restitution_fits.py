"""Restitution of an elastic-perfectly plastic contact from a published finite-element
contact law: the sphere-flat law that Jackson and Green fitted to their FE results, in the
form of Ghaednia, Brake, Berryhill and Jackson, with Brake's elastic unloading, integrated
over one impact (the route of Jackson, Green and Marghitu 2010, whose own fitted e is not
reproduced here).

Sources and what was read of each:

- H. Ghaednia, M. R. W. Brake, M. Berryhill, R. L. Jackson, "Strain hardening from
  elastic-perfectly plastic to perfectly elastic flattening single asperity contact",
  J. Tribol. (2019): the equations below, numbered as in that paper, as read in the open
  implementation of Porter and Brake (github.com/tmd-lab: microslip-rough-contact,
  GHAEDNIA_ET_AL_FLATTENING.m; tmdsimpy, roughcontact/_asperity_functions.py); the paper
  itself was not at hand. With the tangent modulus E_t = 0 (elastic-perfectly plastic) its
  eqs. 25-26 give a = a_p and eq. 30 gives F = F_p, which is Jackson and Green's (2005)
  fit to their FE results for a sphere flattened by a rigid flat (that paper not read here).
- M. R. W. Brake, "An analytical elastic plastic contact model with strain hardening and
  frictional effects for normal and oblique impacts", Int. J. Solids Struct. (2015): the
  unloading, as read in the same implementation (tmdsimpy).
- R. L. Jackson, I. Green, D. B. Marghitu, "Predicting the coefficient of restitution of
  impacting elastic-perfectly plastic spheres", Nonlinear Dyn. 60 (2010) 217-229: only its
  abstract was read (FE static sphere results with the kinetic energy balance give e; a
  critical speed that depends strongly on Poisson's ratio; fitted formulas, not read here).

The law (sphere of radius R [m], contact modulus E* [Pa], yield stress S_y [Pa], Poisson's
ratio nu of the body that yields; interference delta [m]):

    C = 1.295 exp(0.736 nu)                      p0 / S_y at first yield       (eq. 6)
    delta_c = (pi C S_y / (2 E*))^2 R            critical interference         (eq. 5)
    F_c = 4/3 (R / E*)^2 (C pi S_y / 2)^3        Hertz force at delta_c        (eq. 29)
    w = delta / delta_c
    F = 4/3 E* sqrt(R) delta^(3/2)               for w <= 1.9 (Hertz)          (eq. 1, sec. 3.2)
    F = F_c [exp(-w^(5/12) / 4) w^(3/2) + 4 H/(C S_y) (1 - exp(-w^(5/9) / 25)) w]
                                                 for w > 1.9                   (eq. 27)
    H / S_y = 2.84 - 0.92 (1 - cos(pi a / R))    hardness-like pressure        (eq. 28)
    a = R (pi C S_y / (2 E*)) sqrt(w (w / 1.9)^B),  B = 0.14 exp(23 S_y / E*)  (eqs. 23-24)

The two branches meet at w = 1.9 to 2e-3 (tests/test_restitution_fits.py), and C(nu) is
the von Mises onset pressure of theory.hertz_yield to 0.2 % at nu = 0.33. Unloading from the largest
interference delta_m and force F_m (Brake 2015): residual interference
delta_r = delta_m (1 - F_m / F_Hertz(delta_m)), then Hertz with the radius R_r that passes
through (delta_m - delta_r, F_m), F = 4/3 E* sqrt(R_r) (delta - delta_r)^(3/2); it returns
2/5 F_m (delta_m - delta_r) of work. The alternative (Unloading.HERTZ_AT_CONTACT_RADIUS)
is Thornton's (1997) rule applied to this law's contact radius a_m: Hertz unloading on
R_p = 4 E* a_m^3 / (3 F_m), returning 3 F_m^2 / (10 E* a_m). An impact of speed v and effective mass m* reaches
delta_m where the loading work is 1/2 m* v^2, and e^2 = returned work / (1/2 m* v^2).
Below w = 1.9 the law is Hertz both ways, so e = 1 up to the speed that reaches 1.9 delta_c
(1.9^(5/4) = 2.23 v_c). Neither unloading is an FE fit: the loading is the FE part.

What the law describes: a deformable sphere flattened by a rigid flat. flexmvm's study
(docs/plasticity.md) is the reverse, a rigid sphere indenting an elastic-perfectly plastic
block; the elastic part is the same (Hertz) and the onset the same (C S_y), but in FE the
plastic zones differ as the contact grows, so the law is a published FE trend beside the
study, not its exact counterpart.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq

from flexmvm.errors import InputError
from flexmvm.theory.hertz import positive

#: C = C_FACTOR exp(C_EXPONENT nu), Jackson and Green's onset pressure ratio (eq. 6) [-].
C_FACTOR = 1.295
C_EXPONENT = 0.736
#: w = delta / delta_c below which the fitted law is Hertz (Ghaednia et al. sec. 3.2) [-].
ELASTIC_LIMIT = 1.9


class Unloading(Enum):
    """How the contact unloads after the FE-fitted loading (module doc)."""

    #: Brake (2015): residual delta_m (1 - F_m / F_Hertz(delta_m)), Hertz through (delta_m, F_m).
    BRAKE = "brake"
    #: Thornton's (1997) rule on the FE-fitted contact radius a_m (eq. 23): Hertz unloading
    #: with the radius R_p = 4 E* a_m^3 / (3 F_m) that gives F_m at a_m.
    HERTZ_AT_CONTACT_RADIUS = "hertz_at_contact_radius"


def critical_pressure_ratio(nu: float) -> float:
    """C = 1.295 exp(0.736 nu) [-]: Hertz peak pressure over S_y at first yield (eq. 6).
    InputError unless 0 <= nu < 0.5."""
    nu = float(nu)
    if not (math.isfinite(nu) and 0.0 <= nu < 0.5):
        raise InputError(f"restitution_fits: Poisson's ratio must be in [0, 0.5), got {nu!r}")
    return C_FACTOR * math.exp(C_EXPONENT * nu)


@dataclass(frozen=True)
class FlatteningLaw:
    """The FE-fitted sphere-flat force law (module doc): radius_m R [m], e_star_pa E* [Pa],
    yield_pa S_y [Pa], nu the yielding body's Poisson's ratio. Build with ``make``."""

    radius_m: float
    e_star_pa: float
    yield_pa: float
    nu: float

    @classmethod
    def make(cls, radius_m: float, e_star_pa: float, yield_pa: float, nu: float):
        """The law with checked inputs; InputError for a non-positive R, E*, S_y or a nu
        outside [0, 0.5)."""
        critical_pressure_ratio(nu)
        return cls(
            positive("radius_m", radius_m),
            positive("e_star_pa", e_star_pa),
            positive("yield_pa", yield_pa),
            float(nu),
        )

    @property
    def c_ratio(self) -> float:
        return critical_pressure_ratio(self.nu)

    @property
    def delta_c(self) -> float:
        """Critical interference [m] (eq. 5)."""
        s = math.pi * self.c_ratio * self.yield_pa / (2.0 * self.e_star_pa)
        return s * s * self.radius_m

    @property
    def force_c(self) -> float:
        """Hertz force at delta_c [N] (eq. 29)."""
        r_e = self.radius_m / self.e_star_pa
        return 4.0 / 3.0 * r_e * r_e * (0.5 * self.c_ratio * math.pi * self.yield_pa) ** 3

    def hertz_force(self, delta):
        """4/3 E* sqrt(R) delta^(3/2) [N] for interference delta [m] (eq. 1)."""
        d = np.maximum(np.asarray(delta, dtype=float), 0.0)
        return 4.0 / 3.0 * self.e_star_pa * math.sqrt(self.radius_m) * d**1.5

    def contact_radius(self, delta):
        """a [m]: Hertz's sqrt(R delta) up to 1.9 delta_c, eq. 23 past it."""
        w = np.maximum(np.asarray(delta, dtype=float), 0.0) / self.delta_c
        b = 0.14 * math.exp(23.0 * self.yield_pa / self.e_star_pa)  # eq. 24
        a_c = math.sqrt(self.radius_m * self.delta_c)
        plastic = a_c * np.sqrt(w * (np.maximum(w, ELASTIC_LIMIT) / ELASTIC_LIMIT) ** b)
        return np.where(w <= ELASTIC_LIMIT, a_c * np.sqrt(w), plastic)

    def force(self, delta):
        """Loading force [N] at interference delta [m]: Hertz up to 1.9 delta_c, eq. 27
        past it. Scalar or array."""
        d = np.asarray(delta, dtype=float)
        w = np.maximum(d, 0.0) / self.delta_c
        h = 2.84 - 0.92 * (1.0 - np.cos(math.pi * self.contact_radius(d) / self.radius_m))
        plastic = self.force_c * (
            np.exp(-0.25 * w ** (5.0 / 12.0)) * w**1.5
            + 4.0 * h / self.c_ratio * (1.0 - np.exp(-(w ** (5.0 / 9.0)) / 25.0)) * w
        )
        out = np.where(w <= ELASTIC_LIMIT, self.hertz_force(d), plastic)
        return out if out.ndim else float(out)

    def loading_work(self, delta_max: float) -> float:
        """Work [J] of the loading force from 0 to delta_max [m]: Hertz's 8/15 E* sqrt(R)
        d^(5/2) to 1.9 delta_c, quadrature of eq. 27 past it (relative tolerance 1e-12)."""
        d_el = min(delta_max, ELASTIC_LIMIT * self.delta_c)
        work = 8.0 / 15.0 * self.e_star_pa * math.sqrt(self.radius_m) * d_el**2.5
        if delta_max > d_el:
            work += quad(self.force, d_el, delta_max, epsabs=0.0, epsrel=1e-12, limit=200)[0]
        return work

    def unloading(self, delta_max: float) -> tuple[float, float, float]:
        """Brake's (2015) unloading from delta_max [m]: (residual interference delta_r [m],
        unloading radius R_r [m], returned work 2/5 F_m (delta_max - delta_r) [J])."""
        f_m = float(self.force(delta_max))
        delta_r = delta_max * (1.0 - f_m / float(self.hertz_force(delta_max)))
        span = delta_max - delta_r
        r_r = (f_m / (4.0 / 3.0 * self.e_star_pa)) ** 2 / span**3
        return delta_r, r_r, 0.4 * f_m * span

    def unloading_at_contact_radius(self, delta_max: float) -> tuple[float, float, float]:
        """Thornton's (1997) unloading rule on this law's contact radius a_m at delta_max
        [m]: (residual interference [m], R_p = 4 E* a_m^3 / (3 F_m) [m], returned work
        2/5 F_m a_m^2 / R_p = 3 F_m^2 / (10 E* a_m) [J])."""
        f_m = float(self.force(delta_max))
        a_m = float(self.contact_radius(delta_max))
        r_p = 4.0 * self.e_star_pa * a_m**3 / (3.0 * f_m)
        recovered = a_m * a_m / r_p  # the Hertz approach of F_m on R_p
        return delta_max - recovered, r_p, 0.4 * f_m * recovered


def critical_velocity(law: FlatteningLaw, m_star_kg: float) -> float:
    """v_c [m/s]: the impact speed whose Hertz approach is delta_c, from
    1/2 m* v_c^2 = 8/15 E* sqrt(R) delta_c^(5/2)."""
    m = positive("m_star_kg", m_star_kg)
    return math.sqrt(2.0 * law.loading_work(law.delta_c) / m)


def peak_interference(law: FlatteningLaw, energy_j: float) -> float:
    """delta_m [m] whose loading work is energy_j [J] (> 0): bracket by doubling from
    delta_c, then Brent's root to 1e-14 relative."""
    energy = positive("energy_j", energy_j)
    hi = law.delta_c
    while law.loading_work(hi) < energy:
        hi *= 2.0

    def excess(d: float) -> float:
        return law.loading_work(d) - energy

    return brentq(excess, 0.0, hi, xtol=1e-16 * hi, rtol=1e-14)


def flattening_restitution(
    law: FlatteningLaw,
    m_star_kg: float,
    speed_mps,
    unloading: Unloading = Unloading.BRAKE,
):
    """e [-] of an impact at speed_mps [m/s] (scalar or array, each > 0) with effective mass
    m_star_kg [kg]: loading work = 1/2 m* v^2 fixes delta_m (root to 1e-14 relative), and
    e = sqrt(returned work / 1/2 m* v^2), the work returned by ``unloading`` (module doc).
    InputError on bad input."""
    m = positive("m_star_kg", m_star_kg)
    v = np.asarray(speed_mps, dtype=float)
    if not np.all(np.isfinite(v) & (v > 0.0)):
        raise InputError(f"restitution_fits: speeds must be finite and > 0, got {speed_mps!r}")
    out = np.empty(v.shape)
    for i, vi in np.ndenumerate(v):
        energy = 0.5 * m * vi * vi
        d_m = peak_interference(law, energy)
        if d_m <= ELASTIC_LIMIT * law.delta_c:  # Hertz both ways: no loss
            out[i] = 1.0
        else:
            back = (
                law.unloading(d_m)
                if unloading is Unloading.BRAKE
                else law.unloading_at_contact_radius(d_m)
            )
            out[i] = math.sqrt(back[2] / energy)
    return out if out.ndim else float(out)


__all__ = [
    "C_EXPONENT",
    "C_FACTOR",
    "ELASTIC_LIMIT",
    "FlatteningLaw",
    "Unloading",
    "critical_pressure_ratio",
    "critical_velocity",
    "flattening_restitution",
    "peak_interference",
]
