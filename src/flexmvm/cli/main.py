"""The entry point of the ``flexmvm`` command (pyproject: ``flexmvm.cli.main:main``).

It imports nothing but ``sys`` and the two messages of cli/messages.py before :func:`main`
runs, and :func:`main` imports the command (cli/app.py: click, the sub-commands, numpy, scipy,
...) inside a Ctrl-C handler: an interrupt
at any moment of the start, the seconds of imports included, is one line on stderr and exit
status 130, never a traceback. The command's names (``cli``, ``command_path``, ...) are
reachable here as before, imported on first use.
"""

from __future__ import annotations

import sys

from flexmvm.cli.messages import INTERRUPTED, TERMINATED  # noqa: F401 (names of this module)


def main(argv: list[str] | None = None) -> None:
    """Run the command (cli/app.py ``run``); Ctrl-C during its imports exits 130 with the
    same one line as during the run."""
    try:
        from flexmvm.cli import app
    except KeyboardInterrupt:
        sys.stderr.write(INTERRUPTED + "\n")
        sys.exit(130)
    try:
        app.run(argv)
    except KeyboardInterrupt:  # between app's own handler and the exit
        sys.stderr.write(INTERRUPTED + "\n")
        sys.exit(130)


def __getattr__(name: str):
    """The command's module-level names (cli, _register, command_path, ...) from cli/app.py."""
    if name.startswith("__"):
        raise AttributeError(name)
    from flexmvm.cli import app

    return getattr(app, name)


if __name__ == "__main__":
    main()
