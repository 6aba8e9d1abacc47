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

A body of any mesh (issue 34) has no i-j rings: its families are *regions*, balls of given
radii about one centre or node sets of its mesh (studies/region_families.py), x the same mode counts,
with the same reference, cases, resume, search and guard; its ncc.csv rows carry ``region``
instead of ``layers, laps`` and its figure is the NCC-DOF front (fig_front_ncc_dof.png).

DOF convention. ``dof`` is the number of *elastic* generalized coordinates of the study body,
``3 x retained nodes + modes`` (the seed's count: 1-1 with 37 modes = 40 DOF). The six
floating-frame coordinates (``BodyInfo.dof`` counts them) are reported as ``dof_total = dof + 6``.

Files of a study directory ``DIR``:

- ``reference/history.csv`` (+ ``reference/reference.json``: the scenario it was run from, so a
  rerun reuses it only for the same scenario, its provenance stamp and the history's record,
  checked before reuse: studies/reference_run.py), the full-FE reference;
- ``cases/<key>.json`` one per MVM run (flexmvm.studies.runner: atomic, a rerun resumes; a case
  of another code version or reference, or a damaged one, is recomputed and said), key
  ``l<i>-j<j>-m<m>``;
- ``ncc.csv``: ``layers,laps,nodes,modes,dof,ncc_force,ncc_<probe>...,peak_err,impulse_err,
  duration_err,wall_time_s``, one row per evaluated case sorted by (layers, laps, modes); empty
  metric cells for a run that failed (solver did not converge, the case raised: its
  ``cases/<key>.error.txt`` holds the traceback and a rerun tries it again);
- ``selection.json``: the smallest-DOF model reaching the target, the run counts, the target,
  ``failures`` (``{"case", "reason"}`` of every run without a comparison; also printed),
  ``provenance`` (reference_run.study_provenance: the study's and its reference's stamps, so
  that a copy of the file is stamped on its own and covers ncc.csv beside it); with
  the interface kind (``--patches``) also ``interface``, ``best_overall``, ``grid_size`` and
  ``exact`` (select_models);
- ``fig7_ncc_map.png`` (NCC of the force over selection x modes, seed fig. 7) and
  ``fig8_ncc_modes.png`` (NCC against modes per selection, seed fig. 8).

A-priori estimate (studies/estimate.py ``estimate_selection``; the interface kind's:
``estimate_interface``, rule in that module), without any FE time integration:

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

The estimate is checked against a brute-force grid in tests/test_studies.py: it reaches the
grid's median NCC and is no larger than the brute-force winner there (the tiny case's numbers:
docs/notes/2026-11-27-comment-measurements.md).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from flexmvm.errors import SolverError, announce_recompute
from flexmvm.metrics.ncc import Comparison, Target
from flexmvm.results.outdir import claim_study_dir
from flexmvm.runs.guard import invalid_reason
from flexmvm.scenarios import ModelKind, Scenario, load_scenario, scenario_from_dict
from flexmvm.studies.batches import Batches
from flexmvm.studies.grid import (
    SEED_SCHEME_NOTE,
    check_grid,
    mvm_scenario,
    redistributing_contacts,
    rod_of,
    seed_scheme,
    study_kind,
    study_scenario,
)
from flexmvm.studies.interface import (
    failed_interface_row,
    patch_place,
    run_interface_case,
)
from flexmvm.studies.node_grid import NodeGrid
from flexmvm.studies.options import BasisSpec, StudyOptions, split_settings, with_settings
from flexmvm.studies.reference_run import (
    case_reference,
    reference_history,
    scored_row,
    study_provenance,
    study_version,
)
from flexmvm.studies.region_families import (
    RegionGrid,
    failed_region_row,
    run_region_case,
)
from flexmvm.studies.report import echo_summary
from flexmvm.studies.runner import Case, check_study_cluster, cluster_slots, study_cluster
from flexmvm.studies.search import Candidate, brute_force, smallest_passing
from flexmvm.studies.selection_candidates import candidate_cases, study_grid
from flexmvm.studies.selection_files import write_selection_files
from flexmvm.studies.selection_summary import Sweep, selection_summary

__all__ = [
    "FAIL_SCORE",
    "SelectionStudy",
    "run_selection_case",
    "run_selection_study",
    "run_study_case",
    "score",
    "select_models",
]

#: Families a --search keeps open per case the cluster runs at once (search.smallest_passing's
#: max_open = this x cluster_slots). All families at once spends runs on families that a
#: passing candidate of a cheaper family closes a round later; one per slot leaves workers
#: idle in the rounds where a family closes (replays of the seed study's table:
#: docs/notes/2026-11-27-comment-measurements.md).
SEARCH_OPEN_PER_SLOT = 2

