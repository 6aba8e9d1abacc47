"""Selection study (seed section 3.2): node selection x mode count against the full FE force.

One body of a scenario (the *study body*, b2 in the seed) is modelled by the MVM
(Craig-Bampton: the retained "region II" nodes of the seed's ``i-j`` selection + ``m``
fixed-interface modes) for every ``(i, j, m)`` of a grid; every other body keeps its model
from the scenario (b1 stays full FE, as in the seed) unless ``other`` replaces it (e.g. a
converged MVM model of the striker, ``mvm:3-5:40``, to make a seed-scale sweep affordable:
the reference and every candidate then share that model, so the comparison still isolates
the study body's reduction). Each run is compared with a reference
run in which the study body is full FE (the other bodies unchanged), computed once before the
sweep and stored in ``DIR/reference/history.csv``.

DOF convention. ``dof`` is the number of *elastic* generalized coordinates of the study body,
``3 x retained nodes + modes`` (the seed's count: 1-1 with 37 modes = 40 DOF). The six
floating-frame coordinates (``BodyInfo.dof`` counts them) are reported as ``dof_total = dof + 6``.

Files of a study directory ``DIR``:

- ``reference/history.csv`` (+ ``reference/reference.json``: the scenario it was run from, so a
  rerun reuses it only for the same scenario), the full-FE reference;
- ``cases/<key>.json`` one per MVM run (flexmvm.studies.runner: atomic, a rerun resumes), key
  ``l<i>-j<j>-m<m>``;
- ``ncc.csv``: ``layers,laps,nodes,modes,dof,ncc_force,ncc_<probe>...,peak_err,impulse_err,
  duration_err,wall_time_s``, one row per evaluated case sorted by (layers, laps, modes); empty
  metric cells for a run that failed (solver did not converge, the case raised: its
  ``cases/<key>.error.txt`` holds the traceback and a rerun tries it again);
- ``selection.json``: the smallest-DOF model reaching the target, the run counts, the target,
  ``failures`` (``{"case", "reason"}`` of every run without a comparison; also printed);
- ``fig7_ncc_map.png`` (NCC of the force over selection x modes, seed fig. 7) and
  ``fig8_ncc_modes.png`` (NCC against modes per selection, seed fig. 8).

A-priori estimate (:func:`estimate_selection`), without any FE time integration:

- *modes*: the contact force of the 1D wave + Hertz theory (flexmvm.theory.wave; Hertz for a
  hemispherical end of either rod, St Venant otherwise) gives the contact duration ``T_c`` (first
  interval with F > 1 % of the peak, clipped to the scenario's end time, since only that window
  is compared). The force pulse has its energy below ~1/T_c; the modes needed are the
  fixed-interface modes with frequency below ``f_max = k / T_c`` (default ``k = 3``), rounded up
  to the next mode count of the grid.
- *nodes*: in a Craig-Bampton basis the constraint modes reproduce the static response to loads
  at the retained nodes exactly, so the static decay of the Hertz stress field below the contact
  needs no extra node layers: one layer (the contact face) suffices, with the laps whose ring
  radius lies inside the Hertz contact radius ``a = (3 F_max R / 4 E*)^(1/3)`` at the theory's
  peak force (at least lap 1, the axis node).

On tests/data/tiny_impact.toml (30 us window, b2 aluminium, grid 1..2 x 1..2 x {7, 13}) the
estimate is 1-1 with 13 modes, 16 DOF: a = 0.16 mm is inside the first ring (0.25 mm), T_c is
clipped to the 30 us window so f_max = 100 kHz, and 13 fixed-interface modes lie below it
(the first at 11.7 kHz). Brute force: every model has a force NCC above 0.99998 in that window
(the force is still rising); for ``ncc>=0.99`` the smallest is 1-1 with 7 modes (10 DOF, the
estimate is conservative), for the median NCC of the grid (0.9999914) it is 1-1 with 13 modes,
the estimate (tests/test_studies.py checks that the estimate reaches the median target and is
no larger than the brute-force winner there).
"""

from __future__ import annotations

