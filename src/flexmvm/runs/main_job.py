"""The main job: run a scenario (and a full-FE reference), compare, write, plot.

The scenario's own run and the full-FE reference are independent single-threaded simulations:
with jobs = 2 they run side by side in two processes (one per core), each writing its own
files, so the job takes about as long as the longer of the two instead of their sum.

Everything is written into a temporary sibling ``DIR.partial-<pid>`` that becomes ``DIR``
only when the job has finished (flexmvm.results.outdir.staged_dir). A run that stops before
its end time (a step that does not converge at the smallest step) keeps what it computed:
its history, fields and summary (``status = "failed"``, the reason in ``failure``) become
``DIR`` and the job exits non-zero. A full-FE reference that fails does not hide the
scenario's own run: that run is waited for and written (its summary's ``failures`` names the
reference and why), then the job exits non-zero naming the reference; when both fail, the
error names both. Any other failure leaves ``DIR`` as it was.

Nothing is dropped quietly: a comparison that cannot be made (a
theory that does not apply to the scenario, a probe or force that cannot be compared) is
listed in ``summary["failures"]`` as ``{"item", "reason"}`` and echoed. (A run with
``--model``, or of full-FE/rigid bodies only, has no full-FE reference by design: not listed.)
"""

from __future__ import annotations

import contextlib
import logging
import multiprocessing
import os
import sys
from concurrent.futures import FIRST_EXCEPTION, ProcessPoolExecutor, wait
from pathlib import Path

from flexmvm.assembly.build_cache import SETUP_LOG
from flexmvm.bodies.build import ModelKind
from flexmvm.errors import (
    FlexmvmError,
    InputError,
    SimulationFailed,
    SolverError,
    notes_as_lines,
)
from flexmvm.processes import die_with_parent
from flexmvm.reduction.truncation import truncation_warnings
from flexmvm.results.outdir import staged_dir
from flexmvm.results.output import write_run, write_summary, writing
from flexmvm.runs.compare import compare_runs
from flexmvm.runs.guard import guard_warnings
from flexmvm.runs.plastic_summary import plastic_guard_warnings
from flexmvm.runs.run import energy_gain_warning, run_scenario
from flexmvm.runs.showcases import pendulum
from flexmvm.scenarios.load import load_scenario
from flexmvm.scenarios.schema import Scenario


def _theory(sc, failures: list[dict]):
    from flexmvm.theory.scenario import theory_histories

    try:
        t, f, probes, info = theory_histories(sc)
    except InputError as exc:
        failures.append({"item": "comparison_vs_theory", "reason": f"no theory applies: {exc}"})
        return None
    return t, f, probes, info


def _comparison_failures(name: str, comparison: dict) -> list[dict]:
    """The entries of compare_runs that could not be computed (keys ending in _error)."""
    return [
        {"item": f"{name}.{key[: -len('_error')]}", "reason": str(value)}
        for key, value in comparison.items()
        if key.endswith("_error")
    ]


def _labelled(label: str, exc: BaseException, ref_exc: BaseException | None = None):
    """A FlexmvmError of the same class naming the run that failed (and the full-FE
    reference's failure too, ``ref_exc``, when both failed); others unchanged."""
    if isinstance(exc, FlexmvmError):
        also = f"; the {_REF_WHAT} failed too: {ref_exc}" if ref_exc is not None else ""
        try:
            new = type(exc)(f"{label}: {exc}{also}")
        except Exception:  # noqa: BLE001 - a subclass with another signature: keep it
            return exc
        new.__cause__ = exc
        return new
    return exc


class RunStopped(SolverError):
    """A run that stopped before its end time, its histories up to there written (summary
    status "failed"): the job writes what it has and exits non-zero."""


@contextlib.contextmanager
def _stages_printed(label: str, enabled: bool):
    """With progress on, the set-up's stages (assembly.build_cache.SETUP_LOG: mesh, assembly,
    basis, invariants, factorizations) printed to stderr as they happen, one line each
    ("flexmvm: <run>: basis mvm built (...): 12.3 s"), in this process or the reference's."""
    if not enabled:
        yield
        return
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter(f"flexmvm: {label}: %(message)s"))
    SETUP_LOG.addHandler(handler)
    level = SETUP_LOG.level
    SETUP_LOG.setLevel(logging.INFO)
    try:
        yield
    finally:
        SETUP_LOG.removeHandler(handler)
        SETUP_LOG.setLevel(level)


def _run_and_write(sc, label: str, out_dir: Path, fields: bool, progress: bool):
    """Run sc, write its files into out_dir; returns (summary, curves, n_steps, wall [s]).
    A run that stops early (SimulationFailed) writes what it computed, then raises
    RunStopped."""
    try:
        with _stages_printed(label, progress):
            run = run_scenario(sc, label=label, progress=progress, warn=False)
    except SimulationFailed as exc:
        if exc.partial is None:
            raise
        write_run(out_dir, exc.partial, fields=fields)
        raise RunStopped(
            f"{exc} (histories up to t = {exc.partial.result.t[-1]:.6g} s "
            "written, summary status 'failed')"
        ) from None
    write_run(out_dir, run, fields=fields)
    if "pendulum" in run.summary:  # runs.run.summarize: a pendulum release
        with writing(out_dir / f"{sc.name}_event.png"):
            _plot_event(out_dir / f"{sc.name}_event.png", run, f"{sc.name} ({label})")
    return run.summary, run.result.curves(), run.result.n_steps, run.result.wall_time_s