#: Score of a run that failed or misses a non-NCC bound of the target (below any NCC).
FAIL_SCORE = -2.0
_METRICS = ("ncc_force", "peak_err", "impulse_err", "duration_err")

#: What a selection study writes in its directory (a study without the marker is accepted
#: only if it holds nothing else: results.outdir.claim_study_dir).
STUDY_FILES = frozenset(
    {
        "cases",
        "reference",
        "ncc.csv",
        "selection.json",
        "selection_search.json",
        "fig7_ncc_map.png",
        "fig8_ncc_modes.png",
        "ncc_interface.csv",
        "fig_front_ncc_dof.png",
    }
)


def run_selection_case(case: Case, reference: str | Path | None = None) -> dict:
    """One MVM run of a selection study against the stored reference history ``reference``
    (default: ``case.params["reference"]``), module doc.

    Returns {layers, laps, nodes, modes, dof, dof_total, ncc_force, ncc_<probe>..., peak_err,
    impulse_err, duration_err, wall_time_s}; a run whose solver fails returns the grid fields
    with ``failed`` (one line) instead of the metrics.
    """
    from flexmvm.runs.run import run_scenario

    p = case.params
    sc = scenario_from_dict(p["scenario"], source=f"case {case.key}")
    body, i, j, m = p["body"], int(p["layers"]), int(p["laps"]), int(p["modes"])
    t_ref, f_ref, probes_ref = case_reference(case, reference)
    nodes = len(rod_of(sc, body).selection(i, j))
    row: dict[str, Any] = {
        "layers": i,
        "laps": j,
        "nodes": nodes,
        "modes": m,
        "dof": 3 * nodes + m,
        "dof_total": 3 * nodes + m + 6,
    }
    from flexmvm.assembly.build_cache import default_setup

    setup = default_setup().with_mode_floor(int(p.get("modes_max", m)))
    try:
        run = run_scenario(
            mvm_scenario(sc, body, i, j, m, ModelKind(p.get("kind", "mvm"))),
            warn=False,
            setup=setup,
        )
    except SolverError as exc:
        return row | {"failed": str(exc).splitlines()[0]}
    info = next(b for b in run.built.info if b.name == body)
    assert info.dof - 6 == 3 * info.n_retained_nodes + info.n_modes == row["dof"], info
    return scored_row(row, run, body, t_ref, f_ref, probes_ref)


def score(row: dict, target: Target) -> float:
    """NCC of the force if the row meets the target's error bounds, else FAIL_SCORE; so that
    ``score >= target.ncc_min`` is ``target.met_by(...)``. A run outside its model's validity
    (runs.guard.invalid_reason: contact on surface nodes the basis holds stiff, or an
    energy rise, chatter) scores FAIL_SCORE whatever its NCC: a study never picks it."""
    if any(k not in row for k in _METRICS) or invalid_reason(row) is not None:
        return FAIL_SCORE
    c = Comparison(row["ncc_force"], row["peak_err"], row["impulse_err"], row["duration_err"])
    if not target.met_by(Comparison(1.0, c.peak_err, c.impulse_err, c.duration_err)):
        return FAIL_SCORE
    return float(c.ncc)


@dataclass(frozen=True)
class SelectionStudy:
    """The outcome of a selection study: ``rows`` (one per evaluated case, ncc.csv's columns,
    sorted by layers, laps, modes), ``summary`` (selection.json's content: the winner, run
    counts, target, grid, failures) and ``probes`` (the probe names of the NCC columns)."""

    rows: list[dict]
    summary: dict
    probes: list[str]
    interface_rows: tuple[dict, ...] = ()  # the interface cases evaluated (interface.py)

    @property
    def best(self) -> dict | None:
        """The smallest-DOF row reaching the target (None if none does)."""
        if not self.summary["passed"]:
            return None
        fields = ("region", "modes") if "region" in self.summary else ("layers", "laps", "modes")
        key = tuple(self.summary[k] for k in fields)
        return next(r for r in self.rows if tuple(r[k] for k in fields) == key)