import functools
import json
import math
import statistics
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from flexmvm.errors import InputError, SolverError
from flexmvm.metrics.ncc import Comparison, Target, contact_intervals
from flexmvm.results.atomic import (
    canonical_json,
    write_json_atomic,
    write_table_csv,
)
from flexmvm.results.history import read_history, write_history
from flexmvm.results.outdir import make_out_dir
from flexmvm.scenarios.compare import compare_runs, run_curves
from flexmvm.scenarios.schema import (
    ModelConfig,
    ModelKind,
    Scenario,
    load_scenario,
    scenario_from_dict,
)
from flexmvm.studies.runner import Case, case_path, run_cases
from flexmvm.studies.search import Candidate, rank_key, smallest_passing

__all__ = [
    "FAIL_SCORE",
    "cluster",
    "estimate_selection",
    "ncc_columns",
    "reference_history",
    "rod_of",
    "run_selection_case",
    "run_selection_study",
    "score",
    "selection_cases",
]

#: Score of a run that failed or misses a non-NCC bound of the target (below any NCC).
FAIL_SCORE = -2.0
_METRICS = ("ncc_force", "peak_err", "impulse_err", "duration_err")


# ----------------------------------------------------------------------------------------------
# grid and cases
def rod_of(sc: Scenario, body: str):
    """The (cached) RodMesh of rod body ``body``; InputError if there is no such rod body."""
    from flexmvm.scenarios.build import cached_rod_mesh, rod_spec

    cfg = sc.body(body)
    if cfg.rod is None:
        raise InputError(f"body {body!r} is not a rod ([bodies.rod]); the i-j selection needs one")
    return cached_rod_mesh(rod_spec(cfg.rod))


def _ints(name: str, values: Iterable[int]) -> list[int]:
    out = sorted({int(v) for v in values})
    if not out or out[0] < 1:
        raise InputError(f"{name}: expected integers >= 1, got {list(values)!r}")
    return out


def check_grid(sc: Scenario, body: str, layers, laps, modes):
    rod = rod_of(sc, body)
    layers, laps, modes = _ints("layers", layers), _ints("laps", laps), _ints("modes", modes)
    for name, vals, top in (("layers", layers, rod.n_layers), ("laps", laps, rod.n_laps)):
        if vals[-1] > top:
            raise InputError(f"{name} up to {vals[-1]} exceeds the mesh of body {body!r}: "
                             f"maximum {top} {name}")
    return rod, layers, laps, modes


def case_key(layers: int, laps: int, modes: int) -> str:
    return f"l{layers}-j{laps}-m{modes}"


def selection_cases(sc: Scenario, body: str, layers: Iterable[int] = range(1, 5),
                    laps: Iterable[int] = range(1, 6), modes: Iterable[int] = range(7, 44, 6),
                    reference: str | Path | None = None) -> list[Case]:
    """The cases of the grid layers x laps x modes for body ``body`` of scenario ``sc``.

    Keys ``l<i>-j<j>-m<m>``; params {body, layers, laps, modes, modes_max (the grid's largest
    mode count: each selection's Craig-Bampton basis is solved once with it and cut,
    scenarios.build.craig_bampton_mode_floor), scenario (sc.model_dump(json)),
    reference_sha256 (of the reference history CSV ``reference``, or None)}. The path itself is
    not a parameter, so a study directory can be moved; it is given to the case function as
    ``functools.partial(run_selection_case, reference=path)``. Raises InputError for an
    unknown or non-rod body, or layers/laps beyond the rod mesh (naming the maximum).
    """
    _, layers, laps, modes = check_grid(sc, body, layers, laps, modes)
    data = sc.model_dump(mode="json")
    sha = file_sha256(reference) if reference is not None else None
    top = max(modes)
    return [Case(case_key(i, j, m), {"body": body, "layers": i, "laps": j, "modes": m,
                                     "modes_max": top, "scenario": data, "reference_sha256": sha})
            for i in layers for j in laps for m in modes]


def file_sha256(path: str | Path) -> str:
    import hashlib

    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def parse_model(text: str) -> ModelConfig | None:
    """'scenario' -> None (keep); 'full'; 'mvm:I-J:M' (Craig-Bampton, selection I-J, M modes).
    The reference condition is the rod default (end_b). InputError (one line) otherwise."""
    t = text.strip().lower()
    if t == "scenario":
        return None
    if t == "full":
        return ModelConfig(kind=ModelKind.FULL, reference="end_b")
    bits = t.split(":")
    if len(bits) == 3 and bits[0] == "mvm" and bits[2].isdigit():
        try:
            return ModelConfig(kind=ModelKind.MVM, selection=bits[1], modes=int(bits[2]),
                               reference="end_b")
        except ValueError:
            pass
    raise InputError(f"model {text!r}: expected 'scenario', 'full' or 'mvm:I-J:M' "
                     "(e.g. mvm:3-5:40)")


