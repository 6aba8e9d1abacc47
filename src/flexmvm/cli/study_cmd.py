"""`flexmvm study materials SCENARIO --out DIR`: the material study (seed section 3.3)."""

from __future__ import annotations

from pathlib import Path

import click

from flexmvm.cli.kind_choice import retaining_kinds
from flexmvm.cli.study_options import check_workers, study_output, study_run_options


@click.group("study")
def command() -> None:
    """Studies over many runs (Dask, resumable)."""


@command.command("materials")
@click.argument("scenario", type=click.Path(dir_okay=False, path_type=Path))
@click.option(
    "--out",
    "out_dir",
    required=True,
    type=click.Path(file_okay=False, path_type=Path),
    help="Study directory (a rerun resumes).",
)
@click.option("--body", default="b2", show_default=True, help="The body whose material varies.")
@click.option(
    "--materials", default="W,Cu,Al,PA6", show_default=True, help="Seed table 2 materials to run."
)
@click.option("--selections", default="1-1,2-2", show_default=True, help="i-j selections.")
@click.option(
    "--modes",
    default="7:43:12",
    show_default=True,
    help="Mode counts: start:stop:step, stop included.",
)
@click.option(
    "--kind",
    type=retaining_kinds(),
    default="mvm",
    show_default=True,
    help="Reduced model of BODY: Craig-Bampton (mvm) or the seed's eq. (4) readings.",
)
@study_run_options
@click.option("--progress/--no-progress", default=True, show_default=True)
def materials(
    scenario,
    out_dir,
    body,
    materials,
    selections,
    modes,
    kind,
    options,
) -> None:
    """Body BODY of W, Cu, Al, PA6 (seed table 2): runs of the KIND model against each
    full-FE reference; writes materials.csv, materials.json, fig9_materials.png."""
    from flexmvm.cli.select_cmd import parse_range
    from flexmvm.studies.materials import parse_selections, run_materials_study

    check_workers(options.n_workers, options.scheduler)
    names = [m.strip() for m in materials.split(",") if m.strip()]
    with study_output(out_dir):
        run_materials_study(
            scenario,
            out_dir,
            body=body,
            materials=names,
            selections=parse_selections(selections),
            modes=parse_range(modes, "modes"),
            kind=kind,
            options=options,
        )
    click.echo(f"wrote {out_dir}")
