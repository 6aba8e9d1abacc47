"""A run stored in a directory and reused while it is the same run: ``history.csv``,
``summary.json`` and ``key.json`` (the validation report's cases, tools/validation).

key.json holds the key and stamp of the run (runs.provenance: package source,
numpy/scipy/numba, resolved scenario, mesh files), ``outputs`` (history.csv's record,
results.history.history_record: SHA-256, samples, first and last time; summary.json's SHA-256)
and whatever the caller adds (commit, date). A stored run is loaded only if its key is the
current one and its files are those written with it and cover the scenario's window; else it
is run again, announced in one line (``validation case seed_full: history.csv: 7 of 2001
samples, last at 12 us (expected window 0..1000 us): recomputed``).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexmvm.errors import announce_recompute
from flexmvm.results.atomic import file_sha256, write_json_atomic
from flexmvm.results.history import history_problem, history_record, read_history, write_history
from flexmvm.results.summary_keys import with_current_keys
from flexmvm.runs.provenance import run_inputs, stamp, stamp_mismatch
from flexmvm.scenarios.schema import Scenario

__all__ = ["StoredRun", "load_or_run", "stored_run_problem"]


@dataclass
class StoredRun:
    """A run's curves (t (n,) [s], contact force (n,) [N], {probe: axial velocity (n,)
    [m/s]}), its summary and key.json's content."""

    t: np.ndarray
    force: np.ndarray
    probes: dict
    summary: dict
    meta: dict

    @property
    def curves(self):
        return self.t, self.force, self.probes


def _outputs(d: Path) -> dict:
    """What key.json keeps to check the run's files: history.csv's record, summary.json's
    SHA-256."""
    return {
        "history.csv": history_record(d / "history.csv"),
        "summary.json": file_sha256(d / "summary.json"),
    }


def stored_run_problem(d: Path, sc: Scenario) -> str | None:
    """Why the run stored in ``d`` cannot be used for ``sc`` (one line), or None if it can;
    "absent" when there is no key.json."""
    try:
        meta = json.loads((d / "key.json").read_text())
    except FileNotFoundError:
        return "absent"
    except (OSError, ValueError):
        return "key.json unreadable"
    current = stamp(sc)
    if not isinstance(meta, dict) or meta.get("key") != current["key"]:
        return stamp_mismatch(meta.get("provenance") if isinstance(meta, dict) else None, current)
    outputs = meta.get("outputs")
    if not isinstance(outputs, dict):
        return "key.json has no record of its outputs"
    bad = history_problem(d / "history.csv", outputs.get("history.csv"), sc.time.t_end_s)
    if bad is not None:
        return f"history.csv: {bad}"
    try:
        if file_sha256(d / "summary.json") != outputs.get("summary.json"):
            return "summary.json: content differs from the SHA-256 in key.json"
    except OSError:
        return "summary.json: missing"
    return None


def load_or_run(
    d: Path,
    sc: Scenario,
    label: str,
    recompute: bool = False,
    progress: bool = True,
    extra: Callable[[], dict] = dict,
) -> StoredRun:
    """The run of ``sc`` stored in ``d`` if it passes its check (stored_run_problem), else
    ``sc`` run now and stored there (key.json last, with ``extra()`` added); a stored run
    that fails is announced as ``<label>: <why>: recomputed``. ``recompute``: ignore it."""
    problem = None if recompute else stored_run_problem(d, sc)
    if problem is None and not recompute:
        t, f, p = read_history(d / "history.csv")
        return StoredRun(
            t,
            f,
            p,
            with_current_keys(json.loads((d / "summary.json").read_text())),
            json.loads((d / "key.json").read_text()),
        )
    if problem not in (None, "absent"):
        announce_recompute(f"{label}: {problem}: recomputed")
    from flexmvm.runs.run import run_scenario

    r = run_scenario(sc, progress=progress)
    t, f, p = r.result.curves()
    d.mkdir(parents=True, exist_ok=True)
    (d / "key.json").unlink(missing_ok=True)  # a half-rewritten run never matches a key
    write_history(d / "history.csv", t, f, p)
    write_json_atomic(d / "summary.json", r.summary)
    prov = stamp(sc)
    meta = {
        "key": prov["key"],
        "provenance": prov,
        "code_version": prov["code"],
        **extra(),
        "inputs": run_inputs(sc),
        "outputs": _outputs(d),
    }
    write_json_atomic(d / "key.json", meta)
    return StoredRun(t, f, p, r.summary, meta)
