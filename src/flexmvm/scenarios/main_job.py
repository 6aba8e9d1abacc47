"""The main job: run a scenario (and a full-FE reference), compare, write, plot.

The scenario's own run and the full-FE reference are independent single-threaded simulations:
with jobs = 2 they run side by side in two processes (one per core), each writing its own
files, so the job takes about as long as the longer of the two instead of their sum.
"""

from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from flexmvm.errors import InputError
from flexmvm.results.output import write_run
from flexmvm.results.writers import write_summary_json
from flexmvm.scenarios.compare import compare_runs, run_curves
from flexmvm.scenarios.run import run_scenario
from flexmvm.scenarios.schema import load_scenario


def _theory(sc):
    from flexmvm.theory.scenario import theory_histories

    try:
        t, f, probes, info = theory_histories(sc)
    except InputError:
        return None
    return t, f, probes, info


def _run_and_write(sc, label: str, out_dir: Path, fields: bool, progress: bool):
    """Run sc, write its files into out_dir; returns (summary, curves, n_steps, wall [s])."""
    run = run_scenario(sc, label=label, progress=progress)
    write_run(out_dir, run, fields=fields)
    return run.summary, run_curves(run.result), run.result.n_steps, run.result.wall_time_s


def run_main_job(path: Path, out_dir: Path, *, model=None, t_end=None, dt=None, fields=True,
                 progress=True, echo=print, jobs: int = 2) -> dict:
    """Run `path`; with no model also a full-FE reference (jobs = 2: in a second process, at
    the same time); returns the top-level summary."""
    out_dir = Path(out_dir)
    sc = load_scenario(path)
    sc = sc.with_overrides(model=model, t_end_s=t_end, dt_s=dt)
    needs_ref = model is None and any(b.model.kind.value not in ("full", "rigid") for b in sc.bodies)
    ref_sc = sc.with_overrides(model="full") if needs_ref else None
    own_label = model or "scenario"
    if needs_ref and jobs > 1:
        ctx = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=2, mp_context=ctx) as pool:
            ref_future = pool.submit(_run_and_write, ref_sc, "full", out_dir / "full", fields,
                                     progress)
            own_future = pool.submit(_run_and_write, sc, own_label, out_dir, fields, False)
            own, ref = own_future.result(), ref_future.result()
    else:
        own = _run_and_write(sc, own_label, out_dir, fields, progress)
        ref = (_run_and_write(ref_sc, "full", out_dir / "full", fields, progress)
               if needs_ref else None)
    own_summary, own_curves, n_own, wall_own = own
    echo(f"{own_label}: {n_own} steps in {wall_own:.1f} s")
    summary = dict(own_summary)
    curves = {_label(own_summary): own_curves}
    theory = _theory(sc)
    if theory is not None:
        summary["comparison_vs_theory"] = compare_runs(theory[0], theory[1], theory[2],
                                                       *own_curves)
        summary["theory_law"] = theory[3]["law"]
    if ref is not None:
        ref_summary, ref_curves, n_ref, wall_ref = ref
        echo(f"full FE: {n_ref} steps in {wall_ref:.1f} s")
        summary["reference_full"] = ref_summary
        summary["comparison_vs_full"] = compare_runs(*ref_curves, *own_curves)
        summary["speedup_vs_full"] = wall_ref / max(wall_own, 1e-12)
        curves = {"FE": ref_curves, **curves}
    write_summary_json(out_dir / "summary.json", summary)
    th = (theory[0], theory[1], theory[2]) if theory is not None else None
    from flexmvm.plots.figures import plot_run  # matplotlib: 2 s of import, only here

    plot_run(out_dir / f"{sc.name}.png", curves, theory=th,
             title=f"{sc.name}: contact force and axial velocities")
    return summary


def _label(summary: dict) -> str:
    kinds = set(summary["model"].values())
    if kinds <= {"full", "rigid"}:
        return "FE"
    return "MVM" if "mvm" in kinds or "mvm-seed" in kinds else "/".join(sorted(kinds))
