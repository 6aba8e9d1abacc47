"""``fm.read_run(path)``: a written run (results.read.read_run) with the Scenario it ran made
again from the resolved form results.h5 keeps (results sit below scenarios: the Scenario is
made here)."""

from __future__ import annotations

from flexmvm.results.read import WrittenRun
from flexmvm.results.read import read_run as read_files
from flexmvm.scenarios.load import scenario_from_dict

__all__ = ["read_run"]


def read_run(path) -> WrittenRun:
    """The run written in folder ``path`` by ``flexmvm run --out`` or ``fm.write_run``: its
    histories as arrays (``result``, a RunResult; ``t``, ``contact_force``, ``probe``,
    ``curves``), its fields read from results.h5 when asked (``fields(body)``,
    ``elastic(body)``), ``summary`` (summary.json) and ``scenario``, the Scenario it ran
    (None when the folder does not keep it). fm.compare takes it as it takes a run.
    InputError (one line) for a folder that holds no written run."""
    run = read_files(path)
    if run.scenario_data is not None:
        run.scenario = scenario_from_dict(run.scenario_data)
    return run
