"""Exact 1D wave solution of two colliding elastic rods (d'Alembert / characteristics).

Set-up and sign convention (global x axis):

- rod 1 occupies ``[-L1, 0]`` and moves rigidly at ``v0 > 0`` in +x; rod 2 occupies ``[0, L2]``
  and is at rest; their near ends touch at ``t = 0``. Both far ends are free.
- ``F >= 0`` is the compressive contact force: it pushes rod 1 in -x and rod 2 in +x.
- ``delta = x1_near - x2_near`` is the approach (``delta > 0``: overlap/indentation);
  the reported gap is ``gap_m = -delta``.

Each rod carries two travelling waves; ``v_out(t)`` is the particle velocity of the wave leaving
the near end at time t, ``v_in(t)`` that of the wave arriving there. With impedance
``Z = A sqrt(E rho)``, bar speed ``c = sqrt(E/rho)``, round trip ``T = 2L/c``:

    rod 1:  v1_out = v1_in - F/Z1,  v1_near = v0 + v1_in + v1_out,  v1_far = v0 + 2 v1_out(t-L1/c1)
    rod 2:  v2_out = v2_in + F/Z2,  v2_near = v2_in + v2_out,       v2_far = 2 v2_out(t-L2/c2)
    v_in(t) = v_out(t - T)   (a free end reflects a wave keeping its particle velocity; 0 for t < T)

so ``d(delta)/dt = v1_near - v2_near = w(t) - F (1/Z1 + 1/Z2)`` with the free approach rate
``w(t) = v0 + 2 v1_in(t) - 2 v2_in(t)`` known from the stored history.

Contact laws (``ContactLaw``):

- RIGID (flat ends, St Venant): in contact ``F = Z1 Z2/(Z1+Z2) * w`` (the two end velocities are
  equal), release when that F would be negative, re-contact when the gap closes again. All
  signals are piecewise constant in time, so the solution is computed *exactly* by an event-driven
  sweep over the wave fronts (breakpoints) and re-contact instants, then sampled on the grid.
- HERTZ: ``F = k max(delta, 0)^{3/2}``, ``k = 4/3 E* sqrt(R)``,
  ``1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2`` (Hertz 1882; Johnson, *Contact Mechanics*, ch. 4).
  The ODE for delta is integrated by classical RK4 with a fixed step; the delayed terms are taken
  from the stored history by linear interpolation (second-order accurate, F being continuous).
  Separation and re-contact follow from the sign of delta.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from flexmvm.errors import InputError, SolverError
from flexmvm.materials import Material

_MAX_EVENTS = 2_000_000
_MAX_STEPS = 50_000_000
_DEFAULT_STEPS_PER_ROUND_TRIP = 20_000


class ContactLaw(Enum):
    """Contact law between the near ends."""

    RIGID = "rigid"  # flat ends, St Venant: no relative approach while compressive
    HERTZ = "hertz"  # sphere of radius R on a flat: F = 4/3 E* sqrt(R) delta^{3/2}


def _positive(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InputError(f"{name} must be a finite number, got {value!r}")
    if value <= 0:
        raise InputError(f"{name} must be > 0, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class Rod1D:
    """Uniform elastic rod for the 1D wave model.

    length_m [m], area_m2 [m^2], E [Pa], rho [kg/m^3], nu [-] (used only by the Hertz modulus).
    Raises InputError unless all are finite, length, area, E, rho > 0 and -1 < nu < 0.5.
    """

    length_m: float
    area_m2: float
    E: float
    rho: float
    nu: float

    def __post_init__(self) -> None:
        for key in ("length_m", "area_m2", "E", "rho"):
            _positive(f"Rod1D.{key}", getattr(self, key))
        nu = self.nu
        if isinstance(nu, bool) or not isinstance(nu, (int, float)) or not -1.0 < nu < 0.5:
            raise InputError(f"Rod1D.nu must be a number in (-1, 0.5), got {nu!r}")

    @classmethod
    def from_material(cls, material: Material, length_m: float, radius_m: float) -> Rod1D:
        """Round rod of the given material, length [m] and radius [m]."""
        radius = _positive("radius_m", radius_m)
        return cls(length_m, math.pi * radius**2, material.E, material.rho, material.nu)

    @property
    def c(self) -> float:
        """Bar wave speed sqrt(E/rho) [m/s]."""
        return math.sqrt(self.E / self.rho)

    @property
    def impedance(self) -> float:
        """Mechanical impedance Z = A sqrt(E rho) [N s/m]."""
        return self.area_m2 * math.sqrt(self.E * self.rho)

    @property
    def round_trip_s(self) -> float:
        """Time 2L/c for a wave to go to the far end and back [s]."""
        return 2.0 * self.length_m / self.c

    @property
    def mass(self) -> float:
        """rho A L [kg]."""
        return self.rho * self.area_m2 * self.length_m


def st_venant_force(rod1: Rod1D, rod2: Rod1D, v0: float) -> float:
    """First St Venant plateau of the contact force, v0 Z1 Z2 / (Z1 + Z2) [N]."""
    z1, z2 = rod1.impedance, rod2.impedance
    return v0 * z1 * z2 / (z1 + z2)


def hertz_stiffness(rod1: Rod1D, rod2: Rod1D, sphere_radius_m: float) -> float:
    """Hertz constant k = 4/3 E* sqrt(R) [N/m^1.5], 1/E* = sum (1 - nu^2)/E."""
    radius = _positive("sphere_radius_m", sphere_radius_m)
    e_star = 1.0 / ((1 - rod1.nu**2) / rod1.E + (1 - rod2.nu**2) / rod2.E)
    return 4.0 / 3.0 * e_star * math.sqrt(radius)


@dataclass(frozen=True)
class WaveParams:
    """Inputs of a solution: rods, impact speed v0 [m/s], law, sphere radius [m] and Hertz
    constant k [N/m^1.5] (HERTZ only, else None), step dt [s], end time t_end [s]."""

    rod1: Rod1D
    rod2: Rod1D
    v0: float
    law: ContactLaw
    sphere_radius_m: float | None
    hertz_k: float | None
    dt: float
    t_end: float


@dataclass(frozen=True, eq=False)
class WaveSolution:
    """Sampled solution on the grid ``t = k dt`` (all arrays shape (n,), SI units).

    contact_force [N] (compressive >= 0); gap_m [m] (negative = approach delta);
    v1_near, v1_far, v2_near, v2_far [m/s] near/far-end velocities in global x;
    v1_out, v2_out [m/s] particle velocity of the wave leaving each near end (perturbation
    of rod 1 about v0), from which the whole wave field is known.
    """

    t: np.ndarray
    contact_force: np.ndarray
    gap_m: np.ndarray
    v1_near: np.ndarray
    v1_far: np.ndarray
    v2_near: np.ndarray
    v2_far: np.ndarray
    v1_out: np.ndarray
    v2_out: np.ndarray
    law: ContactLaw
    params: WaveParams

    def _fields(
        self, rod: Rod1D, v_out: np.ndarray, t: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Left-/right-going particle velocities along the rod at time t, on a grid of the
        distance d from the near end: vL(d) = v_out(t - d/c), vR(d) = v_out(t - T + d/c)."""
        n_d = max(math.ceil(rod.length_m / (rod.c * self.params.dt)), 8) + 1
        d = np.linspace(0.0, rod.length_m, n_d)
        v_near_wave = np.interp(t - d / rod.c, self.t, v_out, left=0.0)
        v_far_wave = np.interp(t - rod.round_trip_s + d / rod.c, self.t, v_out, left=0.0)
        return d, v_near_wave, v_far_wave

    def _check_time(self, t: float) -> float:
        if not self.t[0] <= t <= self.t[-1]:
            raise InputError(f"time {t!r} s is outside the solution [0, {self.t[-1]!r}] s")
        return float(t)

    def rod_momenta_at(self, t: float) -> tuple[float, float]:
        """Linear momentum of rod 1 and of rod 2 at time t [kg m/s], integrated over the wave
        fields: rho A int (v_rigid + vL + vR) dx. Raises InputError outside the time span."""
        t = self._check_time(t)
        out = []
        for rod, v_out, v_rigid in (
            (self.params.rod1, self.v1_out, self.params.v0),
            (self.params.rod2, self.v2_out, 0.0),
        ):
            d, v_l, v_r = self._fields(rod, v_out, t)
            out.append(float(rod.rho * rod.area_m2 * np.trapezoid(v_rigid + v_l + v_r, d)))
        return out[0], out[1]

    def momentum_at(self, t: float) -> float:
        """Total linear momentum of both rods at time t [kg m/s] (see rod_momenta_at)."""
        return sum(self.rod_momenta_at(t))

    def energy_at(self, t: float) -> float:
        """Total mechanical energy at time t [J]: per rod rho A/2 int [(v_rigid + vL + vR)^2 +
        (vL - vR)^2] dx (kinetic + strain, the axial force being Z (vL - vR) for rod 1 and its
        mirror for rod 2), plus the Hertz contact energy 2/5 k delta^{5/2}."""
        t = self._check_time(t)
        total = 0.0
        for rod, v_out, v_rigid in (
            (self.params.rod1, self.v1_out, self.params.v0),
            (self.params.rod2, self.v2_out, 0.0),
        ):
            d, v_l, v_r = self._fields(rod, v_out, t)
            density = (v_rigid + v_l + v_r) ** 2 + (v_l - v_r) ** 2
            total += 0.5 * rod.rho * rod.area_m2 * np.trapezoid(density, d)
        if self.params.hertz_k is not None:
            delta = max(-float(np.interp(t, self.t, self.gap_m)), 0.0)
            total += 0.4 * self.params.hertz_k * delta**2.5
        return float(total)


