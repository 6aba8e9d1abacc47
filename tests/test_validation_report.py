"""The validation package's report and acceptance table, in the default run (fast: no case is
run; ~2 s). The cases themselves: tests/test_validation.py (-m validation) and
tests/test_validation_live.py."""

from __future__ import annotations

import copy
import json
import runpy
import sys
from pathlib import Path

import pytest

from tools.validation import acceptance, command
from tools.validation.acceptance import Bound, Criterion
from tools.validation.cases import CASES, stored_cases
from tools.validation.report import render

ROOT = Path(__file__).resolve().parents[1]
STORED = ROOT / "docs" / "validation" / "validation.json"


@pytest.fixture(scope="module")
def stored():
    return json.loads(STORED.read_text())


def test_report_from_the_stored_numbers_is_the_page(stored):
    """docs/validation.md is the report rendered from docs/validation/validation.json, byte for
    byte: the page is generated, and its template and the table reproduce it (the stamp is in
    the json, so nothing differs)."""
    assert render(stored) == (ROOT / "docs" / "validation.md").read_text()


def test_report_states_the_tables_verdict(stored):
    """A number moved past a stated bound turns that statement to NOT met (the report reads the
    table, not its own copy of the thresholds), and only that one."""
    bad = copy.deepcopy(stored)
    bad["seed"]["mvm_vs_full"]["ncc_force"] = 0.985
    text = render(bad)
    assert "in b2: **NOT met**" in text
    assert text.count("**NOT met**") == 1
    bad = copy.deepcopy(stored)
    bad["pendulum"]["momenta"]["b2"]["p_end_rel_err_x"] = -2e-3
    assert render(bad).count("**NOT met**") == 1


def test_bounds_and_failures():
    """Each bound's comparison, and a failure naming the row, its value and its reason."""
    assert Bound.AT_LEAST.holds(0.99, 0.99) and not Bound.AT_LEAST.holds(0.98, 0.99)
    assert Bound.ABS_BELOW.holds(-0.02, 0.03) and not Bound.ABS_BELOW.holds(-0.03, 0.03)
    assert Bound.AT_MOST.holds(0, 0) and not Bound.BELOW.holds(1e-9, 1e-9)
    row = Criterion("x", ("a", "b"), Bound.AT_LEAST, 0.5, "because")
    assert row.value({"a": {"b": 0.25}}) == 0.25 and not row.holds({"a": {"b": 0.25}})
    assert acceptance.failures(
        {
            "plateau_err": 0.05,
            "jump_err": 0.0,
            "momentum_rel_error_converged": 0.0,
            "lcp_residual_max": 0.0,
            "steps_on_roundoff_floor": 0,
        },
        "flat_vs_st_venant",
    ) == [
        "flat_vs_st_venant: plateau_err |x| < 0.03 (value 0.05: "
        + acceptance.criteria("flat_vs_st_venant")[0].why
        + ")"
    ]


def test_every_row_reads_a_number_of_the_stored_report(stored):
    """Every row of the table names a case of CASES and a path that exists in its numbers (a
    renamed key cannot leave a row checking nothing)."""
    keys = {c.key for c in CASES}
    for row in acceptance.ACCEPTANCE:
        assert row.section in keys, row
        row.value(stored[row.section])
    assert stored_cases(stored) == stored["cases"]


def test_command_help_and_unknown_case(tmp_path, capsys, monkeypatch):
    """`python -m tools.validation --help` shows the command's options (run in process, as
    `python -m` runs it); an unknown case is one line on stderr and exit status 2, before
    anything runs."""
    monkeypatch.setattr(sys, "argv", ["tools.validation", "--help"])
    runpy.run_module("tools.validation", run_name="__main__")  # returns: exit status 0
    out = capsys.readouterr().out
    assert "Usage: python -m tools.validation" in out and "--recompute" in out
    with pytest.raises(SystemExit) as done:
        command.main(["--out", str(tmp_path), "--case", "nope"])
    captured = capsys.readouterr()
    assert done.value.code == 2 and captured.out == ""
    assert captured.err.strip().splitlines() == [
        (
            "flexmvm: error: unknown validation case 'nope'; expected one of flat_vs_st_venant, "
            "seed, step_convergence, short, pendulum, hertz_block, arm_stop"
        )
    ]