def study_scenario(sc: Scenario, body: str, *, t_end_s: float | None = None,
                   dt_s: float | None = None, other: str | ModelConfig | None = None) -> Scenario:
    """The scenario a study runs: end time and contact step overridden, and the model of
    every body other than ``body`` (rigid ones excepted) replaced by ``other`` (a
    ModelConfig or parse_model text; None keeps the scenario's)."""
    sc.body(body)
    if isinstance(other, str):
        other = parse_model(other)
    models = {}
    if other is not None:
        models = {b.name: other for b in sc.bodies
                  if b.name != body and b.model.kind is not ModelKind.RIGID}
    if t_end_s is None and dt_s is None and not models:
        return sc
    return sc.with_overrides(t_end_s=t_end_s, dt_s=dt_s, body_models=models or None)


def _mvm_scenario(sc: Scenario, body: str, layers: int, laps: int, modes: int) -> Scenario:
    ref = sc.body(body).model.reference
    cfg = ModelConfig(kind=ModelKind.MVM, selection=f"{layers}-{laps}", modes=modes, reference=ref)
    return sc.with_overrides(body_models={body: cfg})


def _reference_scenario(sc: Scenario, body: str) -> Scenario:
    ref = sc.body(body).model.reference
    return sc.with_overrides(body_models={body: ModelConfig(kind=ModelKind.FULL, reference=ref)})


def run_selection_case(case: Case, reference: str | Path | None = None) -> dict:
    """One MVM run of a selection study against the stored reference history ``reference``
    (default: ``case.params["reference"]``), module doc.

    Returns {layers, laps, nodes, modes, dof, dof_total, ncc_force, ncc_<probe>..., peak_err,
    impulse_err, duration_err, wall_time_s}; a run whose solver fails returns the grid fields
    with ``failed`` (one line) instead of the metrics.
    """
    from flexmvm.scenarios.run import run_scenario

    p = case.params
    sc = scenario_from_dict(p["scenario"], source=f"case {case.key}")
    body, i, j, m = p["body"], int(p["layers"]), int(p["laps"]), int(p["modes"])
    reference = reference if reference is not None else p.get("reference")
    if reference is None:
        raise InputError(f"case {case.key}: no reference history given")
    sha = p.get("reference_sha256")
    if sha is not None and file_sha256(reference) != sha:
        raise InputError(f"case {case.key}: {reference} is not the reference of this case "
                         "(its SHA-256 differs)")
    t_ref, f_ref, probes_ref = read_history(Path(reference))
    nodes = len(rod_of(sc, body).selection(i, j))
    row: dict[str, Any] = {"layers": i, "laps": j, "nodes": nodes, "modes": m,
                           "dof": 3 * nodes + m, "dof_total": 3 * nodes + m + 6}
    from flexmvm.scenarios.build import craig_bampton_mode_floor

    try:
        with craig_bampton_mode_floor(int(p.get("modes_max", m))):
            run = run_scenario(_mvm_scenario(sc, body, i, j, m))
    except SolverError as exc:
        return row | {"failed": str(exc).splitlines()[0]}
    info = next(b for b in run.built.info if b.name == body)
    assert info.dof - 6 == 3 * info.n_retained_nodes + info.n_modes == row["dof"], info
    cmp = compare_runs(t_ref, f_ref, probes_ref, *run_curves(run.result))
    row.update({k: v for k, v in cmp.items() if isinstance(v, float)})
    errors = [v for k, v in cmp.items() if k.endswith("_error")]
    if errors:
        row["failed"] = errors[0]
    row["wall_time_s"] = float(run.summary["wall_time_s"])
    return row


def score(row: dict, target: Target) -> float:
    """NCC of the force if the row meets the target's error bounds, else FAIL_SCORE; so that
    ``score >= target.ncc_min`` is ``target.met_by(...)``."""
    if any(k not in row for k in _METRICS):
        return FAIL_SCORE
    c = Comparison(row["ncc_force"], row["peak_err"], row["impulse_err"], row["duration_err"])
    if not target.met_by(Comparison(1.0, c.peak_err, c.impulse_err, c.duration_err)):
        return FAIL_SCORE
    return float(c.ncc)