def _plot_event(path: Path, run, title: str) -> None:
    """The whole event of a pendulum run: string angles, gap, force with a zoomed inset."""
    from flexmvm.plots.pendulum import plot_event  # matplotlib: imported only here

    ev = pendulum.event_histories(run.built, run.result)
    plot_event(
        path,
        ev["t_s"],
        ev["angle_rad"],
        ev["gap_m"],
        ev["force_N"],
        ev["contact_intervals_s"],
        title=title,
    )


def run_main_job(
    scenario: Path | str | Scenario,
    out_dir: Path,
    *,
    model=None,
    t_end=None,
    dt=None,
    fields=True,
    progress=True,
    echo=print,
    jobs: int = 2,
    reference: bool | None = None,
    theory: bool | None = None,
) -> dict:
    """Run ``scenario`` (a Scenario or a scenario file) as written and write its files into
    out_dir; returns the top-level summary. A full-FE reference of its reduced bodies (jobs =
    2: in a second process, at the same time) and the theory (flexmvm.theory.scenario: two
    rods, or a sphere on a beam) run where the scenario's ``[compare]`` asks for them, or
    where ``reference`` / ``theory`` say so (None: the scenario decides). ``model`` (a
    ModelKind or its value) sets every non-rigid body's kind (and then no reference runs),
    ``t_end``, ``dt`` [s] the end time and contact step."""
    out_dir = Path(out_dir)
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    sc = sc.with_overrides(model=model, t_end_s=t_end, dt_s=dt)
    want_ref = sc.compare.full_reference if reference is None else reference
    want_theory = sc.compare.theory if theory is None else theory
    needs_ref = want_ref and model is None and any(b.model.kind.reduced for b in sc.bodies)
    ref_sc = sc.with_kind(ModelKind.FULL) if needs_ref else None
    own_label = ModelKind(model).value if model is not None else "scenario"
    stopped = ref_exc = None
    with staged_dir(out_dir, "flexmvm run", echo=echo) as tmp:
        try:
            summary, ref_exc = _run_into(
                tmp, sc, ref_sc, own_label, fields, progress, echo, jobs, want_theory
            )
        except RunStopped as exc:  # what was computed is kept: DIR gets it, marked failed
            stopped = exc
    if stopped is not None:
        raise SolverError(f"{stopped}; in {out_dir}") from stopped
    if ref_exc is not None:  # the scenario's own run, compared with the theory, is written
        raise SolverError(
            f"{_REF_WHAT}: {_one_line(ref_exc)}; the {own_label} run is written in {out_dir} "
            "(summary.json failures names the reference)"
        ) from ref_exc
    for line in guard_warnings(summary.get("reduced_contact_guard") or {}):
        echo(f"warning: {line}")
    for line in plastic_guard_warnings(summary):  # a reduced plastic body's zone left its region
        echo(f"warning: {line}")
    for line in truncation_warnings(summary.get("modal_truncation_guard") or {}):
        echo(f"warning: {line}")
    gain = energy_gain_warning(summary)
    if gain is not None:
        echo(f"warning: {gain}")
    failures = summary["failures"]
    if failures:
        echo(
            f"not compared ({len(failures)}): "
            + "; ".join(f"{f['item']}: {f['reason']}" for f in failures)
        )
    return summary


def _worker_init(parent_pid: int) -> None:
    """A pool worker: it dies with the job (processes.die_with_parent) and prints its
    notes as one line each (errors.notes_as_lines)."""
    die_with_parent(parent_pid)
    notes_as_lines()


@contextlib.contextmanager
def _stopped_on_exit(pool: ProcessPoolExecutor):
    """Terminate the pool's workers when the block is left by an exception (Ctrl-C, SIGTERM,
    a failed run), instead of the pool's exit waiting for their runs to end."""
    try:
        yield
    except BaseException:
        _stop_workers(pool)
        raise


def _stop_workers(pool: ProcessPoolExecutor) -> None:
    """Terminate the pool's worker processes (the still-running run of a failed job)."""
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        with contextlib.suppress(Exception):
            proc.terminate()


_REF_WHAT = "full-FE reference"  # the reference run, as failures name it


def _one_line(exc: BaseException) -> str:
    """An exception as the CLI would show it: a FlexmvmError's message, else its type too."""
    text = " ".join(str(exc).split())
    return text if isinstance(exc, FlexmvmError) else f"{type(exc).__name__}: {text}"


