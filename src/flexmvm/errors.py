"""Errors that reach the user as one line.

Every error the library raises on bad input is a :class:`FlexmvmError`; the CLI prints
``flexmvm: error: <message>`` and exits with status 2, never a traceback.
"""


class FlexmvmError(Exception):
    """Base of all errors meant for the user: the message is one line."""


class InputError(FlexmvmError, ValueError):
    """Bad input: says what was received and what was expected."""


class MeshError(InputError):
    """A mesh that cannot be used (inverted/degenerate element, empty, wrong cell type)."""


class SolverError(FlexmvmError, RuntimeError):
    """A numerical solve failed (non-convergence, singular system) with a readable reason."""


class SimulationFailed(SolverError):
    """A run that stopped before its end time: the message says where and why, ``partial``
    holds what was computed up to there (an integrate.run_result.RunResult whose ``failure``
    is set)."""

    def __init__(self, message: str, partial=None):
        super().__init__(message)
        self.partial = partial


class StaleDataWarning(UserWarning):
    """Stored data (a setup-cache entry, a study's reference or case, a validation case) that
    failed its check and is recomputed: one line, what was found and that it is recomputed."""


def announce_recompute(message: str) -> None:
    """Say in one line that stored data failed its check and is recomputed (StaleDataWarning;
    the CLI prints it as ``flexmvm: note: <message>``)."""
    import warnings

    warnings.warn(message, StaleDataWarning, stacklevel=3)


class _NotesHook:
    """The warnings.showwarning notes_as_lines installs: a StaleDataWarning as one line,
    every other warning through the hook it replaced (``previous``)."""

    def __init__(self, previous) -> None:
        self.previous = previous

    def __call__(self, message, category, filename, lineno, file=None, line=None) -> None:
        import sys

        if issubclass(category, StaleDataWarning):
            text = " ".join(str(message).split())
            print(f"flexmvm: note: {text}", file=sys.stderr if file is None else file, flush=True)
        else:
            self.previous(message, category, filename, lineno, file, line)


def notes_as_lines() -> None:
    """From now on show every StaleDataWarning of this process as one stderr line,
    ``flexmvm: note: <message>``, not Python's two lines with the source line; other warnings
    as before. The CLI calls it, and the worker processes of a run's main job."""
    import warnings

    if not isinstance(warnings.showwarning, _NotesHook):  # installed once
        warnings.showwarning = _NotesHook(warnings.showwarning)


class OutputError(FlexmvmError, OSError):
    """A result file could not be written (disk full, no permission): names the file."""


class StudyInterrupted(KeyboardInterrupt):
    """A study stopped by Ctrl-C: the message is its one line (how many cases are stored and
    where, and that a rerun resumes); the CLI prints it and exits with status 130."""
