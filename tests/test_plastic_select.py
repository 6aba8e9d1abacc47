"""The plastic guard in a selection study's validity (issue 37): a reduced plastic body whose
cells outside the retained region reached the yield stress is outside its model's validity,
as a contact on nodes the basis holds stiff is, so the search never accepts it whatever its
force NCC (docs/plasticity.md "MVM b2, plastic": 3-5 + 37 modes reached NCC 0.99999 against
full FE plastic with 21 % of the plastic work missing). Dictionaries only: well under 1 s."""

from __future__ import annotations

from flexmvm.metrics.ncc import Target
from flexmvm.runs.guard import invalid_reason, validity_fields
from flexmvm.studies.search import Candidate, smallest_passing
from flexmvm.studies.selection import FAIL_SCORE, score


def _plastic_summary(cells_outside: int) -> dict:
    """A run summary's entries validity_fields reads, for a reduced plastic b2 whose plastic
    guard counted ``cells_outside`` cells at yield outside its retained region."""
    entry = {
        "plastic_work_J": 1.175e-4,
        "steps_yield_outside_retained": 197 if cells_outside else 0,
        "cells_yield_outside_retained": cells_outside,
    }
    return {
        "reduced_contact_guard": {"b2": {"impulse_fraction_outside": 0.0}},
        "energy_gain_rel_max": 0.0,
        "plastic": {"b2": entry},
    }


def test_validity_fields_carry_the_plastic_guard():
    """The study row's plastic_cells_outside is the summary's cells_yield_outside_retained of
    the studied body (exact: a count); None when the body is not plastic, so elastic studies
    and rows stored before the field existed are judged as before."""
    assert validity_fields(_plastic_summary(4), "b2")["plastic_cells_outside"] == 4
    assert validity_fields(_plastic_summary(0), "b2")["plastic_cells_outside"] == 0
    elastic = _plastic_summary(0) | {"plastic": {}}
    assert validity_fields(elastic, "b2")["plastic_cells_outside"] is None
    assert validity_fields(_plastic_summary(4), "b1")["plastic_cells_outside"] is None
    reason = invalid_reason(validity_fields(_plastic_summary(4), "b2"))
    assert reason is not None and "4 cells outside the retained region" in reason
    assert invalid_reason(validity_fields(_plastic_summary(0), "b2")) is None


def test_search_does_not_accept_a_plastic_zone_outside_the_region():
    """The seed's short plastic rods as measured by hand (docs/notes/2026-11-27-seed-plastic.md):
    3-5 + 37 modes (556 DOF) reaches force NCC 0.999994 with 4 cells outside its region at
    yield, 5-5 + 37 (898 DOF) 0.9999997 with the guard quiet. With the plastic guard in the
    score, 3-5 scores FAIL_SCORE and the search answers 5-5; the NCC alone would have picked
    3-5 (the fewer DOF)."""
    target = Target.parse("ncc>=0.995")
    base = {"peak_err": 0.0073, "impulse_err": 0.0044, "duration_err": -0.0002}
    rows = {
        Candidate((3, 5), 37, 556): base
        | {"ncc_force": 0.999994}
        | validity_fields(_plastic_summary(4), "b2"),
        Candidate((5, 5), 37, 898): base
        | {"ncc_force": 0.9999997}
        | validity_fields(_plastic_summary(0), "b2"),
    }
    assert score(rows[Candidate((3, 5), 37, 556)], target) == FAIL_SCORE
    assert score(rows[Candidate((5, 5), 37, 898)], target) == 0.9999997
    winner, scores = smallest_passing(
        list(rows),
        lambda batch: [score(rows[c], target) for c in batch],
        lambda s: s >= target.ncc_min,
    )
    assert winner == Candidate((5, 5), 37, 898)
    assert len(scores) == 2  # neither closes the other: 3-5 fails, 5-5 is needed


def test_study_row_carries_the_plastic_zone():
    """A study row of a plastic body (studies.reference_run.scored_row) carries the run's plastic
    work, dent and plastic cell count (summary ``plastic.<body>``), exactly: the MVM-vs-full
    table of a plastic region study reads them from its cases (docs/plasticity.md, "Sphere on
    block: the region for the plastic zone"); an elastic body's row has none. A half-sine
    pulse against itself: NCC 1 to round-off (1e-12)."""
    from types import SimpleNamespace

    import numpy as np

    from flexmvm.studies.reference_run import scored_row

    t = np.linspace(0.0, 1e-4, 201)
    f = np.where(t < 8e-5, np.sin(np.pi * t / 8e-5), 0.0) * 500.0
    summary = _plastic_summary(0) | {"wall_time_s": 1.0}
    summary["plastic"]["b2"] |= {"permanent_indentation_m": 8.3e-6, "plastic_cells": 242}
    run = SimpleNamespace(result=SimpleNamespace(curves=lambda: (t, f, {})), summary=summary)
    row = scored_row({}, run, "b2", t, f, {})
    assert abs(row["ncc_force"] - 1.0) < 1e-12
    assert row["plastic_work_J"] == 1.175e-4
    assert row["permanent_indentation_m"] == 8.3e-6 and row["plastic_cells"] == 242
    elastic = scored_row({}, run, "b1", t, f, {})
    assert "plastic_work_J" not in elastic and "plastic_cells" not in elastic


def test_rod_candidates_keep_the_scenarios_allow_costly():
    """A layers-laps candidate (studies.grid.mvm_scenario) keeps the studied body's
    ``model.allow_costly``: on the 1 m seed rods a region that holds the plastic zone (5-7 +
    37: 1,378 DOF, ~395 MB dense against ~215 MB for full FE) is refused without it, so a
    study of a scenario that consents to it would have refused every such candidate.
    Scenario objects only: well under 1 s."""
    import tomllib
    from pathlib import Path

    from flexmvm.scenarios import scenario_from_dict
    from flexmvm.studies.grid import mvm_scenario

    path = Path(__file__).resolve().parents[1] / "scenarios" / "rod_impact_short_plastic.toml"
    data = tomllib.loads(path.read_text())
    for consent in (True, False):
        data["bodies"][1]["model"]["allow_costly"] = consent
        sc = scenario_from_dict(data, source=str(path))
        model = mvm_scenario(sc, "b2", 5, 7, 37).body("b2").model
        assert (model.selection, model.modes, model.allow_costly) == ("5-7", 37, consent)
