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


class OutputError(FlexmvmError, OSError):
    """A result file could not be written (disk full, no permission): names the file."""
