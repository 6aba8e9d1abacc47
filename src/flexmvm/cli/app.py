"""The ``flexmvm`` command: a click group; each sub-command lives in its own module. The entry
point (cli/main.py) imports this module inside its own Ctrl-C handler.

No command ends in a traceback:

- errors meant for the user (:class:`flexmvm.errors.FlexmvmError`) become one line on stderr,
  ``flexmvm: error: <message>``, and exit status 2;
- any other exception (a bug, or an OS error nobody turned into a message) becomes one line,
  ``flexmvm: error: <command>: <ExceptionType>: <message>``, and exit status 1;
- a keyboard interrupt exits with 130, SIGTERM with 143 (both after cleaning up: staging
  directories removed, worker processes stopped).

``flexmvm --debug ...`` or the environment variable ``FLEXMVM_DEBUG=1`` re-raises instead, so
Python prints the full traceback.
"""

from __future__ import annotations

import os
import sys

import click

from flexmvm import __version__
from flexmvm.cli.messages import INTERRUPTED, TERMINATED
from flexmvm.errors import FlexmvmError, notes_as_lines
from flexmvm.processes import Terminated, sigterm_as_exit

#: Environment variable that turns on --debug (any value but "", "0", "false", "no").
DEBUG_ENV = "FLEXMVM_DEBUG"
_MAX_MESSAGE = 500


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="flexmvm")
@click.option(
    "--debug", is_flag=True, help=f"Show the Python traceback of a failure (also: {DEBUG_ENV}=1)."
)
def cli(debug: bool) -> None:
    """Contact and impact of flexible bodies with the multi-variable method (MVM)."""


def _register() -> None:
    """Attach the sub-commands; each module defines one click command or group."""
    if cli.commands:
        return
    for name in (
        "mesh_cmd",
        "run_cmd",
        "theory_cmd",
        "select_cmd",
        "region_cmd",
        "study_cmd",
        "cache_cmd",
        "compare_cmd",
    ):
        try:
            module = __import__(f"flexmvm.cli.{name}", fromlist=["command"])
        except ModuleNotFoundError as exc:
            if exc.name != f"flexmvm.cli.{name}":
                raise
            continue
        cli.add_command(module.command)


def debug_enabled(argv: list[str]) -> bool:
    """--debug among the group's options (before the sub-command) or FLEXMVM_DEBUG set."""
    if os.environ.get(DEBUG_ENV, "").strip().lower() not in ("", "0", "false", "no"):
        return True
    for arg in argv:
        if arg == "--debug":
            return True
        if not arg.startswith("-"):
            return False  # the sub-command: later words are its own
    return False


def command_path(argv: list[str]) -> str:
    """The sub-command words of argv ('mesh rod', 'run'), or 'flexmvm' if none."""
    words: list[str] = []
    group: click.Command = cli
    for arg in argv:
        if arg.startswith("-"):
            continue
        sub = group.commands.get(arg) if isinstance(group, click.Group) else None
        if sub is None:
            break
        words.append(arg)
        group = sub
    return " ".join(words) or "flexmvm"


def one_line(text: str) -> str:
    """Newlines and runs of spaces collapsed; cut to a readable length."""
    line = " ".join(str(text).split())
    return line if len(line) <= _MAX_MESSAGE else line[: _MAX_MESSAGE - 3] + "..."


def describe(exc: BaseException, command: str) -> str:
    """The one stderr line of an unexpected exception: command, type, message."""
    message = one_line(str(exc))
    return f"flexmvm: error: {command}: {type(exc).__name__}" + (f": {message}" if message else "")


def run(argv: list[str] | None = None) -> None:
    """Runs the CLI; every failure is one stderr line and a non-zero exit status (module doc),
    unless --debug / FLEXMVM_DEBUG asks for the traceback."""
    args = list(sys.argv[1:] if argv is None else argv)
    debug = debug_enabled(args)
    notes_as_lines()
    try:
        with sigterm_as_exit():
            _register()  # the sub-commands' imports (numpy, scipy, ...): a Ctrl-C is caught
            cli.main(args=args, prog_name="flexmvm", standalone_mode=False)
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
    except click.ClickException as exc:
        click.echo(f"flexmvm: error: {one_line(exc.format_message())}", err=True)
        sys.exit(2)
    except (click.exceptions.Abort, KeyboardInterrupt) as exc:
        if isinstance(exc, Terminated) or isinstance(exc.__context__, Terminated):
            click.echo(TERMINATED, err=True)
            sys.exit(143)
        click.echo(INTERRUPTED, err=True)
        sys.exit(130)
    except FlexmvmError as exc:
        if debug:
            raise
        click.echo(f"flexmvm: error: {one_line(str(exc))}", err=True)
        sys.exit(2)
    except Exception as exc:  # the last line of defence: no traceback
        if debug:
            raise
        click.echo(describe(exc, command_path(args)), err=True)
        sys.exit(1)
