"""Studies from a user's script: a local Dask cluster starts its workers by spawn, which
re-imports the script that started them (``__main__``) in every worker. A script whose top
level calls a study without ``if __name__ == "__main__":`` would run again in each worker
(multiprocessing's "bootstrapping phase" RuntimeError, the workers failing to start). The
library's studies (studies/api.py) run such a script's study in its own process when no
workers were asked for, and a local cluster asked for from it is a one-line InputError
(runner.local_cluster)."""

from __future__ import annotations

import ast
import sys
import warnings
from pathlib import Path

__all__ = [
    "InProcessStudyWarning",
    "in_process_by_default",
    "main_guard_advice",
    "unguarded_main_script",
]


class InProcessStudyWarning(UserWarning):
    """A library study from a script without a main guard, no workers asked: run in-process."""


def _is_main_test(test: ast.expr) -> bool:
    """True for ``__name__ == "__main__"`` (either side)."""
    if not (
        isinstance(test, ast.Compare) and len(test.ops) == 1 and isinstance(test.ops[0], ast.Eq)
    ):
        return False
    sides = (test.left, test.comparators[0])
    return any(isinstance(x, ast.Name) and x.id == "__name__" for x in sides) and any(
        isinstance(x, ast.Constant) and x.value == "__main__" for x in sides
    )


def unguarded_main_script() -> str | None:
    """The path of the ``__main__`` module when it is a Python file whose top level has no
    ``if __name__ == "__main__":`` block, else None (an interactive session, ``python -c``,
    pytest, the flexmvm command). A local cluster's worker processes are started by spawn,
    which re-imports that file in each of them: its top level, a study call included, would
    run again in every worker (multiprocessing's "bootstrapping phase" RuntimeError)."""
    path = getattr(sys.modules.get("__main__"), "__file__", None)
    if not path:
        return None
    try:
        tree = ast.parse(Path(path).read_text(encoding="utf-8"))
    except (OSError, SyntaxError, UnicodeDecodeError, ValueError):
        return None
    if any(isinstance(node, ast.If) and _is_main_test(node.test) for node in tree.body):
        return None
    return str(path)


def main_guard_advice(script: str) -> str:
    return (
        f"put the code of {script} under 'if __name__ == \"__main__\":' (worker processes "
        "re-import the script and would run it again)"
    )


def in_process_by_default(
    scheduler: str | None, n_workers: int | None, serial: bool, stacklevel: int = 3
) -> bool:
    """``serial`` as a library study takes it: also True when neither workers nor a
    scheduler are asked for and the main script has no main guard (unguarded_main_script),
    with an InProcessStudyWarning of one line saying what to add for worker processes."""
    if serial or scheduler is not None or n_workers is not None:
        return serial
    script = unguarded_main_script()
    if script is None:
        return False
    warnings.warn(
        f"study run in this process, not on worker processes: to use them, "
        f"{main_guard_advice(script)}",
        InProcessStudyWarning,
        stacklevel=stacklevel,
    )
    return True
