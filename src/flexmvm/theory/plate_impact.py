"""Hertz impact of a sphere on a plate (Zener, "The intrinsic inelasticity of large plates",
Phys. Rev. 59, 1941): the Hertz contact in series with the plate's point impedance.

A thin plate struck at a point answers, until the bending waves come back from its edges, as
a dashpot: the point velocity is F / Z with Z = 8 sqrt(D rho h), D = E h^3 / (12 (1 - nu^2))
its bending stiffness, rho h its mass per area (the infinite-plate point impedance; Cremer,
Heckl, *Structure-borne sound*, table of point impedances). It is real and independent of
the frequency, so the impact is one ODE: the sphere (mass m1, speed v) approaches the plate
by delta = x - w - X, with F = K delta^(3/2), K = 4/3 E* sqrt(R), and

    m1 x'' = -F,   w' = F / Z (the plate's local deflection),   m2 X'' = F (its recoil)

(m2 = inf: a clamped or held plate, no recoil). Z = inf is Hertz's rigid target (theory/
hertz.py). The energy the bending waves carry away lowers the peak force and lengthens the
contact: on a 100 x 100 x 4 mm clamped aluminium plate struck by a rigid steel ball R 5 mm
at 1 m/s, full FE gives 230 N, this model 230 N, Hertz on a rigid target 376 N
(docs/notes/2026-11-29-region-estimates.md).
"""

from __future__ import annotations

import math

import numpy as np

from flexmvm.theory.hertz import HertzImpact, hertz_impact, positive

__all__ = ["plate_impact", "plate_impedance"]


def plate_impedance(E: float, nu: float, rho: float, h: float) -> float:
    """Point impedance Z = 8 sqrt(D rho h) [N s/m] of an infinite plate of thickness h [m]
    (module doc)."""
    D = positive("E", E) * positive("h", h) ** 3 / (12.0 * (1.0 - nu**2))
    return 8.0 * math.sqrt(D * positive("rho", rho) * h)


def plate_impact(
    radius_m: float,
    speed_mps: float,
    e_star_pa: float,
    m1_kg: float,
    m2_kg: float = math.inf,
    impedance_nspm: float = math.inf,
) -> HertzImpact:
    """The scales of the impact of a sphere (radius ``radius_m``, mass ``m1_kg``, speed
    ``speed_mps``) on a plate of point impedance ``impedance_nspm`` and mass ``m2_kg`` (module
    doc): the peak force, the largest approach delta_max, the contact radius sqrt(R delta_max)
    and the duration, integrated in Hertz's own scales (delta_0, delta_0 / v) with rtol 1e-9.
    ``m_star_kg`` is the sphere's reduced mass with m2; Z = inf gives hertz_impact."""
    rigid = hertz_impact(radius_m, speed_mps, e_star_pa, m1_kg, m2_kg)
    Z = float(impedance_nspm)
    if Z == math.inf:
        return rigid
    Z = positive("impedance_nspm", Z)
    from scipy.integrate import solve_ivp

    m1, m2, v = float(m1_kg), m2_kg, float(speed_mps)
    d0, t0 = rigid.delta_max_m, rigid.delta_max_m / v
    K = 4.0 / 3.0 * e_star_pa * math.sqrt(radius_m)
    f0 = K * d0**1.5  # force scale [N]
    inv_m = 1.0 / m1 + (0.0 if m2 == math.inf else 1.0 / m2)
    # y = (delta / d0, the sphere's closing speed / v, in units of the sphere's mass and the
    # plate's recoil); delta' = u - F / Z, u' = -F (1/m1 + 1/m2)
    a_u, a_d = f0 * t0 * inv_m / v, f0 / (Z * v)

    def rhs(_t, y):
        f = max(y[0], 0.0) ** 1.5
        return [y[1] - a_d * f, -a_u * f]

    def leaves(_t, y):
        return y[0]

    # solve_ivp reads the event's options off the function object
    leaves.terminal, leaves.direction = True, -1.0  # type: ignore[attr-defined]
    sol = solve_ivp(
        rhs, (0.0, 50.0), [0.0, 1.0], events=leaves, rtol=1e-9, atol=1e-12, dense_output=True
    )
    t_end = float(sol.t_events[0][0]) if sol.t_events[0].size else float(sol.t[-1])
    s = np.linspace(0.0, t_end, 4001)
    delta = max(float(np.max(sol.sol(s)[0])), 0.0) * d0
    return HertzImpact(
        e_star_pa,
        rigid.m_star_kg,
        delta,
        K * delta**1.5,
        math.sqrt(radius_m * delta),
        t_end * t0,
    )
