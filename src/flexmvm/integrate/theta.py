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
"""

from __future__ import annotations

from dataclasses import dataclass

from flexmvm.errors import InputError
from flexmvm.integrate import DEFAULT_THETA


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
