"""The slider-crank at a constant crank speed: closed-form rigid kinematics and the connecting
rod's transverse vibration as a pinned-pinned Euler-Bernoulli beam under its rigid-body
inertial load (the reference of scenarios/slider_crank.toml, docs/slider_crank.md).

Kinematics (crank r, rod l, slider line offset e from the crank axis, crank angle phi = omega t,
the pin A = r (cos phi, sin phi), the slider's pin B = (x, e)):

    x(phi) = r cos phi + sqrt(l^2 - (r sin phi - e)^2)                      (e = 0: textbook)

Rod vibration (Simeon 1996, Math. Modelling of Systems 2, 1-18: the lateral modes sin(k pi s/l)
of the IVP test set's "crank" problem; Meirovitch, "Fundamentals of Vibrations", 2001, sec. 8):
the deflection w(s, t) from the chord AB, w = sum_k q_k sin(k pi s / l), obeys

    m q_k'' + k_k q_k = f_k,   m = rho A l / 2,   k_k = E I (k pi)^4 / (2 l^3),
    f_k = -rho A l int_0^1 a_n(xi) sin(k pi xi) dxi

with a_n(xi) = (1 - xi) a_A.n + xi a_B.n the rigid rod's acceleration normal to the chord (linear
along a rigid link), n = z x (B - A) / l. Left out, as by a linear floating-frame model: the
axial force's geometric stiffening, the frame rotation's centrifugal softening
(omega_rod^2 / omega_1^2 ~ 0.3 % at 75 rad/s against 1276 rad/s) and the elastic motion's
feedback on the rigid motion (the crank is driven). The mid-span deflection w(l/2) is
sum_k q_k sin(k pi / 2): the odd modes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from flexmvm.errors import InputError
from flexmvm.theory.hertz import positive


@dataclass(frozen=True)
class SliderCrank:
    """Crank r_m, rod l_m [m], slider line offset e_m [m], crank speed omega_radps [rad/s];
    the rod's E_pa, rho_kg_m3, section area_m2 and second moment I_m4 (about the axis normal to
    the plane of motion)."""

    r_m: float
    l_m: float
    omega_radps: float
    E_pa: float
    rho_kg_m3: float
    area_m2: float
    I_m4: float
    e_m: float = 0.0

    def __post_init__(self) -> None:
        for name in ("r_m", "l_m", "omega_radps", "E_pa", "rho_kg_m3", "area_m2", "I_m4"):
            positive(name, getattr(self, name))
        if not self.r_m + abs(self.e_m) < self.l_m:
            raise InputError(
                f"slider-crank: expected r + |e| < l (a full turn), got r = {self.r_m!r}, "
                f"e = {self.e_m!r}, l = {self.l_m!r} m"
            )

    def slider_x(self, phi) -> np.ndarray:
        """Slider pin position x(phi) [m] along the guide."""
        phi = np.asarray(phi, float)
        s = self.r_m * np.sin(phi) - self.e_m
        return self.r_m * np.cos(phi) + np.sqrt(self.l_m**2 - s**2)

    def slider_velocity(self, phi) -> np.ndarray:
        """dx/dt [m/s] at a constant crank speed: (dx/dphi) omega."""
        phi = np.asarray(phi, float)
        s = self.r_m * np.sin(phi) - self.e_m
        ds = self.r_m * np.cos(phi)
        return (-self.r_m * np.sin(phi) - s * ds / np.sqrt(self.l_m**2 - s**2)) * self.omega_radps

    def _normal_accelerations(self, t: float) -> tuple[float, float]:
        """(a_A.n, a_B.n) [m/s^2]: the pins' accelerations normal to the chord at time t."""
        r, l, w = self.r_m, self.l_m, self.omega_radps
        phi = w * t
        s, ds, dds = r * math.sin(phi) - self.e_m, r * w * math.cos(phi), -r * w * w * math.sin(phi)
        c = math.sqrt(l * l - s * s)
        xB = r * math.cos(phi) + c
        ddx = -r * w * w * math.cos(phi) - (ds * ds + s * dds) / c - (s * ds) ** 2 / c**3
        ax, ay = -r * w * w * math.cos(phi), -r * w * w * math.sin(phi)
        ux, uy = (xB - r * math.cos(phi)) / l, (self.e_m - r * math.sin(phi)) / l
        nx, ny = -uy, ux
        return ax * nx + ay * ny, ddx * nx

    def mode_frequency(self, k: int) -> float:
        """omega_k [rad/s] of the pinned-pinned rod: (k pi / l)^2 sqrt(E I / (rho A))."""
        return (k * math.pi / self.l_m) ** 2 * math.sqrt(
            self.E_pa * self.I_m4 / self.rho_kg_m3 / self.area_m2
        )

    def midspan_deflection(self, t_s, modes: int = 3, q0=None, q0_dot=None) -> np.ndarray:
        """w(l/2, t) [m] at the times t_s (ascending, from 0), from modes 1..``modes``
        started at q0, q0_dot (each (modes,), default zero: the rod undeformed and at rest in
        its frame); positive along n = z x (B - A). Integrated by scipy's DOP853 to 1e-10."""
        t = np.asarray(t_s, float)
        if modes < 1 or t.ndim != 1 or t[0] < 0 or np.any(np.diff(t) <= 0):
            raise InputError("midspan_deflection: expected modes >= 1 and ascending times >= 0")
        k = np.arange(1, modes + 1)
        wk2 = np.array([self.mode_frequency(int(j)) ** 2 for j in k])
        # f_k / m = -2 [a_A (1 - cos k pi) - (a_B - a_A) cos(k pi)] / (k pi)
        #         = -2 [a_A - a_B cos(k pi)] / (k pi)
        gA, gB = -2.0 / (k * math.pi), 2.0 * np.cos(k * math.pi) / (k * math.pi)

        def rhs(tt, y):
            aA, aB = self._normal_accelerations(tt)
            return np.concatenate([y[modes:], gA * aA + gB * aB - wk2 * y[:modes]])

        y0 = np.concatenate(
            [np.zeros(modes) if q0 is None else q0, np.zeros(modes) if q0_dot is None else q0_dot]
        )
        sol = solve_ivp(rhs, (0.0, t[-1]), y0, method="DOP853", t_eval=t, rtol=1e-10, atol=1e-14)
        return np.sin(k * math.pi / 2) @ sol.y[:modes]


def chord_deflection(pin_a, mid, pin_b) -> np.ndarray:
    """The signed distance [m] of the point ``mid`` from the line through ``pin_a`` and
    ``pin_b``, in the (x, y) plane of motion, along n = z x (pin_b - pin_a) / |...|, minus its
    value at the first sample: the mid-span deflection of a rod from three of its points'
    histories (each (n, 3), global; the rigid offset of points off the axis removed)."""
    a, m, b = (np.asarray(x, float)[:, :2] for x in (pin_a, mid, pin_b))
    chord = b - a
    n = np.stack([-chord[:, 1], chord[:, 0]], axis=1) / np.linalg.norm(chord, axis=1)[:, None]
    d = np.einsum("ij,ij->i", m - a, n)
    return d - d[0]


__all__ = ["SliderCrank", "chord_deflection"]
