"""A validation case's stored run: run it, or load it while it is the same run.

A finished case is stored in DIR/<case>/ (history.csv, summary.json, key.json;
runs/stored_run.py) and reused only if its key matches: runs.provenance.run_key, the
one key of every stored run (a SHA-256 of the package source but this validation package, the
numpy, scipy and numba versions and the whole resolved scenario: every body, mesh parameter,
model, contact, joint, probe and time setting, t_end, dt, theta; mesh files by content hash),
and if its outputs are those written with it (key.json "outputs": history.csv's SHA-256,
samples and window, summary.json's SHA-256): an edited or cut history is recomputed, never
checked. Each recomputation of a stored case is announced in one line.
"""

from __future__ import annotations

import datetime as _dt
from pathlib import Path

from flexmvm.runs.provenance import run_inputs, run_key
from flexmvm.runs.stored_run import StoredRun, load_or_run
from flexmvm.scenarios import Scenario
from tools.validation.paths import git_commit

#: A stored case (runs.stored_run).
Case = StoredRun

#: The summary entries a case's report keeps of each run: conservation, solver health, cost.
CONSERVATION_KEYS = (
    "momentum_rel_error",
    "momentum_rel_error_converged",
    "momentum_residual_rel",
    "energy_rel_change",
    "max_penetration_m",
    "max_penetration_at",
    "max_penetration_by_direction_m",
    "lcp_residual_max",
    "steps_on_roundoff_floor",
    "newton_residual_max",
    "min_contact_force_interval_mean_N",
    "max_contact_force_interval_mean_N",
    "wall_time_s",
    "n_steps",
    "dof",
    "contact_intervals_s",
)


def case_inputs(sc: Scenario) -> dict:
    """Everything a run depends on (runs.provenance.run_inputs)."""
    return run_inputs(sc)


def case_key(sc: Scenario) -> str:
    """The key of a stored case (runs.provenance.run_key)."""
    return run_key(sc)


def now() -> str:
    """The report's time stamp: UTC to the minute."""
    return _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC")


def run_case(
    out: Path, name: str, sc: Scenario, recompute: bool = False, progress: bool = True
) -> Case:
    """Run scenario ``sc`` as case ``name`` under ``out``, or load it if a stored case has the
    same key and its outputs pass their check (module doc); a stored case that fails is
    recomputed and announced in one line."""
    return load_or_run(
        out / name,
        sc,
        f"validation case {name}",
        recompute,
        progress,
        lambda: {"commit": git_commit(), "computed_utc": now()},
    )


def conservation(summary: dict) -> dict:
    """The CONSERVATION_KEYS entries of a run's summary (None where absent)."""
    return {k: summary.get(k) for k in CONSERVATION_KEYS}


def case_meta(c: Case) -> dict:
    """What the report's table of cases shows of a stored case."""
    return {k: c.meta.get(k) for k in ("commit", "computed_utc", "code_version", "key")}


def truncate(c: Case, t_end: float) -> tuple:
    """The case's curves up to t_end [s]."""
    keep = c.t <= t_end * (1 + 1e-9)
    return c.t[keep], c.force[keep], {k: v[keep] for k, v in c.probes.items()}


__all__ = [
    "CONSERVATION_KEYS",
    "Case",
    "case_inputs",
    "case_key",
    "case_meta",
    "conservation",
    "now",
    "run_case",
    "truncate",
]
