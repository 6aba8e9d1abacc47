"""The main job: run a scenario (and a full-FE reference), compare, write, plot."""

from __future__ import annotations

from pathlib import Path

from flexmvm.errors import InputError
from flexmvm.plots.figures import plot_run
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


def run_main_job(path: Path, out_dir: Path, *, model=None, t_end=None, dt=None, fields=True,
                 progress=True, echo=print) -> dict:
    """Run `path`; with no model also a full-FE reference; returns the top-level summary."""
    out_dir = Path(out_dir)
    sc = load_scenario(path)
    sc = sc.with_overrides(model=model, t_end_s=t_end, dt_s=dt)
    own = run_scenario(sc, label=model or "scenario", progress=progress)
    echo(f"{own.label}: {own.result.n_steps} steps in {own.result.wall_time_s:.1f} s")
    write_run(out_dir, own, fields=fields)
    summary = dict(own.summary)
    curves = {_label(own.summary): run_curves(own.result)}
    theory = _theory(sc)
    if theory is not None:
        summary["comparison_vs_theory"] = compare_runs(theory[0], theory[1], theory[2],
                                                       *run_curves(own.result))
        summary["theory_law"] = theory[3]["law"]
    needs_ref = model is None and any(b.model.kind.value not in ("full", "rigid") for b in sc.bodies)
    if needs_ref:
        ref = run_scenario(sc.with_overrides(model="full"), label="full", progress=progress)
        echo(f"full FE: {ref.result.n_steps} steps in {ref.result.wall_time_s:.1f} s")
        write_run(out_dir / "full", ref, fields=fields)
        summary["reference_full"] = ref.summary
        summary["comparison_vs_full"] = compare_runs(*run_curves(ref.result), *run_curves(own.result))
        summary["speedup_vs_full"] = ref.result.wall_time_s / max(own.result.wall_time_s, 1e-12)
        curves = {"FE": run_curves(ref.result), **curves}
    write_summary_json(out_dir / "summary.json", summary)
    plot_curves = {k: (t, f, p) for k, (t, f, p) in curves.items()}
    th = (theory[0], theory[1], theory[2]) if theory is not None else None
    plot_run(out_dir / f"{sc.name}.png", plot_curves, theory=th,
             title=f"{sc.name}: contact force and axial velocities")
    return summary


def _label(summary: dict) -> str:
    kinds = set(summary["model"].values())
    if kinds <= {"full", "rigid"}:
        return "FE"
    return "MVM" if "mvm" in kinds or "mvm-seed" in kinds else "/".join(sorted(kinds))