def select_models(
    sc: Scenario,
    body: str,
    out_dir: str | Path,
    basis: BasisSpec | None = None,
    target: Target | None = None,
    search: bool = False,
    options: StudyOptions | None = None,
    **settings: Any,
) -> SelectionStudy:
    """The selection study of ``body`` in scenario ``sc`` (module doc), its cases and reference
    stored in ``out_dir`` (a rerun resumes); no table, figure or console output (see
    :func:`run_selection_study`).

    Brute force runs every case of the grid (one batch); ``search=True`` runs
    studies.search.smallest_passing with SEARCH_OPEN_PER_SLOT families open per case the
    cluster runs at once, each round's batch through run_cases (parallel, resumable).
    ``basis`` (:class:`~flexmvm.studies.options.BasisSpec`): the candidates; ``options``
    (:class:`~flexmvm.studies.options.StudyOptions`): where they run; their fields are also
    accepted as keyword arguments (``settings``), replacing the objects' own.
    ``echo``: the console lines (none by default); a stored reference or case that fails its
    check is recomputed and said through it (default: errors.announce_recompute, a warning).
    ``scheduler``: address of a Dask scheduler; otherwise one LocalCluster of ``n_workers``
    processes for the whole study, or in-process with ``serial=True``. ``kind``:
    the candidates' model (grid.study_kind: mvm, the default, mvm-seed or mvm-seed-fixed).
    ``patches`` (patch-radius sets [m]) adds the interface kind's grid patches x
    ``interface_modes`` (studies/interface.py) beside the node selections, in the same brute
    force or the same search (each patch set a family); then ``summary["interface"]`` is that
    kind's answer (runs, ``grid_size``, ``exact``), ``summary["best_overall"]`` the winner over
    both kinds (search.rank_key), and ``summary["grid_size"]`` / ``summary["exact"]`` the node
    kind's (``exact`` false: ``--search`` stopped that kind at best_overall's DOF, see
    ``exact_note`` and search.kind_exact).
    ``regions`` (studies/region_families.py: ball radii about ``centre_m`` or node sets) replaces the
    i-j grid by region families x ``modes``, for a body of any mesh (``layers`` and ``laps``
    are then ignored; rows carry ``region``, ``nodes``, ``modes``); ``patch_surface``: the
    facet set of the interface kind's patches (default: a mesh body's contact surface, about
    the regions' centre; a rod's end_a).
    Raises InputError for a bad body / grid / options, SolverError if the reference fails.
    Failed runs are listed in ``summary["failures"]``; they count as not reaching the target.
    """
    run_kw, basis_kw = split_settings(settings, "select_models")
    opts = with_settings(options, StudyOptions(), run_kw, "select_models")
    spec = with_settings(basis, BasisSpec(), basis_kw, "select_models")
    target = Target(0.99) if target is None else target
    out = Path(out_dir).resolve()
    sc.body(body)
    sc = seed_scheme(sc, body)
    kind = study_kind(spec.kind)
    grid = study_grid(
        sc, body, spec.layers, spec.laps, spec.modes, kind, spec.regions, spec.centre_m
    )
    patches, interface_modes = spec.patches, spec.interface_modes
    where = patch_place(sc, body, spec.patch_surface, grid.centre) if patches else {}
    check_study_cluster(opts.scheduler, opts.n_workers, opts.serial)  # before the reference
    claim_study_dir(out, "flexmvm select", own=STUDY_FILES)
    echo = opts.echo
    announce, echo = (announce_recompute, _silent) if echo is None else (echo, echo)
    progress = opts.progress
    hist, ref_made = _reference(sc, body, out, progress, announce, echo)
    case_of, if_cases = candidate_cases(sc, body, grid, hist, patches, interface_modes, where, echo)
    cluster = (opts.scheduler, opts.n_workers, opts.serial)
    sweep = _run_candidates(
        sc, case_of, target, search, cluster, progress, out, hist, grid, announce
    )
    report = selection_summary(
        grid,
        sweep,
        body=body,
        kind=kind,
        search=search,
        target=target,
        ref_made=ref_made,
        if_cases=if_cases,
        patches=patches,
        interface_modes=interface_modes,
    )
    summary = report.summary | {"provenance": study_provenance(sc, body, out)}
    return SelectionStudy(report.table, summary, [p.name for p in sc.probes], report.interface_rows)


def _silent(_line: str) -> None:
    """The console of a study without console lines."""


def _reference(sc, body, out, progress, announce, echo) -> tuple[Path, bool]:
    """The reference step: the full-FE history of ``body`` in ``out`` (computed, or loaded
    when stored and valid: studies.reference_run.reference_history) and its console line.
    Returns (its path, whether it was computed)."""
    hist, ref_made = reference_history(sc, body, out, progress=progress, announce=announce)
    echo(f"reference (full FE {body}): {'computed' if ref_made else 'loaded'} {hist}")
    return hist, ref_made


def _run_candidates(sc, case_of, target, search, cluster, progress, out, hist, grid, announce):
    """Every candidate's case (brute force) or the search's (:func:`_sweep`) run against the
    reference history ``hist`` of scenario sc on one cluster (``cluster`` = (scheduler,
    n_workers, serial), as studies.runner.study_cluster), stored in ``out``. Returns the
    Sweep: the rows, run counts, cases, winner (or None) and scores."""
    scheduler, n_workers, serial = cluster
    with study_cluster(scheduler, n_workers, serial) as address:
        batches = Batches(
            out,
            address,
            serial,
            progress,
            functools.partial(run_study_case, reference=str(hist)),
            lambda c, line: _failed_row(c, line, grid),
            study_version(sc, hist),
            announce,
        )
        best, scores = _sweep(
            case_of, batches, target, search, lambda: cluster_slots(scheduler, n_workers, serial)
        )
    return Sweep(batches.rows, batches.made, batches.loaded, case_of, best, scores)


