"""The position-level contact law (issue 14 part 3): [[contacts]] law = "position" holds the gap
at the end of the step, g + h (theta u_N+ + (1 - theta) u_N-) >= 0, instead of Moreau's
u_N+ >= beta max(0, -g) / h; with the contact nodes' mass redistributed (redistribute_mass) it
is the scheme of Khenous, Laborde and Renard (2008) for theta = 1/2.

tests/data/short_flat_impact.toml: brass 50 mm onto aluminium 50 mm, r = 5 mm, flat ends,
0.21 m/s, both full FE, h = 0.25 us, contact over 0..~20 us (2 L / c2), 40 us run.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

from flexmvm.constraints.contact import ContactLaw
from flexmvm.contact.pairs import PointToSurfaceContact
from flexmvm.errors import InputError
from flexmvm.integrate import driver
from flexmvm.integrate.moreau_jean import MoreauJeanIntegrator
from flexmvm.scenarios import load_scenario, scenario_from_dict
from flexmvm.scenarios.build import build_scenario
from flexmvm.scenarios.problems import ScenarioError

CASE = Path(__file__).parent / "data" / "short_flat_impact.toml"


def _scenario(law: str, redistribute: bool, theta: float = 0.5):
    data = load_scenario(CASE).model_dump(mode="json")
    data["time"]["theta"] = theta
    data["contacts"][0].update(law=law, redistribute_mass=redistribute)
    return scenario_from_dict(data)


@functools.cache
def _run(law: str, redistribute: bool, theta: float = 0.5):
    """The run and, per contact step, (h, gaps, lower, u_N-, u_N+, impulses) of its rows."""
    sc = _scenario(law, redistribute, theta)
    built = build_scenario(sc)
    steps = []

    class Recording(MoreauJeanIntegrator):
        def step(self, t, states, h):
            res = super().step(t, states, h)
            c = res.contact
            if c.rows.m:
                u = [sum(c.rows.body_matrix(b) @ s[b].v for b in c.rows.blocks)
                     for s in (states, res.states)]
                steps.append((h, c.gaps, c.lower, u[0], u[1], res.contact_impulses))
            return res

    original = driver.MoreauJeanIntegrator
    driver.MoreauJeanIntegrator = Recording
    try:
        run = driver.simulate(built.system, built.states, built.grid, built.probes)
    finally:
        driver.MoreauJeanIntegrator = original
    return run, steps


def _energy_error(run) -> float:
    E = run.total_energy
    return float(np.abs(E - E[0]).max() / E[0])


@pytest.mark.parametrize("redistribute, theta", [(False, 0.5), (True, 0.55)])
def test_end_gap_held_to_round_off(redistribute, theta):
    """Every row's end gap g + h (theta u_N+ + (1 - theta) u_N-) is >= 0 and, where the row
    carries an impulse, 0: both to 1e-9 of the step's approach h v0 (round-off of the LCP and
    of the rows); the pairs close over the impact (rows with impulse at many steps). Mass
    redistribution needs theta > 1/2 (refused at 1/2: test_redistribution_needs_damping)."""
    _, steps = _run("position", redistribute, theta)
    scale = 0.25e-6 * 0.21
    worst_open = worst_active = 0.0
    n_active = 0
    for h, g, lower, um, up, lam in steps:
        end = g + h * (theta * up + (1.0 - theta) * um)
        assert np.allclose(lower, -(g + (1.0 - theta) * h * um) / (theta * h), rtol=0,
                           atol=1e-12)
        worst_open = max(worst_open, float(-end.min()))
        on = lam > 0
        n_active += int(on.sum())
        if on.any():
            worst_active = max(worst_active, float(np.abs(end[on]).max()))
    assert n_active > 500
    assert worst_open <= 1e-9 * scale
    assert worst_active <= 1e-9 * scale


def test_redistribution_needs_damping():
    """Massless contact nodes at theta = 1/2 (v+ = 2 v_m - v-, neutrally stable) grew without
    bound on the hemispherical short seed case at h = 0.25 us (docs/contact_law.md): the
    scenario is refused with a one-line reason."""
    with pytest.raises(ScenarioError, match="theta > 0.5"):
        _scenario("position", True, theta=0.5)


def test_energy_conserved_through_the_impact():
    """theta = 1/2 with the position law: the largest |E(t) - E(0)| / E(0) over the 40 us (the
    whole impact and 20 us after) is below 1e-3: measured 4.5e-4 (5e-8 with the contact
    nodes' mass redistributed on this flat-on-flat case, but on the hemispherical short seed
    case at h = 0.25 us the massless nodes' end velocities grow instead, so that combination
    is refused: docs/contact_law.md); the velocity law gains 2.8e-3."""
    assert _energy_error(_run("position", False)[0]) < 1e-3
    assert _energy_error(_run("velocity", False)[0]) > 2 * _energy_error(_run("position", False)[0])


def test_law_default_and_checks():
    """velocity stays the default and dumps as before the key existed; position with a
    bonded contact is refused; a provider with the position law needs theta."""
    sc = load_scenario(CASE)
    assert sc.contacts[0].law is ContactLaw.VELOCITY
    dump = sc.model_dump(mode="json")["contacts"][0]
    assert "law" not in dump and "redistribute_mass" not in dump
    assert _scenario("position", False).model_dump(mode="json")["contacts"][0]["law"] == "position"
    data = sc.model_dump(mode="json")
    data["contacts"][0].update(law="position", kind="bonded")
    with pytest.raises(ScenarioError, match="position"):
        scenario_from_dict(data)
    built = build_scenario(_scenario("position", False, theta=0.55))
    c = built.system.contacts[0]
    assert c.law is ContactLaw.POSITION and c.theta == 0.55
    with pytest.raises(InputError, match="theta"):
        PointToSurfaceContact(built.system.bodies, c.slave, c.slave_nodes, c.master, c.surface,
                              law="position")
