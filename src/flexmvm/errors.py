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
    holds what was computed up to there (an integrate.RunResult whose ``failure`` is set)."""

    def __init__(self, message: str, partial=None):
        super().__init__(message)
        self.partial = partial
