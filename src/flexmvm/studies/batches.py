"""The dispatch step of a selection study: batches of cases through studies.runner.run_cases.

Brute force hands every case over in one batch, the search (studies.search.smallest_passing)
one batch per round; :class:`Batches` runs each on the study's one cluster (or in-process),
keeps every evaluated row by case key and which cases were computed now and which were found
stored (selection.json's ``runs_made`` and ``runs_loaded``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from flexmvm.studies.case_store import Case
from flexmvm.studies.runner import run_cases

__all__ = ["Batches"]


class Batches:
    """Runs batches of cases through run_cases (shared cluster at ``address``, or in-process
    with ``serial``) and counts made/loaded runs. A case that raised (not stored; a rerun
    tries it again) gets the row ``failed_row(case, one line)``, so it is listed, and scored
    as failed, like a run whose solver failed."""

    def __init__(
        self,
        out_dir: Path,
        address: str | None,
        serial: bool,
        progress: bool,
        fn: Callable[[Case], dict],
        failed_row: Callable[[Case, str], dict],
        version: dict,
        echo: Callable[[str], Any],
    ) -> None:
        self.out_dir, self.address, self.serial, self.progress = out_dir, address, serial, progress
        self.fn, self.failed_row, self.version, self.echo = fn, failed_row, version, echo
        self.made: set[str] = set()
        self.loaded: set[str] = set()
        self.rows: dict[str, dict] = {}

    def __call__(self, cases: Sequence[Case]) -> list[dict]:
        """The rows of ``cases``, in order (stored ones loaded, the others computed)."""
        kw: dict[str, Any] = {"serial": True} if self.serial else {"scheduler": self.address}
        failures: dict[str, str] = {}
        stored: set[str] = set()
        res = run_cases(
            cases,
            self.fn,
            self.out_dir,
            progress=self.progress,
            failures=failures,
            version=self.version,
            loaded=stored,
            announce=self.echo,
            **kw,
        )
        for c in cases:
            (self.loaded if c.key in stored else self.made).add(c.key)
            self.rows[c.key] = (
                res[c.key] if c.key in res else self.failed_row(c, failures.get(c.key, "failed"))
            )
        return [self.rows[c.key] for c in cases]
