"""A written run read back (issue 52 item 3): fm.read_run on the folder `flexmvm run` or
fm.write_run writes, and `flexmvm compare RUN REFERENCE`. On the tiny seed case."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import flexmvm as fm

TINY = Path(__file__).parent / "data" / "tiny_impact.toml"
HISTORIES = (
    "t",
    "contact_force",
    "probe_x",
    "probe_v",
    "kinetic",
    "strain",
    "potential",
    "momentum",
    "angular_momentum",
    "frame_r",
    "frame_A",
    "frame_v",
    "joint_force",
)


def _flexmvm(*args):
    return subprocess.run(
        [sys.executable, "-m", "flexmvm.cli.main", *map(str, args)],
        check=False,
        capture_output=True,
        text=True,
    )


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """The tiny case run in this process and written as `flexmvm run` writes it."""
    run = fm.run(fm.load_scenario(TINY))
    out = tmp_path_factory.mktemp("tiny")
    fm.write_run(out, run)
    return run, out


def test_round_trip_histories_exact_fields_to_float32(written):
    """Every history read back equals the run's to the bit (float64 in the file); the fields
    equal the run's q, q_dot at their rows within float32 rounding (2^-24 of each value);
    the summary and the scenario are the run's."""
    run, out = written
    back = fm.read_run(out)
    for key in HISTORIES:
        np.testing.assert_array_equal(getattr(back.result, key), getattr(run.result, key), key)
    assert back.result.contact_intervals == run.result.contact_intervals
    assert back.result.body_names == run.result.body_names
    assert back.result.probe_names == run.result.probe_names
    for b, body in enumerate(run.result.body_names):
        fr = back.fields(body)
        np.testing.assert_array_equal(fr.t, run.t[fr.rows])
        np.testing.assert_allclose(fr.q, run.result.q[b][fr.rows], rtol=2.0**-24, atol=0)
        np.testing.assert_allclose(fr.q_dot, run.result.q_dot[b][fr.rows], rtol=2.0**-24, atol=0)
    assert back.summary == run.summary  # the JSON written, read back
    assert back.scenario.model_dump() == fm.load_scenario(TINY).model_dump()
    np.testing.assert_array_equal(back.probe("b2_free_end").v, run.probe("b2_free_end").v)
    c = fm.compare(back, run)
    assert c.ncc_force == pytest.approx(1.0, abs=1e-12) and c.peak_err == 0.0


def test_read_run_refuses_a_folder_without_a_run(tmp_path):
    with pytest.raises(fm.InputError, match="no written run here"):
        fm.read_run(tmp_path)


def test_cli_run_read_back_and_compared(written, tmp_path):
    """A folder written by `flexmvm run` reads back with the in-process run's histories to
    the bit (same scheme, one process each); `flexmvm compare CLI_RUN RUN` prints
    fm.compare's numbers, one per line (force NCC 1, peak error 0); a folder without a run
    is one error line, exit status 2."""
    run, out = written
    cli = tmp_path / "cli"
    proc = _flexmvm("run", TINY, "--out", cli, "--no-progress", "--jobs", "1")
    assert proc.returncode == 0, proc.stderr
    back = fm.read_run(cli)
    for key in HISTORIES:
        np.testing.assert_array_equal(getattr(back.result, key), getattr(run.result, key), key)
    proc = _flexmvm("compare", cli, out)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert "  ncc_force = 1.000000" in lines and "  peak_err = 0.0000%" in lines
    assert any(line.startswith("  ncc_b2_free_end = ") for line in lines)
    proc = _flexmvm("compare", out, tmp_path)
    assert proc.returncode == 2 and proc.stderr.startswith("flexmvm: error: ")
    assert len(proc.stderr.strip().splitlines()) == 1 and "no written run here" in proc.stderr
