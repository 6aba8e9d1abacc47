"""theta of the Moreau-Jean step (moreau_jean.py) as a property of the step size h.

Fixed: theta for every h (1/2: the implicit midpoint rule, second order; above 1/2 first order,
error ~ (theta - 1/2) h). With a damping time tau (a scenario's time.hf_damping_time_s):

    theta(h) = min(1, 1/2 + h / (4 tau))

for every step the driver takes (dt_s 2^k in free flight, dt_s / 2^k when a step is cut). Per
step the amplification at omega h >> 1 is -(1 - theta) / theta = -(2 - x) / (2 + x), x = h / tau,
whose logarithm is -2 artanh(x / 2) = -x - x^3 / 12 - ...: what no step resolves decays as
exp(-t / tau) to (h / tau)^3 / 12 for h << tau, and never slower at any h (theta = 1 from
h = 2 tau on: amplification 0). The local error (theta - 1/2) h^2 y'' is O(h^3): second order
(tests/test_theta_scheme.py; docs/contact_law.md, "theta = 1/2 + h / (4 tau)").
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
    None, else min(1, 1/2 + h / (4 damping_time_s)) (module doc). InputError for a theta outside
    [1/2, 1] or a damping time that is not > 0."""

    theta: float = DEFAULT_THETA
    damping_time_s: float | None = None

    def __post_init__(self):
        if self.damping_time_s is not None:
            if not self.damping_time_s > 0:
                raise InputError(f"theta: damping time must be > 0 s, got {self.damping_time_s!r}")
        elif not 0.5 <= self.theta <= 1.0:
            raise InputError(f"theta must be in [0.5, 1], got {self.theta!r}")

    def at(self, h: float) -> float:
        """theta of a step of h [s]."""
        if self.damping_time_s is None:
            return self.theta
        return min(1.0, theta_for_damping_time(h, self.damping_time_s))

    def __call__(self, h: float) -> float:
        return self.at(h)

    @property
    def order(self) -> int:
        """Order of accuracy for smooth motion: 2 at theta = 1/2 or with a damping time
        (theta - 1/2 = O(h)), 1 for a fixed theta > 1/2."""
        return 2 if (self.damping_time_s is not None or self.theta == 0.5) else 1
