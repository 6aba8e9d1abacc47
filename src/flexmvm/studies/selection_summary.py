"""The report step of a selection study: ncc.csv's table and selection.json's content.

From the dispatch step's :class:`Sweep` (every evaluated row by case key, the runs computed
and loaded, the winner over both kinds and every candidate's score) and the study's grid
(studies.node_grid.NodeGrid or studies.region_families.RegionGrid): the node kind's table sorted as
ncc.csv, its winner (the smallest-DOF model reaching the target), the run counts, the failures
and, with the interface kind, that kind's answer and the winner over both
(studies/selection.py module doc lists the fields).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from flexmvm.metrics.ncc import Target
from flexmvm.scenarios import ModelKind
from flexmvm.studies.case_store import Case
from flexmvm.studies.grid import case_key
from flexmvm.studies.interface import interface_summary, is_interface_key
from flexmvm.studies.node_grid import NodeGrid
from flexmvm.studies.region_families import RegionGrid, region_key, region_winner, row_order
from flexmvm.studies.report import failure_list, target_dict, winner_dict
from flexmvm.studies.search import Candidate, FamilyKind, best_passing, kind_exact

__all__ = ["EXACT_NOTE", "Sweep", "selection_summary"]

#: selection.json's note on ``exact`` (node kind) and ``interface.exact``.
EXACT_NOTE = (
    "exact: this kind's entry is its smallest model reaching the target over its "
    "whole grid (always with brute force); false after --search when the other "
    "kind's winner (best_overall) has fewer DOF and this kind has models above that "
    "DOF: the search then proved only that nothing of this kind passes up to "
    "best_overall's DOF, and the entry (if any) is the best of the runs it made"
)

_RUNS_NOTE = (
    "runs = MVM cases evaluated for this answer = runs_made (computed in this "
    "invocation) + runs_loaded (found stored in cases/); the full-FE reference "
    "is not counted"
)
_DOF_NOTE = (
    "dof = 3 x retained nodes + modes (elastic coordinates, seed count); "
    "dof_total adds the 6 floating-frame coordinates"
)
_FAILURES_NOTE = (
    "failures: the runs that gave no comparison (the solver failed, the "
    "case raised: see cases/<key>.error.txt, a rerun tries it again; or a "
    "metric could not be computed); they count as not reaching the target"
)


@dataclass(frozen=True)
class Sweep:
    """What the dispatch step hands the report: ``rows`` every evaluated row by case key,
    ``made`` / ``loaded`` the keys computed now / found stored, ``case_of`` every candidate's
    case (node and interface kinds), ``best`` the winner over both kinds (None: none passes),
    ``scores`` the score of every evaluated candidate (studies.selection.score)."""

    rows: dict[str, dict]
    made: set[str]
    loaded: set[str]
    case_of: dict[Candidate, Case]
    best: Candidate | None
    scores: dict[Candidate, float]


@dataclass(frozen=True)
class Report:
    """ncc.csv's node-kind ``table`` (sorted), selection.json's ``summary`` and the evaluated
    interface rows (sorted by DOF, model)."""

    table: list[dict]
    summary: dict
    interface_rows: tuple[dict, ...]


class _Counts:
    """Case keys split by kind."""

    def __init__(self, keys: Iterable[str]) -> None:
        keys = list(keys)
        self.interface = sum(map(is_interface_key, keys))
        self.nodes = len(keys) - self.interface


def _node_kind(
    grid: NodeGrid | RegionGrid, rows: dict[str, dict], best: Candidate | None
) -> tuple[list[dict], dict, list[tuple[str, dict]]]:
    """The node kind's sorted table, winner fields + ``grid``, and (case key, row) pairs."""
    keyed = {k: r for k, r in rows.items() if not is_interface_key(k)}
    if isinstance(grid, RegionGrid):
        table = sorted(keyed.values(), key=row_order)
        summary = region_winner(best, keyed) | {"grid": grid.grid_dict()}
        return table, summary, [(region_key(r), r) for r in table]
    by_ijm = {(r["layers"], r["laps"], r["modes"]): r for r in keyed.values()}
    table = sorted(by_ijm.values(), key=lambda r: (r["layers"], r["laps"], r["modes"]))
    summary = winner_dict(best, by_ijm) | {"grid": grid.grid_dict()}
    return table, summary, [(case_key(r["layers"], r["laps"], r["modes"]), r) for r in table]