# ----------------------------------------------------------------------------------------------
# reference
def reference_history(sc: Scenario, body: str, out_dir: Path, progress: bool = False
                      ) -> tuple[Path, bool]:
    """The full-FE reference history of the study (computed once, reused while the scenario is
    the same). Returns (path of history.csv, True if it was computed now)."""
    from flexmvm.scenarios.run import run_scenario

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
    run = run_scenario(_reference_scenario(sc, body), label="full", progress=progress)
    t, f, probes = run_curves(run.result)
    write_history(hist, t, f, probes)
    write_json_atomic(meta, {"identity": ident, "summary": run.summary})
    return hist, True


# ----------------------------------------------------------------------------------------------
# driver
class cluster:
    """Context manager: the scheduler address to give run_cases for a whole study. Starts one
    LocalCluster of n_workers processes (closed at exit) unless an address is given or
    ``serial``; yields None for serial runs."""

    def __init__(self, scheduler: str | None, n_workers: int | None, serial: bool) -> None:
        self.scheduler, self.n_workers, self.serial = scheduler, n_workers, serial
        self._cluster = None

    def __enter__(self) -> str | None:
        if self.serial or self.scheduler is not None:
            return self.scheduler
        import os

        from flexmvm.studies.runner import local_cluster

        n = self.n_workers or os.cpu_count() or 1
        if n < 1:
            raise InputError(f"workers: expected a positive integer, got {n}")
        self._cluster = local_cluster(n)
        return self._cluster.scheduler_address

    def __exit__(self, *exc) -> None:
        if self._cluster is not None:
            self._cluster.close()


class _Batches:
    """Runs batches of cases through run_cases (shared cluster) and counts made/loaded runs.
    A case that raised (not stored; a rerun tries it again) gets the row failed_row(case,
    one line), so it is listed, and scored as failed, like a run whose solver failed."""

    def __init__(self, out_dir: Path, address: str | None, serial: bool, progress: bool,
                 fn: Callable[[Case], dict], failed_row: Callable[[Case, str], dict]) -> None:
        self.out_dir, self.address, self.serial, self.progress = out_dir, address, serial, progress
        self.fn, self.failed_row = fn, failed_row
        self.made: set[str] = set()
        self.loaded: set[str] = set()
        self.rows: dict[str, dict] = {}

    def __call__(self, cases: Sequence[Case]) -> list[dict]:
        stored = {c.key for c in cases if case_path(self.out_dir, c.key).is_file()}
        kw: dict[str, Any] = {"serial": True} if self.serial else {"scheduler": self.address}
        failures: dict[str, str] = {}
        res = run_cases(cases, self.fn, self.out_dir, progress=self.progress, failures=failures,
                        **kw)
        for c in cases:
            (self.loaded if c.key in stored else self.made).add(c.key)
            self.rows[c.key] = (res[c.key] if c.key in res
                                else self.failed_row(c, failures.get(c.key, "failed")))
        return [self.rows[c.key] for c in cases]


def failed_case_row(case: Case, line: str, nodes: int) -> dict:
    """The ncc.csv row of a case that raised: its grid fields and ``failed``, no metrics."""
    p = case.params
    i, j, m = int(p["layers"]), int(p["laps"]), int(p["modes"])
    return {"layers": i, "laps": j, "nodes": nodes, "modes": m, "dof": 3 * nodes + m,
            "dof_total": 3 * nodes + m + 6, "failed": line}


def failure_list(keyed_rows: Iterable[tuple[str, dict]]) -> list[dict]:
    """[{"case", "reason"}] of the rows that carry ``failed``, sorted by case key."""
    return sorted(({"case": k, "reason": r["failed"]} for k, r in keyed_rows if "failed" in r),
                  key=lambda f: f["case"])


def echo_failures(echo: Callable[[str], Any], failures: Sequence[dict], n_runs: int,
                  where: str, shown: int = 5) -> None:
    """One console line per failed case (the first ``shown``), then where the rest are."""
    if not failures:
        return
    echo(f"{len(failures)} of {n_runs} runs failed (listed in {where}):")
    for f in failures[:shown]:
        echo(f"  {f['case']}: {f['reason']}")
    if len(failures) > shown:
        echo(f"  ... and {len(failures) - shown} more")


