"""Replacements of flexmvm.runs.main_job._run_and_write for tests/test_cli_failures.py, at
module level so the main job's worker processes (spawned) can import them."""

from __future__ import annotations

import os
import time
from pathlib import Path

from flexmvm.errors import SolverError
from flexmvm.runs import main_job

_REAL = main_job._run_and_write


def reference_fails(sc, label, out_dir, fields, progress):
    """The full-FE reference fails at once; the scenario's own run is real."""
    if label == "full":
        raise SolverError("contact Newton iteration did not converge")
    return _REAL(sc, label, out_dir, fields, progress)


def reference_fails_while_own_runs_long(sc, label, out_dir, fields, progress):
    """The reference fails after its files are half written; the own run then sleeps 60 s and
    leaves the file $FLEXMVM_TEST_MARKER if it is not terminated before."""
    if label == "full":
        out_dir.mkdir(parents=True, exist_ok=True)
        (out_dir / "history.csv").write_text("t_s,contact_force_N\n")
        raise SolverError("contact Newton iteration did not converge")
    result = _REAL(sc, label, out_dir, fields, progress)
    time.sleep(60)
    Path(os.environ["FLEXMVM_TEST_MARKER"]).write_text("the own run was not stopped\n")
    return result
