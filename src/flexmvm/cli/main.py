"""The ``flexmvm`` command: a click group; each sub-command lives in its own module.

Errors meant for the user (:class:`flexmvm.errors.FlexmvmError`) become one line on stderr and
exit status 2; a keyboard interrupt exits with 130 after whatever was already written.
"""

from __future__ import annotations

import sys

import click

from flexmvm import __version__
from flexmvm.errors import FlexmvmError


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="flexmvm")
def cli() -> None:
    """Contact and impact of flexible bodies with the multi-variable method (MVM)."""


def _register() -> None:
    """Attach the sub-commands; each module defines one click command or group."""
    for name in ("mesh_cmd", "run_cmd", "theory_cmd", "select_cmd", "study_cmd", "cache_cmd"):
        try:
            module = __import__(f"flexmvm.cli.{name}", fromlist=["command"])
        except ModuleNotFoundError as exc:
            if exc.name != f"flexmvm.cli.{name}":
                raise
            continue
        cli.add_command(module.command)


def main(argv: list[str] | None = None) -> None:
    """Entry point: runs the CLI, turning user errors into one line and exit status 2."""
    _register()
    try:
        cli.main(args=argv, prog_name="flexmvm", standalone_mode=False)
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
    except click.ClickException as exc:
        click.echo(f"flexmvm: error: {exc.format_message()}", err=True)
        sys.exit(2)
    except click.exceptions.Abort:
        click.echo("flexmvm: interrupted", err=True)
        sys.exit(130)
    except FlexmvmError as exc:
        click.echo(f"flexmvm: error: {exc}", err=True)
        sys.exit(2)
    except KeyboardInterrupt:
        click.echo("flexmvm: interrupted; results written so far are kept", err=True)
        sys.exit(130)


if __name__ == "__main__":
    main()