def _run_into(
    out_dir: Path,
    sc,
    ref_sc,
    own_label: str,
    fields: bool,
    progress: bool,
    echo,
    jobs: int,
    want_theory: bool = True,
) -> tuple[dict, BaseException | None]:
    """The job proper, writing into out_dir (the staging directory). Returns (summary, the
    full-FE reference's exception or None): a failed reference is listed in the summary's
    failures and does not stop the scenario's own run from being written."""
    failures: list[dict] = []
    runs = (out_dir, sc, ref_sc, own_label, fields, progress, want_theory, failures)
    if ref_sc is not None and jobs > 1:
        own, ref, theory, ref_exc = _runs_side_by_side(*runs)
    else:
        own, ref, theory, ref_exc = _runs_one_after_other(*runs)
    if ref_exc is not None:
        failures.append({"item": "reference_full", "reason": f"failed: {_one_line(ref_exc)}"})
    own_summary, own_curves, n_own, wall_own = own
    echo(f"{own_label}: {n_own} steps in {wall_own:.1f} s")
    summary = dict(own_summary)
    curves = {_label(own_summary): own_curves}
    if theory is not None:
        summary["comparison_vs_theory"] = compare_runs(theory[0], theory[1], theory[2], *own_curves)
        summary["theory_law"] = theory[3]["law"]
        failures += _comparison_failures("comparison_vs_theory", summary["comparison_vs_theory"])
    if ref is not None:
        ref_summary, ref_curves, n_ref, wall_ref = ref
        echo(f"full FE: {n_ref} steps in {wall_ref:.1f} s")
        summary["reference_full"] = ref_summary
        summary["comparison_vs_full"] = compare_runs(*ref_curves, *own_curves)
        failures += _comparison_failures("comparison_vs_full", summary["comparison_vs_full"])
        summary["speedup_vs_full"] = wall_ref / max(wall_own, 1e-12)
        curves = {"FE": ref_curves, **curves}
    summary["failures"] = failures
    bad = write_summary(out_dir / "summary.json", summary)
    if bad:
        echo(f"warning: non-finite values written as null in summary.json: {', '.join(bad)}")
    th = (theory[0], theory[1], theory[2]) if theory is not None else None
    from flexmvm.plots.figures import plot_run  # matplotlib: 2 s of import, only here

    with writing(out_dir / f"{sc.name}.png"):
        plot_run(
            out_dir / f"{sc.name}.png",
            curves,
            theory=th,
            title=f"{sc.name}: contact force and axial velocities",
        )
    return summary, ref_exc


def _runs_side_by_side(out_dir, sc, ref_sc, own_label, fields, progress, want_theory, failures):
    """The run of sc and the full-FE reference ref_sc in two worker processes, the theory
    (into failures, if want_theory) meanwhile. Returns (own, ref or None, theory, the
    reference's exception or None): a failed reference does not stop the scenario's own run,
    which is waited for; a failed own run stops the reference and is raised, labelled (naming
    the reference's failure too if it failed first)."""
    ctx = multiprocessing.get_context("spawn")
    with (
        ProcessPoolExecutor(
            max_workers=2, mp_context=ctx, initializer=_worker_init, initargs=(os.getpid(),)
        ) as pool,
        _stopped_on_exit(pool),
    ):
        ref_future = pool.submit(_run_and_write, ref_sc, "full", out_dir / "full", fields, progress)
        own_future = pool.submit(_run_and_write, sc, own_label, out_dir, fields, False)
        # while the two runs go: the theory and the figure module (matplotlib: ~1 s)
        theory = _theory(sc, failures) if want_theory else None
        import flexmvm.plots.figures  # noqa: F401

        wait([own_future, ref_future], return_when=FIRST_EXCEPTION)
        ref_exc = ref_future.exception() if ref_future.done() else None
        if not (own_future.done() and own_future.exception() is not None):
            wait([own_future])  # the reference failed or both are done: the own run ends
        own_exc = own_future.exception()
        if own_exc is not None:
            if not ref_future.done():
                _stop_workers(pool)  # the job has failed: do not wait for the reference
            raise _labelled(f"{own_label} run", own_exc, ref_exc) from own_exc
        ref = None if ref_exc is not None else ref_future.result()
        return own_future.result(), ref, theory, ref_exc


def _runs_one_after_other(out_dir, sc, ref_sc, own_label, fields, progress, want_theory, failures):
    """The run of sc, then the full-FE reference ref_sc (if any), then the theory (into
    failures, if want_theory), in this process. Returns (own, ref or None, theory or None,
    the reference's exception or None); a failed own run is raised, labelled."""
    try:
        own = _run_and_write(sc, own_label, out_dir, fields, progress)
    except Exception as exc:
        raise _labelled(f"{own_label} run", exc) from exc
    ref = ref_exc = None
    try:
        if ref_sc is not None:
            ref = _run_and_write(ref_sc, "full", out_dir / "full", fields, progress)
    except Exception as exc:  # noqa: BLE001 - listed in failures, raised after the write
        ref_exc = exc
    theory = _theory(sc, failures) if want_theory else None
    return own, ref, theory, ref_exc


def _label(summary: dict) -> str:
    kinds = {ModelKind(k) for k in summary["model"].values()}
    if not any(k.reduced for k in kinds):
        return "FE"
    if any(k.retains_nodes for k in kinds):
        return "MVM"
    return "/".join(sorted(k.value for k in kinds))
