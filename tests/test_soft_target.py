"""The soft target of issue 12 part 4 (docs/studies.md, "Material study"): b2 of PA6 struck by
the seed's brass rod, b2 as Craig-Bampton 1-4 + 43 modes, whose outer ring of retained nodes
is the edge of PA6's Hertz patch (0.66 mm). With the velocity law's penetration recovery
(beta = 0.2) pushing penetrated nodes out at beta |g| / h whatever their speed, the contact
there chattered from ~450 us: the energy rose by 2.2 % over 0.7 ms (2.6 % over 2 ms in
benchmarks/pa6_chatter.py), nodes went 55 um deep and the run warned, so
scenarios/rod_impact_pa6.toml shipped penetration_recovery = 0. Capped by each pair's closing
speed (contact/pairs.py), the default recovery holds the same model as beta = 0 does, and the
scenario ships the default. The node-coverage guard is silent in every case: the chatter was
the failure only the energy check saw. 0.7 ms at h = 1 us, b1 MVM 3-5 + 40 (the study
settings)."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from flexmvm.runs.compare import compare_runs
from flexmvm.runs.run import EnergyGainWarning, run_scenario
from flexmvm.scenarios import load_scenario, scenario_from_dict
from flexmvm.studies.grid import mvm_scenario, study_scenario

# Long (two 0.7 ms MVM runs): in `pytest -m validation`, not the default run.
pytestmark = pytest.mark.validation

PA6 = Path(__file__).resolve().parents[1] / "scenarios" / "rod_impact_pa6.toml"


@pytest.fixture(scope="module")
def runs():
    sc = study_scenario(load_scenario(PA6), "b2", t_end_s=7e-4, dt_s=1e-6, other="mvm:3-5:40")
    data = mvm_scenario(sc, "b2", 1, 4, 43).model_dump(mode="json")
    assert "penetration_recovery" not in data["contacts"][0]  # as shipped: the default
    out = {}
    for beta in (None, 0.0):
        d = {**data, "contacts": [dict(data["contacts"][0])]}
        if beta is not None:
            d["contacts"][0]["penetration_recovery"] = beta
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            run = run_scenario(scenario_from_dict(d, source=f"beta {beta}"))
        out[beta] = (run, [w for w in caught if w.category is EnergyGainWarning])
    return out


def _holds(run, warned) -> None:
    """What a run that does not chatter shows: no energy gain beyond round-off and the
    scheme's own (measured 2e-7 for both), no warning, penetration within the full-FE run's
    scale (full FE 3.7 um), a single contact interval, no impulse on nodes held stiff."""
    s = run.summary
    assert s["energy_gain_rel_max"] < 1e-5 and not warned, s["energy_gain_rel_max"]
    assert s["max_penetration_m"] < 5e-6
    assert len(s["contact_intervals_s"]) == 1
    assert s["reduced_contact_guard"]["b2"]["impulse_fraction_outside"] == 0.0


def test_default_recovery_holds_the_retained_edge(runs):
    """The shipped default (beta = 0.2, capped by the closing speed): as beta = 0 (before the
    cap: energy +2.2 %, 55 um, warned)."""
    _holds(*runs[None])


def test_no_recovery_holds_the_same_model(runs):
    _holds(*runs[0.0])


def test_default_and_no_recovery_agree(runs):
    """With the recovery capped, beta moves the force of the held model by little: force NCC
    between beta = 0.2 and 0 >= 0.9999 and peaks within 1 % (as the full-FE references of
    the material study did with the uncapped recovery: NCC 0.999999, peak 0.01 %); measured
    NCC 0.9999964, peak 0.07 %."""
    a, b = runs[None][0].result, runs[0.0][0].result
    c = compare_runs(*b.curves(), *a.curves())
    assert c["ncc_force"] >= 0.9999 and abs(c["peak_err"]) < 0.01, c
