"""summary.json's keys say what they mean (issue "Numbers a user can trust, part three", item 8):
``energy_conserving_scheme`` (true when every contact is on the position law, even on a scheme
that damped 10 % of a plate's energy) is ``contact_laws_add_no_energy``, beside the energy the
scheme's damping took (``numerical_dissipation_J``, ``numerical_dissipation_share``) and the
damping time in use (``hf_damping_time_s``). Runs written before the rename are read under the
current names by one mapping (results.summary_keys), in results.read.read_run and
runs.stored_run."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from test_cli_failures import TINY

import flexmvm as fm
from flexmvm.results.read import read_run
from flexmvm.results.summary_keys import RENAMED_KEYS, with_current_keys
from flexmvm.runs.guard import energy_gain_warning
from flexmvm.runs.run import run_scenario
from flexmvm.runs.stored_run import load_or_run

STORED = Path(__file__).resolve().parents[1] / "docs" / "validation" / "short_full"


def test_a_run_writes_the_new_keys():
    """The tiny case (velocity law, theta = 0.55 fixed): its contact law may add energy, its
    scheme took a share of it (> 0: theta > 1/2), no damping time."""
    s = run_scenario(fm.load_scenario(TINY).with_time(t_end_s=6e-6), warn=False).summary
    assert not set(RENAMED_KEYS) & set(s)  # no old key written
    assert s["steps_on_roundoff_floor"] == 0 and s["dt_min_taken_s"] > 0
    assert s["max_contact_force_interval_mean_N"] >= s["min_contact_force_interval_mean_N"] >= 0
    assert s["energy_rel_change_max"] >= abs(s["energy_rel_change"])
    assert s["contact_laws_add_no_energy"] is False
    assert s["numerical_dissipation_J"] == s["energy_ledger"]["dissipation_numerical_J"] > 0
    assert 0 < s["numerical_dissipation_share"] < 1e-3
    assert s["hf_damping_time_s"] is None


def test_the_mapping_renames_old_keys_and_keeps_new_ones():
    old = {"energy_conserving_scheme": True, "max_contact_force_N": 1.0, "dof": 3}
    assert with_current_keys(old) == {
        "contact_laws_add_no_energy": True,
        "max_contact_force_interval_mean_N": 1.0,
        "dof": 3,
    }
    both = {"energy_conserving_scheme": True, "contact_laws_add_no_energy": False}
    assert with_current_keys(both) == {"contact_laws_add_no_energy": False}
    new = {"contact_laws_add_no_energy": True}
    assert with_current_keys(new) is new
    assert set(RENAMED_KEYS) == {
        "energy_conserving_scheme",
        "energy_rel_error",
        "energy_rel_error_max",
        "steps_not_converged",
        "max_contact_force_N",
        "min_contact_force_N",
        "smallest_step_s",
    }


def _old_run(d: Path) -> Path:
    """docs/validation/short_full copied to d with its summary written under the old key (as
    runs before the rename have it; the stored case itself is rewritten by each validation)."""
    shutil.copytree(STORED, d)
    path = d / "summary.json"
    summary = json.loads(path.read_text())
    summary["energy_conserving_scheme"] = summary.pop("contact_laws_add_no_energy")
    for old, new in RENAMED_KEYS.items():  # the stored case may already have old names
        if new in summary and old not in summary and old != "smallest_step_s":
            summary[old] = summary.pop(new)
    path.write_text(json.dumps(summary, indent=2) + "\n")
    return d


def test_a_run_written_before_the_rename_is_read_under_the_new_key(tmp_path):
    """A run written with the old key, read by read_run."""
    d = _old_run(tmp_path / "old_run")
    assert "energy_conserving_scheme" in json.loads((d / "summary.json").read_text())
    s = read_run(d).summary
    assert s["contact_laws_add_no_energy"] is True and "energy_conserving_scheme" not in s
    assert s["max_contact_force_interval_mean_N"] > 0 and "max_contact_force_N" not in s


def test_a_stored_run_is_read_under_the_new_key(monkeypatch, tmp_path):
    """runs.stored_run: a stored run that passes its check comes back with the new key."""
    from flexmvm.runs import stored_run

    d = _old_run(tmp_path / "stored")
    monkeypatch.setattr(stored_run, "stored_run_problem", lambda d, sc: None)
    run = load_or_run(d, fm.load_scenario(TINY), "old", progress=False)
    assert run.summary["contact_laws_add_no_energy"] is True
    assert "energy_conserving_scheme" not in run.summary


def test_the_energy_warning_reads_an_old_summary():
    """energy_gain_warning's position-law bound (1e-4) applies to a summary with the old key."""
    line = energy_gain_warning({"energy_gain_rel_max": 4.6e-4, "energy_conserving_scheme": True})
    assert line is not None and "position law" in line
    assert energy_gain_warning({"energy_gain_rel_max": 4.6e-4}) is None


@pytest.mark.parametrize(
    "key",
    [
        "numerical_dissipation_J",
        "contact_laws_add_no_energy",
        "energy_rel_change",
        "steps_on_roundoff_floor",
        "max_contact_force_interval_mean_N",
    ],
)
def test_the_docs_name_the_new_keys(key):
    docs = Path(__file__).resolve().parents[1] / "docs" / "scenario_format.md"
    assert key in docs.read_text()
