"""A Newton step that stalls below the round-off of its positions is converged
(integrate.moreau_jean.newton_iterate.roundoff_momenta, at_roundoff; issue 35: zero steps not
converged).

A body at rest on a joint has a momentum scale of round-off only (the joint's impulse against
the round-off of its constraint, ~1e-8 N s on the shipped arm), so its residual relative to
that scale stalls at 1e-9..5e-8 of it, above rtol = 1e-10, while the residual itself is
~2e-16 N s: five orders of magnitude below eps m L / h = 2e-11 N s, the momentum of a
one-ulp position error over the step. The scheme accepts such a stalled step as converged."""

from __future__ import annotations

import tomllib
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from flexmvm.integrate.moreau_jean.newton_iterate import at_roundoff, roundoff_momenta

EPS = np.finfo(float).eps


def _body(mass, X):
    return SimpleNamespace(inv=SimpleNamespace(mass=mass), X=np.asarray(X, dtype=float))


def test_roundoff_momentum_is_eps_mass_extent():
    """eps m L with L the largest extent of the undeformed nodes (a 0.3 x 0.02 x 0.01 m box:
    L = 0.3 m), exactly."""
    box = np.array([[0, 0, 0], [0.3, 0.02, 0.01], [0.1, 0.0, 0.005]])
    p = roundoff_momenta([_body(0.16, box), _body(2.0, [[0, 0, 0], [0, 0, 0.5]])])
    assert p == pytest.approx([EPS * 0.16 * 0.3, EPS * 2.0 * 0.5], rel=1e-15)


def test_at_roundoff_needs_every_body_below_its_floor():
    """At h = 0.5 us the floors are p / h; one body above its own floor (even if below the
    other's) keeps the step iterating."""
    p = np.array([1e-17, 1e-15])  # [kg m]
    h = 0.5e-6
    low = [np.full(6, 0.9e-17 / h), np.full(9, 0.9e-15 / h)]
    assert at_roundoff(low, p, h)
    high = [np.full(6, 1.1e-17 / h), np.full(9, 0.9e-15 / h)]
    assert not at_roundoff(high, p, h)
    assert at_roundoff([np.zeros(0), np.zeros(3)], p, h)  # a body with no rows


@pytest.mark.validation
def test_shipped_arm_starts_from_rest_with_every_step_converged():
    """The first 3 us of scenarios/arm_stop.toml in full FE (38,502 DOF, ~30 s): its first
    step, from rest with the motor's torque sin^2 ~ 0, stalled at a residual of 1.6e-8 of its
    round-off scale and was counted not converged (measured before this check: 1 of 5 steps)."""
    from flexmvm.assembly.build import build_scenario
    from flexmvm.integrate.driver import simulate
    from flexmvm.scenarios.load import scenario_from_dict

    scenarios = Path(__file__).parents[1] / "scenarios"
    data = tomllib.loads((scenarios / "arm_stop.toml").read_text())
    data["time"].update(t_end_s=3e-6, output_dt_s=3e-6, output_contact_dt_s=3e-6)
    built = build_scenario(scenario_from_dict(data, base_dir=scenarios))
    res = simulate(built.system, built.states, built.grid, built.probes)
    assert res.n_steps == 5 and res.steps_on_roundoff_floor == 0
