"""A run that blew up fails instead of reporting success (runs/blowup.py; issue "Numbers a
user can trust, part three", item 8): a penetration beyond a share of the penetrated body's
thinnest extent, or an energy gain beyond a share of its start, ends the run with status
"failed", exit 2 and its histories written, in one line naming the node, the bodies, the
pair and, when the penetrating nodes are the pair's master side, the reverse pair to add.

The tiny case penetrates by round-off-scale amounts (the hemisphere's nodes into the flat
face, the direction its one pair does not hold): with the bound lowered to zero it is the
blown-up case's path, exactly."""

from __future__ import annotations

import json

import pytest
from test_cli_failures import RUN_FAST, TINY, _in_process, _one_line

import flexmvm as fm
from flexmvm.errors import SimulationFailed
from flexmvm.runs import blowup
from flexmvm.runs.run import run_scenario


def test_a_penetration_beyond_the_bound_fails_the_run(monkeypatch):
    monkeypatch.setattr(blowup, "PENETRATION_FAIL_SHARE", 0.0)
    sc = fm.load_scenario(TINY).with_time(t_end_s=6e-6)
    with pytest.raises(SimulationFailed) as info:
        run_scenario(sc, warn=False)
    partial = info.value.partial
    assert partial.summary["status"] == "failed"
    line = partial.summary["failure"]
    assert line == str(info.value) and "\n" not in line
    at = partial.summary["max_penetration_at"]
    assert f"node {at['node']} of body {at['body']!r}" in line
    assert "b2.end_a->b1.end_a" in line
    # the deepest node is b1's (the pair's master side): the reverse pair is named
    assert at["body"] == "b1" and "reverse pair (slave 'b1', master 'b2')" in line
    assert len(partial.result.t) > 2  # the histories are kept


def test_the_command_line_writes_the_failed_run_and_exits_2(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(blowup, "PENETRATION_FAIL_SHARE", 0.0)
    out = tmp_path / "run"
    code, _, err = _in_process(["run", TINY, "--out", out, *RUN_FAST], capsys)
    _one_line(err, 2, code, "the contact failed", "reverse pair")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and "the contact failed" in summary["failure"]
    assert (out / "history.csv").exists()


def test_healthy_run_passes_and_an_energy_gain_fails():
    """The tiny case passes the shipped bounds (its penetration ~1e-8 of b2's 10 mm, its
    energy falls); a summary whose energy rose by 50 % beyond the inputs fails."""
    run = run_scenario(fm.load_scenario(TINY).with_time(t_end_s=6e-6), warn=False)
    assert run.summary["status"] == "completed"
    assert blowup.blowup_failure(run.summary, run.built) is None
    gained = {**run.summary, "energy_gain_rel_max": 0.5, "max_penetration_at": None}
    line = blowup.blowup_failure(gained, run.built)
    assert line is not None and "rose by 50 %" in line