def _step_value(times: list[float], values: list[float], s: float) -> float:
    """Right-continuous step function: the value of the last breakpoint <= s (0 before any)."""
    i = bisect.bisect_right(times, s)
    return values[i - 1] if i > 0 else 0.0


def _push(times: list[float], values: list[float], t: float, value: float, tol: float) -> None:
    last = values[-1] if values else 0.0
    if abs(value - last) > tol:
        times.append(t)
        values.append(value)


Steps = tuple[list[float], list[float]]


def _rigid_events(p: WaveParams) -> tuple[list[Steps], list[float], list[float]]:
    """Event-driven exact RIGID solution up to t_end.

    Returns the breakpoints/values of v1_out, v2_out and F (right-continuous step functions) as
    ``[(t1, val1), (t2, val2), (tf, valf)]`` and the knots (t, delta) of the piecewise-linear
    approach. Events: a wave front arriving at a near end (a breakpoint of v_out delayed by T),
    and re-contact (delta reaching 0 while closing).
    """
    r1, r2, v0 = p.rod1, p.rod2, p.v0
    z1, z2 = r1.impedance, r2.impedance
    zeff = z1 * z2 / (z1 + z2)
    big_t1, big_t2 = r1.round_trip_s, r2.round_trip_s
    tol = 1e-12 * min(big_t1, big_t2)
    vtol = 1e-13 * abs(v0)
    b1: list[float] = []
    w1: list[float] = []
    b2: list[float] = []
    w2: list[float] = []
    bf: list[float] = []
    wf: list[float] = []
    kt: list[float] = []
    kd: list[float] = []
    t, delta = 0.0, 0.0
    for _ in range(_MAX_EVENTS):
        v1_in = _step_value(b1, w1, t - big_t1 + tol)
        v2_in = _step_value(b2, w2, t - big_t2 + tol)
        w = v0 + 2.0 * v1_in - 2.0 * v2_in
        if delta >= 0.0 and w > 0.0:
            force, rel, delta = zeff * w, 0.0, 0.0
        else:
            force, rel = 0.0, w
        _push(b1, w1, t, v1_in - force / z1, vtol)
        _push(b2, w2, t, v2_in + force / z2, vtol)
        _push(bf, wf, t, force, vtol * zeff)
        kt.append(t)
        kd.append(delta)
        fronts = []
        for times, delay in ((b1, big_t1), (b2, big_t2)):
            i = bisect.bisect_right(times, t - delay + tol)
            if i < len(times):
                fronts.append(times[i] + delay)
        t_front = min(fronts, default=math.inf)
        t_touch = t + (-delta) / rel if (rel > 0.0 and delta < 0.0) else math.inf
        if t_touch <= t_front + tol:
            t_next, delta_next = (t_touch if t_touch < t_front - tol else t_front), 0.0
        else:
            t_next, delta_next = t_front, delta + rel * (t_front - t)
        if t_next >= p.t_end:
            kt.append(p.t_end)
            kd.append(delta + rel * (p.t_end - t))
            return [(b1, w1), (b2, w2), (bf, wf)], kt, kd
        t, delta = t_next, delta_next
    raise SolverError(
        f"RIGID wave solution needs more than {_MAX_EVENTS} events before t_end = {p.t_end!r} s; "
        "expected a shorter t_end"
    )


