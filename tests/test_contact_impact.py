"""Contact and impact by constraints (issue 4) on a short flat-on-flat rod impact.

tests/data/short_flat_impact.toml: brass 50 mm onto aluminium 50 mm, r = 5 mm, 0.21 m/s, both
full FE (725 nodes each), Moreau-Jean theta = 0.55, h = 0.25 us. St Venant (1D): contact force
F0 = v0 Z1 Z2 / (Z1 + Z2) while 0 < t < 2 L / c2 (Z1 > Z2: the target's reflection ends it).
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

from flexmvm.materials import ALUMINIUM, BRASS
from flexmvm.runs.run import run_scenario
from flexmvm.scenarios import load_scenario, scenario_from_dict
from flexmvm.theory.wave import Rod1D, st_venant_force

CASE = Path(__file__).parent / "data" / "short_flat_impact.toml"
EPS = float(np.finfo(float).eps)  # machine round-off: n steps lose at most ~n EPS of |p|
L, R, V0 = 0.05, 0.005, 0.21


@functools.cache
def _run(dt: float = 0.25e-6, theta: float | None = None):
    sc = load_scenario(CASE).with_overrides(dt_s=dt)
    if theta is not None:
        data = sc.model_dump(mode="json")
        data["time"]["theta"] = theta
        sc = scenario_from_dict(data)
    return run_scenario(sc)


def _F0() -> float:
    return st_venant_force(
        Rod1D.from_material(BRASS, L, R), Rod1D.from_material(ALUMINIUM, L, R), V0
    )


def test_invariants_momentum_no_tension_no_penetration():
    """Free bodies: total linear momentum, as the steps converged (before the balance of
    their translational rows), is conserved to round-off through the impact, 160 steps x eps
    (the translational equations are linear; the impulses act in equal and opposite pairs;
    measured 7.6e-16), and so is the momentum summed from the solves' translational
    residuals (5.5e-16). Every LCP met its
    complementarity tolerance (a tensile impulse or one on an opening gap would show as a
    residual ~1, LCP_RTOL = 1e-8), and every step converged. Penetration is bounded by the
    Moreau-Jean estimate h v0 (1 - theta) = 2.4e-8 m; we allow 10 % over it."""
    r = _run()
    s = r.summary
    assert s["momentum_rel_error_converged"] < 160 * EPS  # the run's 160 steps x round-off
    assert s["momentum_residual_rel"] < 160 * EPS
    assert s["lcp_residual_max"] <= 1e-8
    assert s["steps_on_roundoff_floor"] == 0
    assert s["max_penetration_m"] < 1.1 * 0.25e-6 * V0 * (1 - 0.55)
    assert s["dof"]["b1"] > 2000 and s["model"]["b2"] == "full"


def test_flat_plateau_matches_st_venant():
    """Mean contact force over the middle of the first plateau (0.2..0.8 of 2L/c2) within 3 %
    of St Venant's F0 (measured -1.0 %: 3D lateral inertia of a rod with r/L = 0.1); the
    contact ends within 10 % of 2 L / c2 (measured +6 %: the 3D front is smeared)."""
    r = _run()
    res = r.result
    T2 = 2 * L / ALUMINIUM.bar_wave_speed
    mid = (res.t > 0.2 * T2) & (res.t < 0.8 * T2)
    F0 = _F0()
    assert abs(res.contact_force[mid].mean() / F0 - 1) < 0.03
    end = r.summary["contact_intervals_s"][0][1]
    assert abs(end / T2 - 1) < 0.10


def test_energy_error_converges_with_the_step():
    """With theta = 1/2 (implicit midpoint) the elastic parts conserve energy exactly; what is
    left is the e = 0 impact law at the contact nodes: |error| 0.24 % at h = 0.25 us and 0.11 %
    at h/2 (measured). Required: below 1 %, and at least 40 % smaller on halving the step.
    (A theta fixed above 1/2, as this case's own 0.55, also damps the unresolved
    high-frequency modes the impact excites: 1.3 % at theta = 0.52, 2.2 % at 0.55, not
    shrinking with h. The seed scenarios take theta(h) = 1/2 + h / (4 tau) instead:
    integrate.theta.)"""
    e1 = abs(_run(0.25e-6, 0.5).summary["energy_rel_change"])
    e2 = abs(_run(0.125e-6, 0.5).summary["energy_rel_change"])
    assert e1 < 0.01
    assert e2 < 0.6 * e1


def test_energy_ledger_closes_through_the_impact():
    """The energy ledger (integrate.energy_ledger): the frames do not rotate, so the mass
    matrix is constant and the step's energy identity exact. At theta = 1/2 without damping,
    E(t) - E(0) - W_contact = 0 to the Newton tolerance (measured 1e-13 of E(0), bound 1e-6:
    the issue's); the contact's work is what the e = 0 impact law took (negative). At
    theta = 0.51 (20 us, through the first plateau) the balance misses by the scheme's
    numerical dissipation (theta - 1/2)(dv^T M dv + dq^T K dq) (measured 0.9 % of E(0) over
    40 us) and closes with it to the same 1e-6: the dissipation is over 1000 times that
    bound, so this checks the dissipation term itself. The free pair's momentum error stays
    defined (no reason against it). The theta = 1/2 run is test_energy_error_converges'
    (cached); the 0.51 one ~5 s."""
    half = _run(0.25e-6, 0.5).summary
    led = half["energy_ledger"]
    assert led["balance_reference"] == "initial energy"
    assert led["balance_residual_rel_max"] < 1e-6
    assert led["work_contact_J"] < 0 and led["dissipation_numerical_J"] == 0.0
    assert half["momentum_error_undefined_because"] is None
    damped = run_scenario(load_scenario(CASE).with_time(t_end_s=20e-6, theta=0.51)).summary
    led = damped["energy_ledger"]
    assert led["balance_residual_rel_max"] < 1e-6
    assert led["dissipation_numerical_J"] > 1e3 * 1e-6 * led["total_start_J"]


def test_bonded_contact_holds_the_pair_together_and_conserves_momentum():
    """Seed eq. (7), bonded: once a pair carries a compressive impulse all three components of
    x_S - x_C are held (equality rows) until its normal impulse would turn tensile. Checked on the
    short flat impact: momentum as converged to round-off, 160 steps x eps (measured 1.3e-15),
    bonds formed (the contact lasts at least as long as the
    frictionless one), penetration within the same Moreau-Jean bound."""
    sc = load_scenario(CASE)
    data = sc.model_dump(mode="json")
    data["contacts"][0]["kind"] = "bonded"
    r = run_scenario(scenario_from_dict(data))
    s = r.summary
    assert s["momentum_rel_error_converged"] < 160 * EPS
    assert s["max_penetration_m"] < 1.1 * 0.25e-6 * V0 * (1 - 0.55)
    free = _run().summary["contact_intervals_s"][0][1]
    assert s["contact_intervals_s"] and s["contact_intervals_s"][-1][1] >= free - 1e-12


def test_rod_against_a_grounded_rigid_wall_converges_and_balances():
    """A rigid body held by a ground joint (a wall) has no momentum of its own: the Newton
    check must scale its residual by the constraint impulses it balances (it once never
    converged at step 1). The striker's momentum loss along x equals the normal contact
    impulse summed over the steps to 1e-4: the impulses act along the master facet normals of
    the faceted cap, tilted off the axis by the chord angle, so x takes cos(tilt) of each
    (measured 1.4e-5 short); a non-converged step would miss by its residual, not by this."""
    import flexmvm as fm

    sc = fm.load_scenario(Path(__file__).parents[1] / "scenarios" / "rod_impact_short.toml")
    data = sc.with_kind("mvm").with_model("b2", fm.rigid()).model_dump(mode="json")
    data["joints"] = [{"type": "ground", "body": "b2"}]
    run = fm.run(fm.scenario_from_dict(data).with_time(t_end_s=3e-5))
    assert run.summary["steps_on_roundoff_floor"] == 0
    p = run.result.momentum  # the wall is still: the total is the striker's
    lost = p[0, 0] - p[-1, 0]
    impulse = run.steps.contact_impulse_Ns.sum()
    assert impulse > 0 and 0.0 <= impulse - lost <= 1e-4 * impulse