def _sweep(
    case_of: dict[Candidate, Case],
    batches: Batches,
    target: Target,
    search: bool,
    slots: Callable[[], int],
) -> tuple[Candidate | None, dict[Candidate, float]]:
    """The dispatch step: every candidate (brute force, one batch) or the pruned search's
    (``search``: SEARCH_OPEN_PER_SLOT families open per one of the cluster's ``slots()``),
    scored against ``target``; returns the winner over both kinds and the scores."""

    def evaluate(batch: Sequence[Candidate]) -> list[float]:
        rows = batches([case_of[c] for c in batch])
        return [score(r, target) for r in rows]

    def passes(s: float) -> bool:
        return s >= target.ncc_min

    if search:
        return smallest_passing(
            list(case_of), evaluate, passes, max_open=SEARCH_OPEN_PER_SLOT * slots()
        )
    return brute_force(list(case_of), evaluate, passes)


def run_study_case(case: Case, reference: str | Path | None = None) -> dict:
    """One run of a selection study, of any kind: the interface kind's (params ``kind``
    "interface", studies/interface.py), a region family's (params ``region``,
    studies/region_families.py) or a node selection's (:func:`run_selection_case`)."""
    if case.params.get("kind") == "interface":
        return run_interface_case(case, reference=reference)
    if "region" in case.params:
        return run_region_case(case, reference=reference)
    return run_selection_case(case, reference=reference)


def _failed_row(case: Case, line: str, grid: NodeGrid | RegionGrid) -> dict:
    """ncc.csv's row of a case of any kind that raised (``line``: the one-line reason)."""
    if case.params.get("kind") == "interface":
        return failed_interface_row(case, line)
    if "region" in case.params:
        return failed_region_row(case, line)
    assert isinstance(grid, NodeGrid), grid
    return grid.failed_row(case, line)


#: run_selection_study's options when none are given: progress bars, console lines printed.
_COMMAND = StudyOptions(progress=True, echo=print)


def run_selection_study(
    scenario: str | Path | Scenario,
    body: str,
    out_dir: str | Path,
    basis: BasisSpec | None = None,
    target: Target | None = None,
    search: bool = False,
    options: StudyOptions | None = None,
    **settings: Any,
) -> dict:
    """The selection study of ``body`` in ``scenario`` (a Scenario or a scenario file) with
    its files and console lines (module doc): :func:`select_models` (``basis``, ``options``
    and ``settings`` as there; here progress bars and console lines on by default: echo
    print), then ncc.csv, selection.json, the two figures and the summary line. ``t_end_s``,
    ``dt_s`` (fields of ``options``) override the
    scenario's end time and contact step, ``other`` the model of the other bodies
    (grid.study_scenario). With ``regions`` (region families of any body, studies/region_families.py)
    ncc.csv has a row per region x modes and the figure is fig_front_ncc_dof.png (force NCC
    against DOF per region family, and the interface kind's with ``patches``). Returns the
    selection.json content.

    Raises InputError for a bad body / grid / options, SolverError if the reference fails or,
    after everything is written, if every run failed.
    """
    run_kw, basis_kw = split_settings(settings, "run_selection_study")
    opts = with_settings(options, _COMMAND, run_kw, "run_selection_study")
    spec = with_settings(basis, BasisSpec(), basis_kw, "run_selection_study")
    echo = print if opts.echo is None else opts.echo
    opts = dataclasses.replace(opts, echo=echo)
    target = Target(0.99) if target is None else target
    out = Path(out_dir).resolve()
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    switched = bool(redistributing_contacts(sc, body))
    sc = study_scenario(sc, body, t_end_s=opts.t_end_s, dt_s=opts.dt_s, other=opts.other)
    if not spec.regions:
        check_grid(sc, body, spec.layers, spec.laps, spec.modes)
    if switched:
        echo(SEED_SCHEME_NOTE)
    study = select_models(sc, body, out, spec, target, search, opts)
    result = study.summary
    write_selection_files(out, study, sc.name, body, target, bool(spec.regions))
    echo_summary(echo, result, target, out / "selection.json")
    failures = result["failures"] + result.get("interface", {}).get("failures", [])
    if failures and len(failures) == result["runs"] + result.get("interface", {}).get("runs", 0):
        first = failures[0]
        raise SolverError(
            f"selection study: every run failed ({first['case']}: "
            f"{first['reason']}); see {out / 'selection.json'}"
        )
    return result
