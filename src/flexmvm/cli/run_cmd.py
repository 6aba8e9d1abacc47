"""`flexmvm run SCENARIO --out DIR`: simulate a scenario and write its results."""

from __future__ import annotations

from pathlib import Path

import click

from flexmvm.cli.kind_choice import every_kind


@click.command("run")
@click.argument("scenario", type=click.Path(dir_okay=False, path_type=Path))
@click.option(
    "--out",
    "out_dir",
    required=True,
    type=click.Path(file_okay=False, path_type=Path),
    help="Output directory (created; an earlier run's output there is replaced at the end).",
)
@click.option(
    "--model",
    type=every_kind(),
    default=None,
    help="Model of every non-rigid body (then no full-FE reference runs). Default: "
    "the scenario's models.",
)
@click.option(
    "--reference/--no-reference",
    default=None,
    help="Also run a full-FE copy of the reduced bodies and compare (default: the "
    "scenario's [compare] full_reference; the seed scenarios ask for it).",
)
@click.option(
    "--theory/--no-theory",
    default=None,
    help="Lay the theory over the run: the 1D wave solution of a two-rod impact, or "
    "a Timoshenko beam with a Hertz spring for a sphere on a beam (default: "
    "the scenario's [compare] theory).",
)
@click.option("--t-end", "t_end", type=float, default=None, help="End time [s].")
@click.option("--dt", type=float, default=None, help="Time step near contact [s].")
@click.option("--no-fields", is_flag=True, help="Skip results.h5 and the ParaView series.")
@click.option("--progress/--no-progress", default=True, show_default=True)
@click.option(
    "--jobs",
    type=click.IntRange(1, 2),
    default=2,
    show_default=True,
    help="Processes for the scenario's run and its full-FE reference (2: side by "
    "side, one per core).",
)
def command(
    scenario, out_dir, model, reference, theory, t_end, dt, no_fields, progress, jobs
) -> None:
    """Simulate SCENARIO; write history.csv, summary.json, results.h5, ParaView series, PNG.

    Everything is written into a temporary DIR.partial-<pid> beside DIR and renamed to DIR
    at the end. A run that stops early (a step that fails even when cut) still writes what it
    computed, up to the failure, with status "failed" in summary.json, and exits with status
    2; a run interrupted or killed leaves DIR as it was. An existing DIR is replaced as a
    whole, and only if it is empty or an unchanged earlier output of `flexmvm run`. Comparisons that cannot be made are printed and listed in
    summary.json under "failures"."""
    from flexmvm.runs.main_job import run_main_job
    from flexmvm.runs.run import numerical_dissipation_line

    summary = run_main_job(
        scenario,
        out_dir,
        model=model,
        t_end=t_end,
        dt=dt,
        fields=not no_fields,
        progress=progress,
        echo=click.echo,
        jobs=jobs,
        reference=reference,
        theory=theory,
    )
    keys = (
        "max_contact_force_interval_mean_N",
        "momentum_rel_error",
        "momentum_rel_error_converged",
        "energy_rel_change",
        "max_penetration_m",
        "wall_time_s",
    )
    click.echo("  ".join(f"{k} = {summary[k]:.4g}" for k in keys if summary.get(k) is not None))
    damping = numerical_dissipation_line(summary)  # the scheme's damping, its cost
    if damping is not None:
        click.echo(damping)
    click.echo(
        "dof (6 frame + elastic): "
        + ", ".join(
            f"{name} = {dof} ({summary['model'][name]})" for name, dof in summary["dof"].items()
        )
    )
    for label, s in (("", summary), ("full FE reference: ", summary.get("reference_full") or {})):
        if s.get("steps_on_roundoff_floor"):
            click.echo(
                f"warning: {label}{s['steps_on_roundoff_floor']} step(s) stopped on the "
                f"round-off floor above the Newton tolerance (worst relative residual "
                f"{s['newton_residual_max']:.2e}; summary.json steps_on_roundoff_floor)",
                err=True,
            )
    if "comparison_vs_full" in summary:
        c = summary["comparison_vs_full"]
        click.echo(
            "vs full FE: "
            + "  ".join(f"{k} = {v:.4f}" for k, v in c.items() if isinstance(v, float))
        )
    click.echo(f"wrote {out_dir}")