def ncc_columns(probes: Sequence[str]) -> list[str]:
    return (["layers", "laps", "nodes", "modes", "dof", "ncc_force"]
            + [f"ncc_{p}" for p in probes] + ["peak_err", "impulse_err", "duration_err",
                                                "wall_time_s"])


def write_ncc_csv(path: Path, rows: Iterable[dict], probes: Sequence[str]) -> list[dict]:
    cols = ncc_columns(probes)
    rows = sorted(rows, key=lambda r: (r["layers"], r["laps"], r["modes"]))
    write_table_csv(path, cols, rows)
    return rows


def _winner_dict(best: Candidate | None, rows: dict[tuple, dict]) -> dict:
    if best is None:
        return {"passed": False}
    r = rows[(*best.selection, best.modes)]
    return {"passed": True, "layers": r["layers"], "laps": r["laps"], "nodes": r["nodes"],
            "modes": r["modes"], "dof": r["dof"], "dof_total": r["dof_total"],
            "ncc_force": r.get("ncc_force")}


def run_selection_study(scenario_path: str | Path, body: str, out_dir: str | Path,
                        layers: Iterable[int] = range(1, 5), laps: Iterable[int] = range(1, 6),
                        modes: Iterable[int] = range(7, 44, 6), target: Target | None = None,
                        search: bool = False, scheduler: str | None = None,
                        n_workers: int | None = None, progress: bool = True, *,
                        t_end_s: float | None = None, dt_s: float | None = None,
                        other: str | None = None, serial: bool = False,
                        echo: Callable[[str], Any] = print) -> dict:
    """The selection study of ``body`` in ``scenario_path`` (module doc), written to out_dir.

    Brute force runs every case of the grid; ``search=True`` runs
    studies.search.smallest_passing, each round's batch through run_cases (parallel,
    resumable). ``scheduler``: address of a Dask scheduler; otherwise one LocalCluster of
    ``n_workers`` processes for the whole study, or in-process with ``serial=True``.
    ``t_end_s``, ``dt_s`` override the scenario's end time and contact step, ``other`` the
    model of the other bodies (study_scenario). Returns the selection.json content.

    Raises InputError for a bad body / grid / options, SolverError if the reference fails or,
    after everything is written, if every run failed. Failed runs are listed in the result's
    ``failures`` and printed; they count as not reaching the target.
    """
    target = Target(0.99) if target is None else target
    out = Path(out_dir).resolve()
    sc = load_scenario(scenario_path)
    check_grid(sc, body, layers, laps, modes)
    sc = study_scenario(sc, body, t_end_s=t_end_s, dt_s=dt_s, other=other)
    rod, layers, laps, modes = check_grid(sc, body, layers, laps, modes)
    if serial and (scheduler is not None or n_workers is not None):
        raise InputError("serial=True received with scheduler/workers; expected one")
    if scheduler is not None and n_workers is not None:
        raise InputError("--workers applies to a local cluster; expected no --scheduler with it")
    make_out_dir(out)
    hist, ref_made = reference_history(sc, body, out, progress=progress)
    echo(f"reference (full FE {body}): {'computed' if ref_made else 'loaded'} {hist}")
    cases = {(c.params["layers"], c.params["laps"], c.params["modes"]): c
             for c in selection_cases(sc, body, layers, laps, modes, reference=hist)}
    cands = {k: Candidate((k[0], k[1]), k[2], 3 * len(rod.selection(k[0], k[1])) + k[2])
             for k in cases}
    key_of = {v: k for k, v in cands.items()}
    with cluster(scheduler, n_workers, serial) as address:
        batches = _Batches(out, address, serial, progress,
                           functools.partial(run_selection_case, reference=str(hist)),
                           lambda c, line: failed_case_row(
                               c, line, len(rod.selection(c.params["layers"],
                                                          c.params["laps"]))))

        def evaluate(batch: Sequence[Candidate]) -> list[float]:
            rows = batches([cases[key_of[c]] for c in batch])
            return [score(r, target) for r in rows]

        def passes(s: float) -> bool:
            return s >= target.ncc_min

        if search:
            best, scores = smallest_passing(list(cands.values()), evaluate, passes)
        else:
            evaluate(list(cands.values()))
            scores = {c: score(batches.rows[cases[key_of[c]].key], target)
                      for c in cands.values()}
            passing = [(rank_key(c, s), c) for c, s in scores.items() if passes(s)]
            best = min(passing, key=lambda x: x[0])[1] if passing else None
    rows = {(r["layers"], r["laps"], r["modes"]): r for r in batches.rows.values()}
    probes = [p.name for p in sc.probes]
    table = write_ncc_csv(out / "ncc.csv", rows.values(), probes)
    result = _winner_dict(best, rows) | {
        "body": body, "search": bool(search), "target": _target_dict(target),
        "runs": len(scores), "runs_made": len(batches.made), "runs_loaded": len(batches.loaded),
        "runs_note": "runs = MVM cases evaluated for this answer = runs_made (computed in this "
                     "invocation) + runs_loaded (found stored in cases/); the full-FE reference "
                     "is not counted",
        "reference_computed": ref_made, "grid": {"layers": layers, "laps": laps, "modes": modes},
        "dof_note": "dof = 3 x retained nodes + modes (elastic coordinates, seed count); "
                    "dof_total adds the 6 floating-frame coordinates",
        "failed_cases": sorted(case_key(r["layers"], r["laps"], r["modes"])
                               for r in table if "failed" in r),
        "failures": failure_list((case_key(r["layers"], r["laps"], r["modes"]), r)
                                 for r in table),
        "failures_note": "failures: the runs that gave no comparison (the solver failed, the "
                         "case raised: see cases/<key>.error.txt, a rerun tries it again; or a "
                         "metric could not be computed); they count as not reaching the target",
    }
    write_json_atomic(out / "selection.json", result)
    from flexmvm.plots.study_figures import plot_ncc_map, plot_ncc_modes

    plot_ncc_map(out / "fig7_ncc_map.png", table, title=f"{sc.name}: NCC of the contact force")
    plot_ncc_modes(out / "fig8_ncc_modes.png", table, title=f"{sc.name}: NCC against modes")
    echo_failures(echo, result["failures"], result["runs"], out / "selection.json")
    if result["passed"]:
        echo(f"smallest model reaching {_target_text(target)}: {result['layers']}-{result['laps']}"
             f" with {result['modes']} modes, {result['dof']} DOF ({result['nodes']} nodes), "
             f"NCC {result['ncc_force']:.6f}; {result['runs']} runs ({result['runs_made']} made,"
             f" {result['runs_loaded']} loaded)")
    else:
        echo(f"no model of the grid reaches {_target_text(target)}; {result['runs']} runs "
             f"({result['runs_made']} made, {result['runs_loaded']} loaded)")
    if result["failures"] and len(result["failures"]) == result["runs"]:
        first = result["failures"][0]
        raise SolverError(f"selection study: every run failed ({first['case']}: "
                          f"{first['reason']}); see {out / 'selection.json'}")
    return result


