"""A rigid sphere striking a free Timoshenko beam through a Hertz spring (Timoshenko 1913).

The classic model of transverse impact (S. Timoshenko, "Zur Frage nach der Wirkung eines
Stosses auf einen Balken", Z. Math. Phys. 62, 1913, 198; Goldsmith, "Impact", 1960, sect.
4.5): the beam by its modes, the sphere as a point mass, and between them the quasi-static
Hertz law of a sphere of radius R pressing on a flat (Johnson, "Contact Mechanics", eq. 4.23)

    F = k_H s^(3/2),  k_H = 4/3 E* sqrt(R),   s the local indentation [m], F >= 0 [N].

Coordinates along the impact direction (the sphere's approach, positive into the beam),
from the instant of first touch: u [m] the sphere's displacement, w(x) the beam's deflection
and psi(x) its section rotation (flexmvm.theory.timoshenko), the contact at x_c:

    m u'' = -F,    q_i'' + omega_i^2 q_i = phi_i(x_c) F,    w(x, t) = sum_i phi_i(x) q_i(t)
    delta = u - w(x_c) = s + c_r F                                       (approach [m])

with the N lowest mass-normalized free-free modes phi_i (the two rigid ones included) and
the residual flexibility c_r = sum_{i > N} phi_i(x_c)^2 / omega_i^2 [m/N] of the modes left
out, which answer the pulse quasi-statically (the mode-acceleration correction; Craig and
Kurdila, "Fundamentals of Structural Dynamics", 2006, sect. 14.6). It makes the solution
converge fast in N: a point load on a Timoshenko beam excites modes whose static share
phi_i(x_c)^2 / omega_i^2 only falls as 1/i^2 once shear dominates. Contact holds while
delta > 0; the sphere is free otherwise.

The system is integrated with scipy's solve_ivp from one contact event to the next (terminal
events at delta = 0, so no step straddles the kink of F), by default with DOP853: with the
quasi-static correction the retained spectrum stops near omega_N and the problem is not stiff
(the step is set by accuracy, not stability); "Radau" is accepted too and given the exact
Jacobian, for many modes. Linear momentum m u' + rho A int w_t dx and energy (kinetic,
modal strain, 2/5 k_H s^(5/2) + 1/2 c_r F^2) are conserved by the equations; the solution
reports both so that the integration error can be read off. A ``local_law`` F = k s^p
replaces Hertz's where the local compliance of another model is to be matched.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from flexmvm.errors import InputError, SolverError
from flexmvm.theory.hertz import positive
from flexmvm.theory.timoshenko import BeamModes, TimoshenkoBeam, free_free_modes

_MAX_SEGMENTS = 1000  # contact events in one solution (each a restart of solve_ivp)
_METHODS = ("DOP853", "RK45", "Radau", "BDF", "LSODA")


@dataclass(frozen=True)
class SphereOnBeam:
    """The impact: ``beam`` struck at ``contact_x_m`` [m from its end x = 0] by a rigid
    sphere of ``sphere_mass_kg`` and ``sphere_radius_m`` at ``speed_mps`` (normal to the
    beam), ``e_star_pa`` [Pa] the Hertz effective modulus. n_modes: modes kept (the two
    rigid ones counted); n_elements: 1D elements of the beam; residual_flexibility: the
    quasi-static correction of the modes left out (module doc); local_law: (k [N/m^p], p >= 1),
    a local contact law F = k s^p in place of Hertz's (to study the local compliance of a
    model that is not Hertz's; None: Hertz, k_H and 3/2)."""

    beam: TimoshenkoBeam
    contact_x_m: float
    sphere_radius_m: float
    sphere_mass_kg: float
    e_star_pa: float
    speed_mps: float
    n_modes: int = 40
    n_elements: int = 200
    residual_flexibility: bool = True
    local_law: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        for name in ("sphere_radius_m", "sphere_mass_kg", "e_star_pa", "speed_mps"):
            positive(name, getattr(self, name))
        if not 0.0 < self.contact_x_m < self.beam.length_m:
            raise InputError(
                f"contact_x_m: expected inside the beam (0, {self.beam.length_m}) "
                f"m, got {self.contact_x_m!r}"
            )
        if self.local_law is not None:
            positive("local_law k", self.local_law[0])
            if not (math.isfinite(self.local_law[1]) and self.local_law[1] >= 1.0):
                raise InputError(f"local_law exponent: expected >= 1, got {self.local_law[1]!r}")
        if not 2 <= self.n_modes <= 2 * (self.n_elements + 1):
            raise InputError(
                f"n_modes: expected 2 .. {2 * (self.n_elements + 1)} (the two "
                f"rigid-body modes and elastic ones), got {self.n_modes!r}"
            )

    @property
    def hertz_k(self) -> float:
        """k_H = 4/3 E* sqrt(R) [N/m^1.5] (sphere on a flat)."""
        return 4.0 / 3.0 * self.e_star_pa * math.sqrt(self.sphere_radius_m)

    @property
    def contact_law(self) -> tuple[float, float]:
        """(k, p) of the local law F = k s^p: local_law, or Hertz's (k_H, 3/2)."""
        return (
            (self.hertz_k, 1.5)
            if self.local_law is None
            else (float(self.local_law[0]), float(self.local_law[1]))
        )

    def modes(self) -> BeamModes:
        """All free-free modes of the beam's n_elements elements, a node at the contact (a
        point load at a node: the static flexibility there is exact); probes elsewhere are
        read through the element's interpolation."""
        return free_free_modes(self.beam, self.n_elements, (self.contact_x_m,))

    def solve(
        self,
        t_end_s: float,
        dt_out_s: float,
        *,
        probes_x_m: tuple[float, ...] = (),
        rtol: float = 1e-10,
        method: str = "DOP853",
    ) -> BeamImpactSolution:
        """The history on t = 0, dt_out_s, ... <= t_end_s [s] (t = 0 the first touch), with
        w_t and psi_t at probes_x_m [m]. InputError on bad arguments, SolverError if the
        integration fails."""
        t_end = positive("t_end_s", t_end_s)
        dt = positive("dt_out_s", dt_out_s)
        if method not in _METHODS:
            raise InputError(f"method: expected one of {', '.join(_METHODS)}, got {method!r}")
        if not 0 < rtol < 1e-3:
            raise InputError(f"rtol: expected 0 < rtol < 1e-3, got {rtol!r}")
        if t_end / dt > 1e7:
            raise InputError(f"t_end_s / dt_out_s = {t_end / dt:.3g}: expected <= 1e7 samples")
        return _solve(self, t_end, dt, tuple(float(x) for x in probes_x_m), rtol, method)


