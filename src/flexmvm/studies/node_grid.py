"""The node-selection grid of a rod body's selection study (seed section 3.2).

A rod body's candidates are its ``i-j`` node selections (``i`` layers from the contact face,
``j`` laps about the axis: studies.grid.rod_of) x ``m`` fixed-interface modes. :class:`NodeGrid`
is that grid checked against the mesh (studies.grid.check_grid), with the number of retained
nodes of each selection, and it meets the selection study the way a body of any mesh's
studies.region_families.RegionGrid does: ``cases``, ``candidate``, ``grid_dict``.

DOF of a candidate: ``3 x retained nodes + modes`` (elastic coordinates, the seed's count;
studies/selection.py module doc).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path

from flexmvm.scenarios import ModelKind, Scenario
from flexmvm.studies.case_store import Case
from flexmvm.studies.grid import check_grid, selection_cases
from flexmvm.studies.report import failed_case_row
from flexmvm.studies.search import Candidate

__all__ = ["NodeGrid"]


class NodeGrid:
    """``layers`` x ``laps`` x ``modes`` of rod body ``body`` (sorted, checked by
    studies.grid.check_grid: InputError for a mesh body or a grid beyond the mesh);
    ``n_nodes[(i, j)]`` the retained nodes of selection ``i-j``; ``centre`` the patches' centre
    [m] as given (None: studies.interface.patch_place's default, the rod's end_a)."""

    def __init__(
        self,
        sc: Scenario,
        body: str,
        layers: Iterable[int],
        laps: Iterable[int],
        modes: Iterable[int],
        kind: ModelKind,
        centre_m: Sequence[float] | None = None,
    ) -> None:
        rod, self.layers, self.laps, self.modes = check_grid(sc, body, layers, laps, modes)
        self.body, self.kind, self.centre = body, kind, centre_m
        self.n_nodes = {(i, j): len(rod.selection(i, j)) for i in self.layers for j in self.laps}

    def cases(self, sc: Scenario, reference: str | Path | None) -> list[Case]:
        """The grid's cases (studies.grid.selection_cases), against reference history
        ``reference``."""
        return selection_cases(
            sc, self.body, self.layers, self.laps, self.modes, reference=reference, kind=self.kind
        )

    def candidate(self, case: Case) -> Candidate:
        """The search's candidate of one of :meth:`cases`: family ``(i, j)``, its DOF."""
        i, j, m = case.params["layers"], case.params["laps"], case.params["modes"]
        return Candidate((i, j), m, 3 * self.n_nodes[(i, j)] + m)

    def failed_row(self, case: Case, line: str) -> dict:
        """ncc.csv's row of a case that raised (``line``: the one-line reason)."""
        return failed_case_row(
            case, line, self.n_nodes[(case.params["layers"], case.params["laps"])]
        )

    def grid_dict(self) -> dict:
        """selection.json's ``grid``."""
        return {"layers": self.layers, "laps": self.laps, "modes": self.modes}