def _sample_steps(times: list[float], values: list[float], s: np.ndarray) -> np.ndarray:
    """Vectorized right-continuous step function (0 before the first breakpoint)."""
    vals = np.concatenate(([0.0], np.asarray(values, dtype=float)))
    idx = np.searchsorted(np.asarray(times, dtype=float), s, side="right")
    return vals[idx]


def _solve_rigid(p: WaveParams, t: np.ndarray) -> WaveSolution:
    """RIGID law: exact event-driven solution, sampled (right-continuously) on the grid t."""
    ((b1, w1), (b2, w2), (bf, wf)), kt, kd = _rigid_events(p)
    r1, r2 = p.rod1, p.rod2
    v1_out, v2_out = _sample_steps(b1, w1, t), _sample_steps(b2, w2, t)
    v1_in = _sample_steps(b1, w1, t - r1.round_trip_s)
    v2_in = _sample_steps(b2, w2, t - r2.round_trip_s)
    return WaveSolution(
        t=t,
        contact_force=_sample_steps(bf, wf, t),
        gap_m=-np.interp(t, kt, kd),
        v1_near=p.v0 + v1_in + v1_out,
        v1_far=p.v0 + 2.0 * _sample_steps(b1, w1, t - r1.length_m / r1.c),
        v2_near=v2_in + v2_out,
        v2_far=2.0 * _sample_steps(b2, w2, t - r2.length_m / r2.c),
        v1_out=v1_out,
        v2_out=v2_out,
        law=p.law,
        params=p,
    )