@dataclass(frozen=True)
class BeamImpactSolution:
    """The history of a SphereOnBeam on the grid t (nt,) [s] (0: first touch): contact force
    [N], approach delta [m] (> 0 in contact), sphere velocity [m/s], beam velocity and rate
    of rotation at the probes (nt, n_probes) [m/s, rad/s], linear momentum [kg m/s] and
    energy [J] of the whole system, the contact intervals [(t_close, t_open)] from the
    events [s] (an open interval ends at t_end), the number of right-hand-side evaluations,
    and the modes (omega of the kept ones) used."""

    t: np.ndarray
    force: np.ndarray
    approach: np.ndarray
    sphere_velocity: np.ndarray
    probe_w_t: np.ndarray
    probe_psi_t: np.ndarray
    momentum: np.ndarray
    energy: np.ndarray
    contacts: tuple[tuple[float, float], ...]
    n_rhs: int
    omega_kept: np.ndarray
    residual_flexibility_m_per_n: float


def _check_finite(name: str, y: np.ndarray) -> None:
    if not np.all(np.isfinite(y)):
        raise SolverError(f"sphere on beam: {name} is not finite; expected a finite solution")


class _Model:
    """The kept modes at the contact and the probes, and the contact law (module doc)."""

    def __init__(self, imp: SphereOnBeam, probes_x_m: tuple[float, ...]):
        modes = imp.modes()
        n = imp.n_modes
        shapes, omega = modes.shapes, modes.omega
        phi_all = (modes.at([imp.contact_x_m])[0] @ shapes)[0]
        static = np.zeros_like(omega)
        static[n:] = phi_all[n:] / omega[n:] ** 2  # all elastic: n >= 2
        self.n, self.omega, self.omega2 = n, omega[:n], omega[:n] ** 2
        self.phi_c = phi_all[:n]
        self.c_r = float(phi_all @ static) if imp.residual_flexibility else 0.0
        nw, npsi = modes.at(probes_x_m) if probes_x_m else (np.zeros((0, shapes.shape[0])),) * 2
        self.probe_w, self.probe_psi = nw @ shapes[:, :n], npsi @ shapes[:, :n]
        on = 1.0 if imp.residual_flexibility else 0.0
        self.res_w, self.res_psi = on * (nw @ shapes) @ static, on * (npsi @ shapes) @ static
        translation = np.zeros(shapes.shape[0])
        translation[0::2] = 1.0
        self.momentum_per_mode = translation @ modes.M @ shapes[:, :n]  # rho A int phi_i dx
        self.m = imp.sphere_mass_kg
        self.k, self.p = imp.contact_law

    def indentation(self, delta: np.ndarray) -> np.ndarray:
        """s [m] with s + c_r k s^p = delta (0 where delta <= 0): Newton from an upper bound
        of the root, monotone on this convex increasing function (p >= 1)."""
        d = np.maximum(np.asarray(delta, dtype=float), 0.0)
        if self.c_r == 0.0:
            return d
        ck = self.c_r * self.k
        p = self.p
        s = np.minimum(d, (d / ck) ** (1.0 / p))
        for _ in range(60):
            sp1 = s ** (p - 1.0)
            step = (s + ck * s * sp1 - d) / (1.0 + p * ck * sp1)
            s = np.maximum(s - step, 0.0)
            if np.all(np.abs(step) <= 1e-15 * d + 1e-300):
                return s
        raise SolverError(
            "sphere on beam: the Hertz indentation did not converge in 60 "
            "Newton iterations; expected a few"
        )

    def stiffness(self, s: np.ndarray) -> np.ndarray:
        """dF / d delta [N/m] at indentation s: p k s^(p-1) / (1 + c_r p k s^(p-1))."""
        kt = self.p * self.k * np.maximum(s, 0.0) ** (self.p - 1.0)
        return kt / (1.0 + self.c_r * kt)

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        n = self.n
        delta = y[n] - self.phi_c @ y[:n]
        force = self.k * float(self.indentation(delta)) ** self.p if delta > 0.0 else 0.0
        out = np.empty_like(y)
        out[: n + 1] = y[n + 1 :]
        out[n + 1 : 2 * n + 1] = -self.omega2 * y[:n] + self.phi_c * force
        out[2 * n + 1] = -force / self.m
        return out

    def jac(self, t: float, y: np.ndarray) -> np.ndarray:
        n = self.n
        delta = y[n] - self.phi_c @ y[:n]
        kt = float(self.stiffness(self.indentation(delta))) if delta > 0.0 else 0.0
        g = np.concatenate([-self.phi_c, [1.0]])  # d delta / d (q, u)
        a = np.outer(np.concatenate([self.phi_c, [-1.0 / self.m]]), g) * kt
        a[np.arange(n), np.arange(n)] -= self.omega2
        out = np.zeros((2 * n + 2, 2 * n + 2))
        out[: n + 1, n + 1 :] = np.eye(n + 1)
        out[n + 1 :, : n + 1] = a
        return out


