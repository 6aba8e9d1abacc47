"""A constant force moving at constant speed over a simply supported beam: the modal series
of Fryba (Vibration of Solids and Structures under Moving Loads, 3rd ed. 1999, ch. 1), the
reference of scenarios/moving_load.toml (docs/notes/2026-11-29-moving-load.md).

A force P enters the span L at x = 0 at t = 0 and crosses it at speed c; the beam starts at
rest, undeformed. With the simply supported modes sin(j pi x / L) the deflection is
w(x, t) = sum_j q_j(t) sin(j pi x / L), each mode a forced oscillator while the force is on
the span (0 <= t <= T = L / c):

    q_j'' + w_j^2 q_j = w_j^2 S_j sin(W_j t),   W_j = j pi c / L,
    q_j = S_j / (1 - r_j^2) (sin W_j t - r_j sin w_j t),   r_j = W_j / w_j,

S_j = (2 P / L) f_j the mode's static response, f_j its flexibility. Euler-Bernoulli:
f_j = 1 / (E I k_j^4), k_j = j pi / L, w_j = k_j^2 sqrt(E I / mu), so r_j = alpha / j with
alpha = c / c_cr and c_cr = (pi / L) sqrt(E I / mu) the critical speed (Fryba eq. 1.26:
w = w0 (96 / pi^4) sum_j sin(j pi x / L) [sin(j omega t) - (alpha / j) sin(w_j t)] /
(j^2 (j^2 - alpha^2)) with w0 = P L^3 / (48 E I), omega = pi c / L). After T the modes ring
freely from their state at T. At r_j = 1 the mode's limit S_j (sin w t - w t cos w t) / 2.

Shear (``kappa_G_pa`` given: a Timoshenko beam): f_j = 1 / (E I k^4) + 1 / (kappa G A k^2)
(the static response of the Timoshenko sine mode, exact) and w_j the lower root of the
Timoshenko frequency equation of the simply supported beam (rotary inertia rho I included);
the upper (thickness-shear) branch is left out, so that the static limit stays exact and
the dynamics carry the first-order shear and rotary-inertia corrections of each mode.

Checks (tests/test_moving_load.py): c -> 0 gives the static deflection under the load
P a b (L^2 - a^2 - b^2) / (6 E I L) (a = c t, b = L - a); at alpha = 1 the mid-span deflection
when the force leaves is w0 48 / pi^3 = 1.548 w0 (every mode j > 1 is zero there:
sin(j pi) = sin(j^2 pi) = 0; mode 1 at resonance, S_1 pi / 2 with S_1 = (96 / pi^4) w0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError
from flexmvm.theory.hertz import positive

__all__ = ["MovingForce", "static_deflection"]

_RESONANCE = 1e-9  # |1 - r_j^2| below this: the mode's resonant limit


def static_deflection(x, a, length_m: float, force_n: float, EI_nm2: float) -> np.ndarray:
    """Deflection [m] at x of a simply supported Euler-Bernoulli beam under a force at a
    (both [m] in [0, L]): P b x (L^2 - b^2 - x^2) / (6 E I L) for x <= a (b = L - a), the
    mirror image beyond (Roark, table 8.1 case 1e)."""
    x, a = np.broadcast_arrays(np.asarray(x, float), np.asarray(a, float))
    L = length_m
    left = force_n * (L - a) * x * (L**2 - (L - a) ** 2 - x**2)
    right = force_n * a * (L - x) * (L**2 - a**2 - (L - x) ** 2)
    return np.where(x <= a, left, right) / (6.0 * EI_nm2 * L)


@dataclass(frozen=True)
class MovingForce:
    """Force force_n [N] (positive along the deflection) crossing a simply supported beam of
    span length_m [m] at speed_mps [m/s]; bending stiffness EI_nm2 [N m^2], mass per length
    mu_kg_m [kg/m]. Optional shear (a Timoshenko beam, module doc): kappa_G_pa the shear
    modulus times the shear coefficient [Pa] with area_m2 [m^2] and rho_I_kg_m the rotary
    inertia per length rho I [kg m]."""

    length_m: float
    EI_nm2: float
    mu_kg_m: float
    force_n: float
    speed_mps: float
    kappa_G_pa: float | None = None
    area_m2: float | None = None
    rho_I_kg_m: float = 0.0

    def __post_init__(self) -> None:
        for name in ("length_m", "EI_nm2", "mu_kg_m", "speed_mps"):
            positive(name, getattr(self, name))
        if (self.kappa_G_pa is None) != (self.area_m2 is None):
            raise InputError(
                f"moving force: give both kappa_G_pa and area_m2 or neither, got "
                f"{self.kappa_G_pa!r} and {self.area_m2!r}"
            )
        if self.kappa_G_pa is not None and self.area_m2 is not None:  # both or neither
            positive("kappa_G_pa", self.kappa_G_pa)
            positive("area_m2", self.area_m2)

    @property
    def critical_speed_mps(self) -> float:
        """c_cr = (pi / L) sqrt(E I / mu) [m/s]: the speed at which the force's passage
        (half a period of sin(pi c t / L)) matches the first mode's half period."""
        return math.pi / self.length_m * math.sqrt(self.EI_nm2 / self.mu_kg_m)

    @property
    def alpha(self) -> float:
        """Speed parameter c / c_cr (Fryba's alpha)."""
        return self.speed_mps / self.critical_speed_mps

    @property
    def crossing_time_s(self) -> float:
        """T = L / c [s]: the force leaves the span."""
        return self.length_m / self.speed_mps

    @property
    def midspan_static_m(self) -> float:
        """w0 = P L^3 / (48 E I) [m], the static mid-span deflection under a mid-span force
        (bending only)."""
        return self.force_n * self.length_m**3 / (48.0 * self.EI_nm2)

    def modes(self, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(k_j [1/m], flexibility f_j [m/N per unit modal load], w_j [rad/s]) of modes
        j = 1..n (module doc)."""
        k = np.arange(1, n + 1) * math.pi / self.length_m
        flex = 1.0 / (self.EI_nm2 * k**4)
        if self.kappa_G_pa is None or self.area_m2 is None:
            return k, flex, k**2 * math.sqrt(self.EI_nm2 / self.mu_kg_m)
        gA = self.kappa_G_pa * self.area_m2
        flex = flex + 1.0 / (gA * k**2)
        # det [[gA k^2 - mu w^2, -gA k], [-gA k, EI k^2 + gA - rho_I w^2]] = 0, in s = w^2
        a = self.mu_kg_m * self.rho_I_kg_m
        b = -(self.mu_kg_m * (self.EI_nm2 * k**2 + gA) + self.rho_I_kg_m * gA * k**2)
        c = gA * k**2 * (self.EI_nm2 * k**2 + gA) - (gA * k) ** 2
        s = 2.0 * c / (-b + np.sqrt(b**2 - 4.0 * a * c))  # the lower root, stable as a -> 0
        return k, flex, np.sqrt(s)

    def modal_history(self, t, n_modes: int = 50) -> tuple[np.ndarray, np.ndarray]:
        """(k_j, q_j(t)) (n_modes,), (len(t), n_modes) [m]: each mode forced while the force is
        on the span, free after T (module doc)."""
        t = np.atleast_1d(np.asarray(t, float))
        k, flex, w = self.modes(n_modes)
        s = 2.0 * self.force_n / self.length_m * flex
        big_w = k * self.speed_mps
        r = big_w / w
        T = self.crossing_time_s

        def forced(tt):
            tt = tt[:, None]
            out = np.empty((len(tt), n_modes))
            rate = np.empty_like(out)
            res = np.abs(1.0 - r**2) < _RESONANCE
            d = np.where(res, 1.0, 1.0 - r**2)
            out[:] = s / d * (np.sin(big_w * tt) - r * np.sin(w * tt))
            rate[:] = s / d * big_w * (np.cos(big_w * tt) - np.cos(w * tt))
            lim = 0.5 * s * (np.sin(w * tt) - w * tt * np.cos(w * tt))
            lim_rate = 0.5 * s * w**2 * tt * np.sin(w * tt)
            return np.where(res, lim, out), np.where(res, lim_rate, rate)

        q, _ = forced(np.minimum(t, T))
        after = t > T
        if np.any(after):
            qT, vT = forced(np.array([T]))
            tau = (t[after] - T)[:, None]
            q[after] = qT * np.cos(w * tau) + vT / w * np.sin(w * tau)
        return k, q

    def deflection(self, x, t, n_modes: int = 50) -> np.ndarray:
        """w(x, t) [m], (len(t),) at one x [m] or (len(t), len(x)) (module doc)."""
        k, q = self.modal_history(t, n_modes)
        xs = np.atleast_1d(np.asarray(x, float))
        w = q @ np.sin(np.outer(k, xs))
        return w[:, 0] if np.ndim(x) == 0 else w
