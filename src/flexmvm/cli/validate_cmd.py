"""`flexmvm validate [--out DIR] [--md FILE] [--case KEY ...] [--recompute]`: run the physics
validation (flexmvm.validation) and write its report; also `python -m flexmvm.validation`."""

from __future__ import annotations

from pathlib import Path

import click


@click.command("validate")
@click.option(
    "--out",
    "out_dir",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Folder of the stored cases, figures and validation.json (default: the "
    "checkout's docs/validation; required when installed from a wheel).",
)
@click.option(
    "--md",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    help="Report page (default: beside --out with its name + .md, i.e. "
    "docs/validation.md in a checkout).",
)
@click.option(
    "--case",
    "cases",
    multiple=True,
    metavar="KEY",
    help="Run only this case (repeatable): flat_vs_st_venant, seed, step_convergence, "
    "short, pendulum, hertz_block or arm_stop (flexmvm.validation.cases.CASES). The report "
    "page needs every case, so only validation.json is written. 'short' (0.1 m "
    "rods) and 'hertz_block' (a sphere on a block) take a few minutes, 'arm_stop' "
    "(a 38,502-DOF full-FE arm) a quarter of an hour.",
)
@click.option("--recompute", is_flag=True, help="Ignore stored cases.")
def command(out_dir: Path | None, md: Path | None, cases: tuple[str, ...], recompute: bool) -> None:
    """Run the physics validation and write its report.

    Each case's runs are stored under --out and reused while their key (package source,
    numpy/scipy/numba versions, the whole resolved scenario) matches; the full set takes
    about 12 minutes of two cores when nothing is stored."""
    from flexmvm.validation.paths import default_outputs
    from flexmvm.validation.report import claim_report_md
    from flexmvm.validation.suite import run_validation

    what = None
    if out_dir is None:
        out_dir, default_md = default_outputs()
        md = default_md if md is None else md
    elif md is None:
        md = out_dir.parent / f"{out_dir.name}.md"
        what = f"--out {out_dir}: its report page {md}"
    if not cases:  # the page is written only with every case: refused before the runs
        claim_report_md(md, what)
    run_validation(out_dir, md, recompute, list(cases) or None, echo=click.echo)