def _integrate(model: _Model, imp: SphereOnBeam, grid: np.ndarray, rtol: float, method: str):
    """solve_ivp from event to event (module doc); returns (y on the grid (nt, 2 n + 2),
    contact intervals, number of rhs evaluations)."""
    from flexmvm.theory.hertz import hertz_impact

    n, t_end = model.n, float(grid[-1])
    scale_d = hertz_impact(
        imp.sphere_radius_m, imp.speed_mps, imp.e_star_pa, imp.sphere_mass_kg
    ).delta_max_m
    root_m = math.sqrt(imp.beam.mass_kg)
    atol = rtol * np.concatenate(
        [
            np.full(n, root_m * scale_d),
            [scale_d],
            np.full(n, root_m * imp.speed_mps),
            [imp.speed_mps],
        ]
    )
    y = np.zeros(2 * n + 2)
    y[-1] = imp.speed_mps
    rows, events, n_rhs = [y.copy()], [0.0], 0
    in_contact, t0 = True, 0.0
    implicit = {"jac": model.jac} if method in ("Radau", "BDF", "LSODA") else {}
    for _ in range(_MAX_SEGMENTS):

        def gap_event(t, y):
            return y[n] - model.phi_c @ y[:n]

        # solve_ivp reads the event's options off the function object
        gap_event.terminal = True  # type: ignore[attr-defined]
        gap_event.direction = -1.0 if in_contact else 1.0  # type: ignore[attr-defined]
        sol = solve_ivp(
            model.rhs,
            (t0, t_end),
            y,
            method=method,
            t_eval=grid[grid > t0],
            events=gap_event,
            rtol=rtol,
            atol=atol,
            **implicit,
        )
        n_rhs += sol.nfev
        if sol.status < 0:
            raise SolverError(
                f"sphere on beam: solve_ivp ({method}) failed at t = {t0:.6g} s: {sol.message}"
            )
        rows.extend(sol.y.T)
        if sol.status == 0:
            intervals = list(zip(events[0::2], [*events[1::2], t_end]))
            return np.array(rows), tuple(intervals), n_rhs
        t0, y = float(sol.t_events[0][0]), sol.y_events[0][0].copy()
        events.append(t0)
        in_contact = not in_contact
    raise SolverError(
        f"sphere on beam: more than {_MAX_SEGMENTS} contact events before "
        f"t = {t_end:.6g} s; expected a few"
    )


