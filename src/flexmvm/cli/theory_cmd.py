"""`flexmvm theory SCENARIO --out DIR`: the scenario's theory (1D waves of two rods, or a
Timoshenko beam + Hertz for a sphere on a beam) in the run's history format."""

from __future__ import annotations

from pathlib import Path

import click


@click.command("theory")
@click.argument("scenario", type=click.Path(dir_okay=False, path_type=Path))
@click.option(
    "--out",
    "out_dir",
    required=True,
    type=click.Path(file_okay=False, path_type=Path),
    help="Output directory (history.csv is written there; an earlier theory output "
    "there is replaced at the end).",
)
@click.option("--dt", type=float, default=None, help="Grid step of the solution [s].")
def command(scenario: Path, out_dir: Path, dt: float | None) -> None:
    """1D wave solution of a two-rod scenario: St Venant (flat end) or wave + Hertz
    (hemisphere); for a sphere on a beam, a Timoshenko beam with a Hertz spring.

    Written into a temporary DIR.partial-<pid> renamed to DIR at the end: a failure leaves DIR
    as it was. An existing DIR is replaced, if it is empty or an earlier theory output."""
    from flexmvm.results.history import write_history
    from flexmvm.results.outdir import check_creatable, staged_dir
    from flexmvm.scenarios import load_scenario
    from flexmvm.theory.scenario import theory_histories

    check_creatable(out_dir)
    sc = load_scenario(scenario)
    with staged_dir(out_dir, "flexmvm theory", echo=click.echo) as tmp:
        t, force, probes, info = theory_histories(sc, dt=dt)
        write_history(tmp / "history.csv", t, force, probes)
    path = out_dir / "history.csv"
    click.echo(
        f"theory ({info['law']}, v0 = {info['v0_mps']:.4g} m/s): peak force "
        f"{force.max():.2f} N; wrote {path}"
    )
