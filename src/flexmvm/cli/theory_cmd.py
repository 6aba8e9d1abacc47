"""`flexmvm theory SCENARIO --out DIR`: the 1D wave solution in the run's history format."""

from __future__ import annotations

from pathlib import Path

import click


@click.command("theory")
@click.argument("scenario", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False, path_type=Path),
              help="Output directory (history.csv is written there).")
@click.option("--dt", type=float, default=None, help="Grid step of the 1D solution [s].")
def command(scenario: Path, out_dir: Path, dt: float | None) -> None:
    """1D wave solution of a two-rod scenario: St Venant (flat end) or wave + Hertz (hemisphere)."""
    from flexmvm.results.history import write_history
    from flexmvm.scenarios.schema import load_scenario
    from flexmvm.theory.scenario import theory_histories

    sc = load_scenario(scenario)
    t, force, probes, info = theory_histories(sc, dt=dt)
    out_dir.mkdir(parents=True, exist_ok=True)
    path = write_history(out_dir / "history.csv", t, force, probes)
    click.echo(f"theory ({info['law']}, v0 = {info['v0_mps']:.4g} m/s): peak force "
               f"{force.max():.2f} N; wrote {path}")