def _target_dict(t: Target) -> dict:
    return {k: getattr(t, k) for k in ("ncc_min", "peak_err_max", "impulse_err_max",
                                       "duration_err_max")}


def _target_text(t: Target) -> str:
    parts = [f"ncc>={t.ncc_min:g}"]
    for key, name in (("peak_err_max", "peak"), ("impulse_err_max", "impulse"),
                      ("duration_err_max", "duration")):
        if getattr(t, key) is not None:
            parts.append(f"{name}<={getattr(t, key):g}")
    return ",".join(parts)


# ----------------------------------------------------------------------------------------------
# a-priori estimate
def _contact_bodies(sc: Scenario, body: str):
    for c in sc.contacts:
        if body in (c.slave_body, c.master_body):
            other = c.master_body if c.slave_body == body else c.slave_body
            return sc.body(body), sc.body(other)
    raise InputError(f"body {body!r} is in no contact of the scenario; the estimate needs one")


def theory_pulse(sc: Scenario, body: str) -> dict:
    """1D wave(-Hertz) force pulse of the contact of ``body``: T_c, peak force, law, a (m)."""
    from flexmvm.theory.wave import ContactLaw, Rod1D, hertz_stiffness, two_rod_impact

    b, other = _contact_bodies(sc, body)
    if other.rod is None or b.rod is None:
        raise InputError("the estimate needs two rods ([bodies.rod])")
    hemi = [x for x in (other, b) if str(getattr(x.rod.end_a, "value", x.rod.end_a)) == "hemisphere"]
    rods = {x.name: Rod1D.from_material(x.material_obj(), x.rod.length_m, x.rod.radius_m)
            for x in (b, other)}
    axis = b.placement.rotation.matrix()[:, 0]
    v0 = abs(float(axis @ (np.asarray(other.placement.velocity_mps)
                           - np.asarray(b.placement.velocity_mps))))
    if v0 == 0.0:
        raise InputError("the estimate needs an impact speed: both rods are at rest")
    striker = hemi[0] if hemi else other
    target_b = b if striker is other else other
    r1, r2 = rods[striker.name], rods[target_b.name]
    law = ContactLaw.HERTZ if hemi else ContactLaw.RIGID
    radius = striker.rod.radius_m if hemi else None
    t_end = max(4.0 * max(r1.round_trip_s, r2.round_trip_s), sc.time.t_end_s)
    sol = two_rod_impact(r1, r2, v0, t_end, law, sphere_radius_m=radius)
    f = sol.contact_force
    fmax = float(f.max())
    first = contact_intervals(sol.t, f, 0.01 * fmax)[0]
    t_c = first[1] - first[0]
    # peak within the compared window
    fwin = float(f[sol.t <= sc.time.t_end_s].max())
    a = 0.0
    if hemi:
        k = hertz_stiffness(r1, r2, radius)
        e_star = 3.0 * k / (4.0 * math.sqrt(radius))
        a = (3.0 * fwin * radius / (4.0 * e_star)) ** (1.0 / 3.0)
    return {"law": law.value, "v0_mps": v0, "contact_duration_s": t_c, "peak_force_N": fmax,
            "peak_force_window_N": fwin, "contact_radius_m": a, "sphere_radius_m": radius}


