"""`python -m tools.validation [--out DIR] [--md FILE] [--case KEY ...] [--recompute]`, run from
the repository root: run the physics validation and write its report (it replaces the former
`flexmvm validate`). Errors meant for the user are one line, ``flexmvm: error: <message>``,
exit status 2, as the ``flexmvm`` command's (flexmvm.cli.app)."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from flexmvm.cli.app import one_line
from flexmvm.cli.messages import INTERRUPTED
from flexmvm.errors import FlexmvmError

#: The program name in the usage line.
PROG = "python -m tools.validation"


@click.command("validation", context_settings={"help_option_names": ["-h", "--help"]})
@click.option(
    "--out",
    "out_dir",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Folder of the stored cases, figures and validation.json (default: the "
    "repository's docs/validation).",
)
@click.option(
    "--md",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    help="Report page (default: beside --out with its name + .md, i.e. "
    "docs/validation.md by default).",
)
@click.option(
    "--case",
    "cases",
    multiple=True,
    metavar="KEY",
    help="Run only this case (repeatable): flat_vs_st_venant, seed, step_convergence, "
    "short, pendulum, hertz_block or arm_stop (tools.validation.cases.CASES). The report "
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
    from tools.validation.paths import default_outputs
    from tools.validation.report import claim_report_md
    from tools.validation.suite import run_validation

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


def main(argv: list[str] | None = None) -> None:
    """Run the command; a user error (FlexmvmError) or a bad option is one stderr line and
    exit status 2, Ctrl-C one line and 130."""
    args = list(sys.argv[1:] if argv is None else argv)
    try:
        command.main(args=args, prog_name=PROG, standalone_mode=False)
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
    except click.ClickException as exc:
        click.echo(f"flexmvm: error: {one_line(exc.format_message())}", err=True)
        sys.exit(2)
    except (click.exceptions.Abort, KeyboardInterrupt):
        click.echo(INTERRUPTED, err=True)
        sys.exit(130)
    except FlexmvmError as exc:
        click.echo(f"flexmvm: error: {one_line(str(exc))}", err=True)
        sys.exit(2)


__all__ = ["PROG", "command", "main"]