def _solve(
    imp: SphereOnBeam,
    t_end: float,
    dt: float,
    probes_x_m: tuple[float, ...],
    rtol: float,
    method: str,
) -> BeamImpactSolution:
    model = _Model(imp, probes_x_m)
    n_out = math.floor(t_end / dt * (1.0 + 1e-12))
    grid = np.arange(n_out + 1) * dt
    y, contacts, n_rhs = _integrate(model, imp, grid, rtol, method)
    _check_finite("the state", y)
    n = model.n
    q, u, qd, ud = y[:, :n], y[:, n], y[:, n + 1 : 2 * n + 1], y[:, 2 * n + 1]
    delta = u - q @ model.phi_c
    s = model.indentation(delta)
    force = model.k * s**model.p
    force_rate = model.stiffness(s) * (ud - qd @ model.phi_c) * (delta > 0.0)
    energy = (
        0.5 * model.m * ud**2
        + 0.5 * np.sum(qd**2 + model.omega2 * q**2, axis=1)
        + model.k * s ** (model.p + 1.0) / (model.p + 1.0)
        + 0.5 * model.c_r * force**2
    )
    return BeamImpactSolution(
        t=grid,
        force=force,
        approach=delta,
        sphere_velocity=ud,
        probe_w_t=qd @ model.probe_w.T + np.outer(force_rate, model.res_w),
        probe_psi_t=qd @ model.probe_psi.T + np.outer(force_rate, model.res_psi),
        momentum=model.m * ud + qd @ model.momentum_per_mode,
        energy=energy,
        contacts=contacts,
        n_rhs=n_rhs,
        omega_kept=model.omega,
        residual_flexibility_m_per_n=model.c_r,
    )


__all__ = ["BeamImpactSolution", "SphereOnBeam"]
