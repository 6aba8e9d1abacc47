"""theta of the Moreau-Jean step (moreau_jean/scheme.py) as a property of the step size h.

Fixed: theta for every h (1/2: the implicit midpoint rule, second order; above 1/2 first order,
error ~ (theta - 1/2) h). With a damping time tau (a scenario's time.hf_damping_time_s) and
the contact step dt_c (time.dt_s, the step the driver takes while a contact is active or near):

    theta(h) = min(1, 1/2 + h / (4 tau))          for h <= dt_c (the contact step, cut steps),
    theta(h) = 1/2 + dt_c^2 / (4 tau h)           for h >  dt_c (the free-flight steps).

At and below dt_c, per step the amplification at omega h >> 1 is -(1 - theta) / theta =
-(2 - x) / (2 + x), x = h / tau, whose logarithm is -2 artanh(x / 2) = -x - x^3 / 12 - ...: what
the contact step does not resolve decays as exp(-t / tau) to (h / tau)^3 / 12 for h << tau, and
never slower at any h (theta = 1 from h = 2 tau on: amplification 0).

Above dt_c, (theta - 1/2) h = dt_c^2 / (4 tau) is kept: the damping of what a step resolves
(omega h << 1), an amplitude decay rate of (theta - 1/2) omega^2 h / 2 = omega^2 dt_c^2 / (8 tau),
is then the same at every free-flight step as at the contact step, where theta(h) = 1/2 +
h / (4 tau) would raise it as h^2 (16 x at the seed scenarios' 2 us free-flight step: the rods'
waves, resolved, lost 1.6e-3 of the energy in 1.34 ms of free flight, against 1.1e-4 with this
rule; docs/notes/2026-11-29-seed-window.md). What the free-flight step does not resolve decays
at (1 / tau) (dt_c / h)^2: the contact's high-frequency content is gone by then (it decayed as
exp(-t / tau) through the contact steps).

Both branches keep theta - 1/2 = O(h) when the steps are refined together (dt_c and h halved):
the local error (theta - 1/2) h^2 y'' is O(h^3), second order (tests/test_theta_scheme.py,
tests/test_shipped_window.py; docs/contact_law.md, "theta = 1/2 + h / (4 tau)"). Without a
contact step (contact_step_s None) the first branch applies at every h.

Chosen damping time (a scenario's ``hf_damping_time_s = "auto"``, auto_damping_time). tau trades
the two: the shorter, the faster the content the contact step cannot resolve decays (exp(-t /
tau)), and the more energy the resolved motion loses: a mode of angular frequency omega with
omega h << 1 loses its energy at the rate omega^2 dt_c^2 / (4 tau) (twice the amplitude rate
above) at every step size, so over a window T the share 1 - exp(-omega^2 dt_c^2 T / (4 tau)).
The resolved motion that matters is what the contact excites: a pulse of duration T_c (a
half-sine's spectrum has its main lobe below 3 pi / T_c). The chosen tau is the shortest
whose loss at omega_c = 3 pi / T_c over the window stays below AUTO_WINDOW_LOSS:

    tau = omega_c^2 dt_c^2 T / (4 AUTO_WINDOW_LOSS),   at least dt_c / 2 (theta <= 1).

Measured against the hand-set 12.5 us of the seed scenarios (T_c from the 1D wave-Hertz
solution, theory.scenario.theory_pulse): rod_impact.toml (T_c 646 us, T 2 ms) 26.6 us,
rod_impact_short.toml (177 us, 0.25 ms) 44 us, sphere_block.toml (Hertz 86.7 us, 0.2 ms)
148 us; 12.5 us there gives the estimate 2.1e-3, 3.5e-3 and 1.2e-2. The content above omega_c
(the mesh's, at the step's scale) is what tau then damps; what it took is in the run's energy
ledger (numerical dissipation, summary.json ``numerical_dissipation_J``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from flexmvm.errors import InputError
from flexmvm.integrate import DEFAULT_THETA

#: The share of its energy the contact's resolved motion (omega_c = 3 pi / T_c) may lose to the
#: scheme's damping over the window, for the chosen damping time (module doc)
AUTO_WINDOW_LOSS = 1e-3


def auto_damping_time(dt_s: float, t_end_s: float, contact_duration_s: float) -> float:
    """The damping time tau [s] of ``hf_damping_time_s = "auto"`` (module doc): the shortest
    whose energy loss of a mode at 3 pi / contact_duration_s over t_end_s is AUTO_WINDOW_LOSS
    at the contact step dt_s; at least dt_s / 2. InputError for a value that is not > 0."""
    for name, x in (
        ("dt_s", dt_s),
        ("t_end_s", t_end_s),
        ("contact_duration_s", contact_duration_s),
    ):
        if not x > 0:
            raise InputError(f"auto damping time: {name} must be > 0 s, got {x!r}")
    omega = 3.0 * math.pi / contact_duration_s
    return max((omega * dt_s) ** 2 * t_end_s / (4.0 * AUTO_WINDOW_LOSS), 0.5 * dt_s)


def theta_for_damping_time(h: float, tau_s: float) -> float:
    """1/2 + h / (4 tau_s) (module doc; above 1 for h > 2 tau_s: ThetaRule caps it)."""
    return 0.5 + h / (4.0 * tau_s)


@dataclass(frozen=True)
class ThetaRule:
    """theta(h) of the step of size h [s]: ``theta`` for every h when ``damping_time_s`` is
    None, else the module doc's rule: min(1, 1/2 + h / (4 damping_time_s)) up to
    ``contact_step_s`` (every h when it is None) and 1/2 + contact_step_s^2 /
    (4 damping_time_s h) above it. InputError for a theta outside [1/2, 1], a damping time or
    a contact step that is not > 0."""

    theta: float = DEFAULT_THETA
    damping_time_s: float | None = None
    contact_step_s: float | None = None

    def __post_init__(self):
        if self.damping_time_s is not None:
            if not self.damping_time_s > 0:
                raise InputError(f"theta: damping time must be > 0 s, got {self.damping_time_s!r}")
            if self.contact_step_s is not None and not self.contact_step_s > 0:
                raise InputError(f"theta: contact step must be > 0 s, got {self.contact_step_s!r}")
        elif not 0.5 <= self.theta <= 1.0:
            raise InputError(f"theta must be in [0.5, 1], got {self.theta!r}")

    def at(self, h: float) -> float:
        """theta of a step of h [s]."""
        if self.damping_time_s is None:
            return self.theta
        dt_c = self.contact_step_s
        if dt_c is not None and h > dt_c * (1.0 + 1e-9):
            h = dt_c * dt_c / h  # the same (theta - 1/2) h as at the contact step
        return min(1.0, theta_for_damping_time(h, self.damping_time_s))

    def __call__(self, h: float) -> float:
        return self.at(h)

    @property
    def order(self) -> int:
        """Order of accuracy for smooth motion: 2 at theta = 1/2 or with a damping time
        (theta - 1/2 = O(h) as the steps are refined), 1 for a fixed theta > 1/2."""
        return 2 if (self.damping_time_s is not None or self.theta == 0.5) else 1
