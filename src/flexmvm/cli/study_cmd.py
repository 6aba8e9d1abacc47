"""`flexmvm study materials SCENARIO --out DIR`: the material study (seed section 3.3)."""

from __future__ import annotations

from pathlib import Path

import click

from flexmvm.errors import InputError


@click.group("study")
def command() -> None:
    """Studies over many runs (Dask, resumable)."""


@command.command("materials")
@click.argument("scenario", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False, path_type=Path),
              help="Study directory (a rerun resumes).")
@click.option("--body", default="b2", show_default=True, help="The body whose material varies.")
@click.option("--materials", default="W,Cu,Al,PA6", show_default=True,
              help="Seed table 2 materials to run.")
@click.option("--selections", default="1-1,2-2", show_default=True, help="i-j selections.")
@click.option("--modes", default="7:43:12", show_default=True,
              help="Mode counts: start:stop:step, stop included.")
@click.option("--scheduler", default=None, help="Address of a Dask scheduler (tcp://host:port).")
@click.option("--workers", type=int, default=None, help="Local worker processes.")
@click.option("--serial", is_flag=True, help="Run in this process, no Dask.")
@click.option("--t-end", "t_end", type=float, default=None, help="End time [s].")
@click.option("--dt", "dt", type=float, default=None,
              help="Contact time step [s] (reference and candidates alike).")
@click.option("--other", "other", default="scenario", show_default=True,
              help="Model of the other bodies: 'scenario' (as in the file: the seed's b1 is "
                   "full FE), 'full', or 'mvm:I-J:M', shared by the reference and every run.")
@click.option("--progress/--no-progress", default=True, show_default=True)
def materials(scenario, out_dir, body, materials, selections, modes, scheduler, workers, serial,
              t_end, dt, other, progress) -> None:
    """Body BODY of W, Cu, Al, PA6 (seed table 2): MVM runs against each full-FE reference;
    writes materials.csv, materials.json, fig9_materials.png."""
    from flexmvm.cli.select_cmd import parse_range
    from flexmvm.studies.materials import parse_selections, run_materials_study

    if workers is not None and workers < 1:
        raise InputError(f"--workers {workers}: expected a positive integer")
    names = [m.strip() for m in materials.split(",") if m.strip()]
    run_materials_study(scenario, out_dir, body=body, materials=names,
                        selections=parse_selections(selections), modes=parse_range(modes, "modes"),
                        scheduler=scheduler, n_workers=workers, progress=progress, t_end_s=t_end,
                        dt_s=dt, other=other,
                        serial=serial, echo=click.echo)
    click.echo(f"wrote {out_dir}")