def _delayed(v_out: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """v_out at fractional grid positions pos (index units), linear, 0 before t = 0."""
    return np.interp(pos, np.arange(v_out.size, dtype=float), v_out, left=0.0)


def _hertz_chunk(
    delta0: float, w: list[float], w_mid: list[float], kz: float, dt: float
) -> list[float]:
    """Classical RK4 for d(delta)/dt = w(t) - kz max(delta,0)^1.5 over len(w_mid) steps.

    w: free approach rate at the len(w_mid)+1 grid instants, w_mid: at the step midpoints.
    Returns the approach delta [m] at the end of each step."""
    out = []
    d = delta0
    half = 0.5 * dt
    for j, wm in enumerate(w_mid):
        wa, wb = w[j], w[j + 1]
        k1 = wa - kz * (d**1.5 if d > 0.0 else 0.0)
        x = d + half * k1
        k2 = wm - kz * (x**1.5 if x > 0.0 else 0.0)
        x = d + half * k2
        k3 = wm - kz * (x**1.5 if x > 0.0 else 0.0)
        x = d + dt * k3
        k4 = wb - kz * (x**1.5 if x > 0.0 else 0.0)
        d += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        out.append(d)
    return out


def _solve_hertz(p: WaveParams, t: np.ndarray) -> WaveSolution:
    """HERTZ law: RK4 on the approach with the delayed wave terms interpolated from the history.

    The grid is advanced in chunks shorter than the shorter round trip, so every delayed value
    a chunk needs is already known; the free approach rate w is then computed for the whole chunk
    at once and only the scalar ODE runs in a Python loop.
    """
    r1, r2, v0, dt = p.rod1, p.rod2, p.v0, p.dt
    if p.hertz_k is None:
        raise InputError("HERTZ solution needs the Hertz constant k, got None")
    k = p.hertz_k
    z1, z2 = r1.impedance, r2.impedance
    kz = k * (1.0 / z1 + 1.0 / z2)
    n = t.size
    p1, p2 = r1.round_trip_s / dt, r2.round_trip_s / dt
    chunk = math.floor(min(p1, p2)) - 1
    v1_out, v2_out = np.zeros(n), np.zeros(n)
    v1_in, v2_in = np.zeros(n), np.zeros(n)
    delta, force = np.zeros(n), np.zeros(n)
    k0 = 0
    while k0 < n - 1:
        k1 = min(k0 + chunk, n - 1)
        idx = np.arange(k0, k1 + 1, dtype=float)
        mid = idx[:-1] + 0.5
        v1_in[k0 : k1 + 1] = _delayed(v1_out, idx - p1)
        v2_in[k0 : k1 + 1] = _delayed(v2_out, idx - p2)
        w = v0 + 2.0 * v1_in[k0 : k1 + 1] - 2.0 * v2_in[k0 : k1 + 1]
        w_mid = v0 + 2.0 * _delayed(v1_out, mid - p1) - 2.0 * _delayed(v2_out, mid - p2)
        delta[k0 + 1 : k1 + 1] = _hertz_chunk(delta[k0], w.tolist(), w_mid.tolist(), kz, dt)
        force[k0 + 1 : k1 + 1] = k * np.maximum(delta[k0 + 1 : k1 + 1], 0.0) ** 1.5
        v1_out[k0 + 1 : k1 + 1] = v1_in[k0 + 1 : k1 + 1] - force[k0 + 1 : k1 + 1] / z1
        v2_out[k0 + 1 : k1 + 1] = v2_in[k0 + 1 : k1 + 1] + force[k0 + 1 : k1 + 1] / z2
        k0 = k1
    if not np.all(np.isfinite(delta)):
        raise SolverError(f"HERTZ wave solution diverged (non-finite approach) with dt = {dt!r} s")
    grid = np.arange(n, dtype=float)
    return WaveSolution(
        t=t,
        contact_force=force,
        gap_m=-delta,
        v1_near=v0 + v1_in + v1_out,
        v1_far=v0 + 2.0 * _delayed(v1_out, grid - r1.length_m / (r1.c * dt)),
        v2_near=v2_in + v2_out,
        v2_far=2.0 * _delayed(v2_out, grid - r2.length_m / (r2.c * dt)),
        v1_out=v1_out,
        v2_out=v2_out,
        law=p.law,
        params=p,
    )


def two_rod_impact(
    rod1: Rod1D,
    rod2: Rod1D,
    v0: float,
    t_end: float,
    law: ContactLaw,
    sphere_radius_m: float | None = None,
    dt: float | None = None,
) -> WaveSolution:
    """Two-rod impact by the 1D wave equation (module docstring: equations and sign convention).

    rod1 strikes rod2 at v0 [m/s] (> 0, in +x); solution on ``t = 0, dt, ..., <= t_end`` [s].
    sphere_radius_m [m]: radius R of rod 1's spherical end, required by HERTZ, refused by RIGID.
    dt [s]: grid step, default min(T1, T2)/20000; it must resolve the waves (dt <= min(T)/100).
    RIGID is exact at the grid instants; HERTZ is second-order accurate in dt.
    Raises InputError on bad arguments, SolverError if the solution cannot be computed.
    """
    if not isinstance(rod1, Rod1D) or not isinstance(rod2, Rod1D):
        raise InputError(f"rods must be Rod1D, got {type(rod1).__name__} and {type(rod2).__name__}")
    if not isinstance(law, ContactLaw):
        raise InputError(f"law must be a ContactLaw (RIGID or HERTZ), got {law!r}")
    v0 = _positive("impact speed v0 [m/s]", v0)
    t_end = _positive("t_end [s]", t_end)
    t_min = min(rod1.round_trip_s, rod2.round_trip_s)
    dt = t_min / _DEFAULT_STEPS_PER_ROUND_TRIP if dt is None else _positive("dt [s]", dt)
    if dt > t_min / 100.0:
        raise InputError(
            f"dt = {dt!r} s is too coarse; expected dt <= min(2L/c)/100 = {t_min / 100.0!r} s"
        )
    n_steps = math.floor(t_end / dt * (1.0 + 1e-12))
    if n_steps < 2 or n_steps > _MAX_STEPS:
        raise InputError(f"t_end/dt = {t_end / dt:.4g} steps; expected between 2 and {_MAX_STEPS}")
    if law is ContactLaw.HERTZ:
        if sphere_radius_m is None:
            raise InputError("HERTZ contact needs sphere_radius_m (rod 1's end radius), got None")
        hertz_k: float | None = hertz_stiffness(rod1, rod2, sphere_radius_m)
        radius: float | None = float(sphere_radius_m)
    else:
        if sphere_radius_m is not None:
            raise InputError(f"RIGID contact takes no sphere_radius_m, got {sphere_radius_m!r}")
        hertz_k = radius = None
    params = WaveParams(rod1, rod2, v0, law, radius, hertz_k, dt, t_end)
    t = np.arange(n_steps + 1, dtype=float) * dt
    return _solve_hertz(params, t) if law is ContactLaw.HERTZ else _solve_rigid(params, t)
