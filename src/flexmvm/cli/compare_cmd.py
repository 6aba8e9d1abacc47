"""`flexmvm compare RUN REFERENCE`: two written runs (folders of `flexmvm run --out`) compared as
fm.compare compares them: force NCC over the contact window, peak, impulse and duration
errors, NCC of every probe both have."""

from __future__ import annotations

from pathlib import Path

import click


@click.command("compare")
@click.argument("run", type=click.Path(file_okay=False, exists=True, path_type=Path))
@click.argument("reference", type=click.Path(file_okay=False, exists=True, path_type=Path))
@click.option(
    "--axis",
    type=click.Choice(["x", "y", "z", "norm"]),
    default=None,
    help="The probes' velocity compared: a global component or the speed. Default: each "
    "probe's own (the scenario's probe axis, x when not given).",
)
def command(run: Path, reference: Path, axis: str | None) -> None:
    """RUN against REFERENCE, two folders written by `flexmvm run` (or fm.write_run; a
    full-FE reference is the run's full/ folder): NCC of the contact force over the contact
    window and over the whole window, relative errors (run - reference) / reference of its
    peak, impulse and contact duration, and NCC of each probe's velocity (--axis) both runs
    have.
    Comparisons that cannot be made are printed with their reason."""
    from flexmvm.runs.compare import compare
    from flexmvm.runs.written_run import read_run

    c = compare(read_run(run), read_run(reference), axis)
    shown = axis or "as each probe's axis"
    click.echo(f"{run} vs {reference} (probe velocity {shown}):")
    rows = [
        ("ncc_force", c.ncc_force, ".6f"),
        ("ncc_force_whole", c.ncc_force_whole, ".6f"),
        ("peak_err", c.peak_err, ".4%"),
        ("impulse_err", c.impulse_err, ".4%"),
        ("duration_err", c.duration_err, ".4%"),
    ] + [(f"ncc_{name}", value, ".6f") for name, value in c.ncc_probes.items()]
    for key, value, fmt in rows:
        if value is not None:
            click.echo(f"  {key} = {value:{fmt}}")
    for key, reason in c.not_compared.items():
        click.echo(f"  {key}: not compared: {reason}")