def _best_overall(
    best: Candidate | None, case_of: dict[Candidate, Case], rows: dict[str, dict], kind: ModelKind
) -> dict | None:
    """selection.json's best_overall: the search's (or brute force's) winner over both kinds."""
    if best is None:
        return None
    r = rows[case_of[best].key]
    if best.kind is FamilyKind.INTERFACE:
        model, name = r["model"], "interface"
    elif best.region is not None:
        model, name = f"{kind.value} {r['region']} + {r['modes']}", kind.value
    else:
        model, name = f"{kind.value} {r['layers']}-{r['laps']} + {r['modes']}", kind.value
    return {"kind": name, "model": model, "dof": r["dof"], "ncc_force": r.get("ncc_force")}


def _interface_kind(
    sweep: Sweep,
    target: Target,
    search: bool,
    kind: ModelKind,
    if_cases: Sequence[Case],
    patches: Sequence[Sequence[float]],
    interface_modes: Iterable[int],
) -> dict:
    """selection.json's fields of a study with the interface kind (``--patches``)."""

    def passes(s: float) -> bool:
        return s >= target.ncc_min

    def exact(k: FamilyKind) -> bool:
        return not search or kind_exact(k, sweep.best, sweep.scores, passes, list(sweep.case_of))

    if_best = best_passing(sweep.scores, passes, FamilyKind.INTERFACE)
    made, loaded = _Counts(sweep.made), _Counts(sweep.loaded)
    return {
        "grid_size": len(sweep.case_of) - len(if_cases),
        "exact": exact(FamilyKind.NODES),
        "exact_note": EXACT_NOTE,
        "interface": interface_summary(
            sweep.rows,
            if_cases,
            None if if_best is None else sweep.case_of[if_best].key,
            exact(FamilyKind.INTERFACE),
            made.interface,
            loaded.interface,
            patches,
            interface_modes,
        ),
        "best_overall": _best_overall(sweep.best, sweep.case_of, sweep.rows, kind),
    }


def selection_summary(
    grid: NodeGrid | RegionGrid,
    sweep: Sweep,
    *,
    body: str,
    kind: ModelKind,
    search: bool,
    target: Target,
    ref_made: bool,
    if_cases: Sequence[Case] = (),
    patches: Sequence[Sequence[float]] | None = None,
    interface_modes: Iterable[int] = (),
) -> Report:
    """The table and selection.json of a selection study of ``body`` whose candidates of
    model ``kind`` were evaluated in ``sweep`` against ``target`` (``search``: by the pruned
    search; ``ref_made``: the reference was computed in this invocation); ``if_cases`` the
    interface kind's cases of ``patches`` x ``interface_modes`` (none: no interface kind)."""

    def passes(s: float) -> bool:
        return s >= target.ncc_min

    node_best = best_passing(sweep.scores, passes, FamilyKind.NODES)
    table, summary, keyed = _node_kind(grid, sweep.rows, node_best)
    summary |= {
        "body": body,
        "kind": kind.value,
        "search": bool(search),
        "target": target_dict(target),
        "runs": sum(c.kind is FamilyKind.NODES for c in sweep.scores),
        "runs_made": _Counts(sweep.made).nodes,
        "runs_loaded": _Counts(sweep.loaded).nodes,
        "runs_note": _RUNS_NOTE,
        "reference_computed": ref_made,
        "dof_note": _DOF_NOTE,
        "failed_cases": sorted(k for k, r in keyed if "failed" in r),
        "failures": failure_list(keyed),
        "failures_note": _FAILURES_NOTE,
    }
    if_rows = [sweep.rows[c.key] for c in if_cases if c.key in sweep.rows]
    if if_cases:
        summary |= _interface_kind(
            sweep, target, search, kind, if_cases, patches or (), interface_modes
        )
    return Report(table, summary, tuple(sorted(if_rows, key=lambda r: (r["dof"], r["model"]))))
