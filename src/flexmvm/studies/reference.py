"""The full-FE reference of a study: run once, stored as ``reference/history.csv`` with the
scenario it was run from (``reference/reference.json``), reused while the study is the same."""

from __future__ import annotations

import json
from pathlib import Path

from flexmvm.errors import InputError
from flexmvm.results.atomic import canonical_json, file_sha256, write_json_atomic
from flexmvm.results.history import read_history, write_history
from flexmvm.scenarios import Scenario


def reference_history(sc: Scenario, body: str, out_dir: Path, progress: bool = False
                      ) -> tuple[Path, bool]:
    """The full-FE reference history of the study (computed once, reused while the scenario is
    the same). Returns (path of history.csv, True if it was computed now)."""
    from flexmvm.scenarios.run import run_scenario
    from flexmvm.studies.grid import reference_scenario

    ref_dir = Path(out_dir) / "reference"
    hist, meta = ref_dir / "history.csv", ref_dir / "reference.json"
    ident = {"body": body, "scenario": sc.model_dump(mode="json")}
    if hist.is_file() and meta.is_file():
        stored = json.loads(meta.read_text(encoding="utf-8"))
        if canonical_json(stored.get("identity")) == canonical_json(ident):
            return hist, False
        raise InputError(f"{meta}: the stored reference was run from another scenario or body; "
                         "expected the same study (use another --out or delete the directory)")
    ref_dir.mkdir(parents=True, exist_ok=True)
    run = run_scenario(reference_scenario(sc, body), label="full", progress=progress)
    t, f, probes = run.result.curves()
    write_history(hist, t, f, probes)
    write_json_atomic(meta, {"identity": ident, "summary": run.summary})
    return hist, True


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
        raise InputError(f"case {case.key}: {reference} is not the reference of this case "
                         "(its SHA-256 differs)")
    return read_history(Path(reference))
