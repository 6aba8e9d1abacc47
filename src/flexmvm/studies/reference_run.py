"""The full-FE reference of a study: run once, stored as ``reference/history.csv`` with the
scenario it was run from (``reference/reference.json``), reused while the study is the same.

reference.json holds {identity (body, scenario), provenance (runs.provenance.stamp of
the reference run: package source, numpy/scipy/numba, resolved scenario, mesh files), history
(results.history.history_record: SHA-256, samples, first and last time), summary}. A stored
reference of another study (identity) is refused; one run under another code version, one
without that record, or a history that fails its check (cut short, edited) is recomputed,
and that is announced in one line (``reference history.csv: 7 of 31 samples (expected
window 0..30 us): recomputed``).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from flexmvm.errors import InputError, announce_recompute
from flexmvm.results.atomic import canonical_json, file_sha256, write_json_atomic
from flexmvm.results.history import history_problem, history_record, read_history, write_history
from flexmvm.results.output import writing
from flexmvm.runs.compare import compare_runs
from flexmvm.runs.guard import validity_fields
from flexmvm.runs.provenance import stamp, stamp_mismatch
from flexmvm.scenarios import Scenario


def _read_meta(meta: Path) -> dict | None:
    try:
        stored = json.loads(meta.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return None
    return stored if isinstance(stored, dict) else None


def reference_problem(sc: Scenario, body: str, out_dir: Path) -> str | None:
    """Why the stored reference of the study (``sc``, ``body``) in ``out_dir`` cannot be
    reused, one line naming the file ("reference history.csv: 7 of 31 samples (expected
    window 0..30 us)"); None if it can, or if there is none (nothing to announce).

    Raises:
        InputError: the stored reference is of another scenario or body (another study).
    """
    from flexmvm.studies.grid import reference_scenario

    ref_dir = Path(out_dir) / "reference"
    hist, meta = ref_dir / "history.csv", ref_dir / "reference.json"
    if not hist.exists() and not meta.exists():
        return None
    stored = _read_meta(meta) if meta.exists() else None
    if stored is None:
        return f"reference {meta.name}: missing or unreadable"
    ident = {"body": body, "scenario": sc.model_dump(mode="json")}
    if canonical_json(stored.get("identity")) != canonical_json(ident):
        raise InputError(
            f"{meta}: the stored reference was run from another scenario or body; "
            "expected the same study (use another --out or delete the directory)"
        )
    stale = stamp_mismatch(stored.get("provenance"), stamp(reference_scenario(sc, body)))
    if stale is not None:
        return f"reference {hist.name}: {stale}"
    if not hist.exists():
        return f"reference {hist.name}: missing"
    bad = history_problem(hist, stored.get("history"), sc.time.t_end_s)
    return None if bad is None else f"reference {hist.name}: {bad}"


def reference_history(
    sc: Scenario,
    body: str,
    out_dir: Path,
    progress: bool = False,
    announce: Callable[[str], Any] = announce_recompute,
) -> tuple[Path, bool]:
    """The full-FE reference history of the study (computed once, reused while the scenario,
    the code and the file are the same; module doc). A stored reference that fails its check
    is recomputed and ``announce``d (one line). Returns (path of history.csv, True if it was
    computed now). InputError if the stored reference is of another study."""
    from flexmvm.runs.run import run_scenario
    from flexmvm.studies.grid import reference_scenario

    ref_dir = Path(out_dir) / "reference"
    hist, meta = ref_dir / "history.csv", ref_dir / "reference.json"
    problem = reference_problem(sc, body, out_dir)
    if problem is None and hist.is_file():
        return hist, False
    if problem is not None:
        announce(f"{problem}: recomputed")
    ref_dir.mkdir(parents=True, exist_ok=True)
    meta.unlink(missing_ok=True)  # a half-rewritten reference never passes its check
    ref = reference_scenario(sc, body)
    run = run_scenario(ref, label="full", progress=progress)
    t, f, probes = run.result.curves()
    with writing(hist):  # a full disk: OutputError naming the file
        write_history(hist, t, f, probes)
    with writing(meta):
        write_json_atomic(
            meta,
            {
                "identity": {"body": body, "scenario": sc.model_dump(mode="json")},
                "provenance": stamp(ref),
                "history": history_record(hist),
                "summary": run.summary,
            },
        )
    return hist, True


def study_version(sc: Scenario, reference: Path) -> dict:
    """The ``version`` of a study's cases (runner.run_cases): the provenance stamp of the study
    scenario ``sc`` (package source, numpy/scipy/numba, resolved scenario, mesh files) and the
    SHA-256 of the reference history they are compared with; a case stored under another is
    recomputed."""
    return {"provenance": stamp(sc), "reference_sha256": file_sha256(reference)}


def study_provenance(sc: Scenario, body: str, out_dir: Path) -> dict[str, Any]:
    """The provenance a study's summary JSON (selection.json, materials.json) carries, so that
    a copy of it (under docs/) is stamped on its own: {study: runs.provenance.stamp of the
    study scenario ``sc`` (package source, libraries with scikit-fem and gmsh, resolved
    scenario, mesh files: what its cases are keyed by), reference: the stamp stored in
    ``out_dir/reference/reference.json`` (the full-FE reference run of ``body``; None if
    there is none), reference_sha256: SHA-256 of its history.csv (None if absent)}."""
    ref_dir = Path(out_dir) / "reference"
    meta = _read_meta(ref_dir / "reference.json") or {}
    hist = ref_dir / "history.csv"
    return {
        "study": stamp(sc),
        "reference": meta.get("provenance"),
        "reference_sha256": file_sha256(hist) if hist.is_file() else None,
    }


def case_reference(case, reference=None):
    """(t, force, probes) of the stored reference history a study case is compared with:
    ``reference`` (default: ``case.params["reference"]``), checked against the case's
    ``reference_sha256`` when it has one. InputError (one line) if there is none or it is
    not this case's."""
    p = case.params
    reference = reference if reference is not None else p.get("reference")
    if reference is None:
        raise InputError(f"case {case.key}: no reference history given")
    sha = p.get("reference_sha256")
    if sha is not None and file_sha256(reference) != sha:
        raise InputError(
            f"case {case.key}: {reference} is not the reference of this case (its SHA-256 differs)"
        )
    return read_history(Path(reference))


def scored_row(row: dict, run, body: str, t_ref, f_ref, probes_ref) -> dict:
    """A study case's row completed by its run against the reference histories: the
    comparison's numbers (runs.compare.compare_runs), its first error as "failed", the
    validity fields of ``body`` (runs.guard), a plastic ``body``'s plastic work [J],
    permanent indentation [m] and plastic cells (summary.json ``plastic``) and the run's wall
    time."""
    cmp = compare_runs(t_ref, f_ref, probes_ref, *run.result.curves())
    row.update({k: v for k, v in cmp.items() if isinstance(v, float)})
    errors = [v for k, v in cmp.items() if k.endswith("_error")]
    if errors:
        row["failed"] = errors[0]
    row.update(validity_fields(run.summary, body))
    plastic = run.summary.get("plastic", {}).get(body)
    if plastic is not None:  # a plastic body: what its zone did, beside the guard's count
        row["plastic_work_J"] = float(plastic["plastic_work_J"])
        row["permanent_indentation_m"] = plastic["permanent_indentation_m"]  # None: no contact
        row["plastic_cells"] = int(plastic["plastic_cells"])
    row["wall_time_s"] = float(run.summary["wall_time_s"])
    return row