def estimate_selection(sc: Scenario, body: str, target: Target | None = None, *, k: float = 3.0,
                       modes: Sequence[int] = tuple(range(7, 44, 6))) -> dict:
    """A-priori MVM model of ``body`` without a full-FE run (module doc: the rule).

    Returns {layers, laps, nodes, modes, dof, f_max_hz, contact_duration_s, window_s,
    contact_radius_m, n_modes_below_f_max, rule}. ``target`` is recorded only: the rule does
    not depend on the NCC level (k sets the bandwidth).
    """
    from flexmvm.reduction.basis import BasisKind
    from flexmvm.scenarios.build import basis_for, rod_spec

    if not k > 0:
        raise InputError(f"k: expected a number > 0, got {k!r}")
    rod = rod_of(sc, body)
    pulse = theory_pulse(sc, body)
    window = min(pulse["contact_duration_s"], sc.time.t_end_s)
    f_max = k / window
    a = pulse["contact_radius_m"]
    face = np.flatnonzero(rod.node_layer == 1)
    X = rod.mesh.nodes
    r = np.hypot(X[face, 1], X[face, 2])
    laps = 1
    for j in range(2, rod.n_laps + 1):
        ring = r[rod.node_lap[face] == j]
        if ring.size and float(ring.min()) <= a:
            laps = j
    sel = tuple(int(i) for i in rod.selection(1, laps))
    cfg = sc.body(body)
    grid = sorted(int(m) for m in modes)
    basis = basis_for(rod_spec(cfg.rod), cfg.material_obj(), BasisKind.CRAIG_BAMPTON, sel,
                   grid[-1], cfg.model.reference)
    n_below = int(np.count_nonzero(basis.mode_freqs_hz < f_max))
    m = next((g for g in grid if g >= n_below), grid[-1])
    nodes = len(sel)
    return {"layers": 1, "laps": laps, "nodes": nodes, "modes": m, "dof": 3 * nodes + m,
            "f_max_hz": f_max, "k": k, "window_s": window, "n_modes_below_f_max": n_below,
            "grid_max_modes_insufficient": n_below > grid[-1],
            "first_mode_hz": float(basis.mode_freqs_hz[0]),
            "target": None if target is None else _target_dict(target),
            **{f"theory_{k2}": v for k2, v in pulse.items()},
            "rule": "modes: fixed-interface modes below k/T_c (T_c = 1D wave-Hertz contact "
                    "duration clipped to the window), rounded up to the grid; nodes: layer 1, "
                    "the laps inside the Hertz contact radius at the window's peak force"}


def median_ncc(rows: Iterable[dict]) -> float:
    """Median force NCC of rows that have one (used to derive a target splitting a grid)."""
    vals = [r["ncc_force"] for r in rows if "ncc_force" in r]
    if not vals:
        raise InputError("no row has an NCC of the force")
    return float(statistics.median(vals))
