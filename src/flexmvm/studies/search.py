"""Find the smallest reduced model that reaches a target score without running every case.

The selection study (seed §3.2) asks for the model with the fewest DOF whose contact force
reaches a target NCC, over a grid of node selections x mode counts (20 x 7 = 140 runs).
Each candidate costs one expensive simulation; this module finds the same answer as running
the whole grid (:func:`brute_force`) with far fewer runs (:func:`smallest_passing`).

Assumption (Rayleigh-Ritz): for a fixed node selection, the score is non-decreasing in the
number of modes, because adding modes enlarges the trial subspace; so ``passes(score)`` is
false up to some mode count and true from there on. Candidates of one selection must have
DOF strictly increasing with the mode count (each mode adds one generalised coordinate).

Strategy of :func:`smallest_passing`:

1. Keep ``best_dof`` = the smallest DOF of any passing candidate evaluated so far (inf at
   start). Only candidates with ``dof <= best_dof`` can still win (``<=`` keeps DOF ties,
   which the score then decides).
2. Open the selections in order of the DOF of their cheapest candidate (at most
   ``max_open`` at a time; all by default); a selection whose cheapest candidate has
   ``dof > best_dof`` is closed without any run.
3. Each open selection binary-searches the smallest passing mode count among its candidates
   with ``dof <= best_dof``: everything below a failing candidate fails, everything above a
   passing one passes. In each round the midpoints of all open selections are evaluated
   together, in one call of ``evaluate`` (so a Dask runner runs the batch in parallel);
   then ``best_dof`` is lowered and every search range is cut to ``dof <= best_dof``.
4. When no search is open, the winner is the evaluated passing candidate of smallest DOF;
   ties go to the higher score, then to fewer node DOF (``dof - modes``), then to the
   smaller ``(selection, modes)``. The brute-force answer uses the same order, so both agree
   whenever the assumption holds (tests/test_search.py checks 200 random monotone tables).

Each round costs one ``evaluate`` call, so ``max_open`` trades rounds (wall time on a
cluster) against runs: ``max_open=1`` is the sequential search with the strongest pruning.
"""

from __future__ import annotations

import bisect
import itertools
import math
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from flexmvm.errors import InputError

__all__ = ["Candidate", "brute_force", "rank_key", "smallest_passing"]


@dataclass(frozen=True)
class Candidate:
    """One reduced model of a selection study.

    Attributes:
        selection: node selection ``(layers, laps)`` (seed's i-j scheme), both >= 1.
        modes: number of modes of the basis (>= 0).
        dof: number of generalised coordinates of the model (>= 1), the cost to minimise.

    Raises:
        InputError: a field has the wrong type or range.
    """

    selection: tuple[int, int]
    modes: int
    dof: int

    def __post_init__(self) -> None:
        sel = tuple(self.selection)
        if len(sel) != 2 or not all(isinstance(v, int) and v >= 1 for v in sel):
            raise InputError(
                f"Candidate selection {self.selection!r}: expected (layers, laps) >= 1"
            )
        object.__setattr__(self, "selection", sel)
        if not isinstance(self.modes, int) or self.modes < 0:
            raise InputError(f"Candidate modes {self.modes!r}: expected an integer >= 0")
        if not isinstance(self.dof, int) or self.dof < 1:
            raise InputError(f"Candidate dof {self.dof!r}: expected an integer >= 1")


def rank_key(candidate: Candidate, score: float) -> tuple:
    """Order of passing candidates, best first: fewer DOF, higher score, fewer node DOF,
    then ``(selection, modes)`` so the choice is deterministic."""
    return (
        candidate.dof,
        -score,
        candidate.dof - candidate.modes,
        candidate.selection,
        candidate.modes,
    )


def _group(candidates: Sequence[Candidate]) -> dict[tuple[int, int], list[Candidate]]:
    """Candidates per selection, sorted by modes; checks uniqueness and increasing DOF."""
    groups: dict[tuple[int, int], list[Candidate]] = {}
    for c in candidates:
        if not isinstance(c, Candidate):
            raise InputError(f"received {type(c).__name__}, expected Candidate objects")
        groups.setdefault(c.selection, []).append(c)
    for sel, items in groups.items():
        items.sort(key=lambda c: c.modes)
        for a, b in itertools.pairwise(items):
            if a.modes == b.modes:
                raise InputError(f"selection {sel}: {a.modes} modes appears twice; expected once")
            if b.dof <= a.dof:
                raise InputError(
                    f"selection {sel}: dof {a.dof} at {a.modes} modes but {b.dof} at {b.modes}; "
                    "expected dof strictly increasing with modes"
                )
    return groups


class _Evaluator:
    """Calls ``evaluate`` on batches, checks its answers and remembers every score."""

    def __init__(self, evaluate: Callable[[Sequence[Candidate]], Sequence[float]]) -> None:
        self.evaluate = evaluate
        self.scores: dict[Candidate, float] = {}
        self.calls = 0

    def __call__(self, batch: list[Candidate]) -> list[float]:
        raw = list(self.evaluate(list(batch)))
        self.calls += 1
        if len(raw) != len(batch):
            raise InputError(
                f"evaluate returned {len(raw)} scores for {len(batch)} candidates; expected one each"
            )
        scores = []
        for c, s in zip(batch, raw):
            value = float(s)
            if math.isnan(value):
                raise InputError(f"evaluate returned NaN for {c}; expected a number")
            self.scores[c] = value
            scores.append(value)
        return scores


class _Bisection:
    """Binary search for the first passing candidate of one selection.

    Invariant: items[:lo] fail, items[hi] passes (or hi == len(items)).
    """

    def __init__(self, items: list[Candidate]) -> None:
        self.items = items
        self.dofs = [c.dof for c in items]
        self.lo = 0
        self.hi = len(items)

    def probe(self, best_dof: float) -> Candidate | None:
        """The next candidate to evaluate, or None when the search is over."""
        cap = bisect.bisect_right(self.dofs, best_dof)
        end = min(self.hi, cap)
        if self.lo >= end:
            return None
        return self.items[(self.lo + end) // 2]

    def record(self, candidate: Candidate, passed: bool) -> None:
        index = self.items.index(candidate)
        if passed:
            self.hi = index
        else:
            self.lo = index + 1


def _winner(scores: dict[Candidate, float], passes: Callable[[float], bool]) -> Candidate | None:
    passing = [(rank_key(c, s), c) for c, s in scores.items() if passes(s)]
    return min(passing, key=lambda item: item[0])[1] if passing else None


def smallest_passing(
    candidates: Sequence[Candidate],
    evaluate: Callable[[Sequence[Candidate]], Sequence[float]],
    passes: Callable[[float], bool],
    *,
    max_open: int | None = None,
) -> tuple[Candidate | None, dict[Candidate, float]]:
    """The passing candidate of fewest DOF, found by per-selection bisection (module doc).

    Args:
        candidates: the grid; per selection, unique mode counts with DOF strictly increasing.
        evaluate: scores of a batch of candidates, in order (e.g. NCC against the full FE
            force); called once per round with at most one candidate per open selection.
        passes: whether a score reaches the target (e.g. ``lambda r: r >= 0.99``); must be
            monotone in the score for the search to be exact.
        max_open: number of selections searched at once (None: all).

    Returns:
        ``(winner or None, {candidate: score} of every evaluated candidate)``; the length of
        the dict is the number of runs made.

    Raises:
        InputError: duplicate or non-increasing candidates, ``max_open < 1``, or ``evaluate``
            returning the wrong number of scores or a NaN.
    """
    if max_open is not None and max_open < 1:
        raise InputError(f"max_open={max_open}; expected a positive integer or None")
    groups = _group(candidates)
    queue = deque(sorted(groups, key=lambda sel: (groups[sel][0].dof, sel)))
    run = _Evaluator(evaluate)
    best_dof = math.inf
    searches: list[_Bisection] = []
    while queue or searches:
        while queue and (max_open is None or len(searches) < max_open):
            sel = queue.popleft()
            if groups[sel][0].dof <= best_dof:
                searches.append(_Bisection(groups[sel]))
        probes = [(s, s.probe(best_dof)) for s in searches]
        searches = [s for s, c in probes if c is not None]
        batch = [c for _, c in probes if c is not None]
        if not batch:
            continue
        for search, c, score in zip(searches, batch, run(batch)):
            passed = bool(passes(score))
            search.record(c, passed)
            if passed:
                best_dof = min(best_dof, c.dof)
    return _winner(run.scores, passes), run.scores


def brute_force(
    candidates: Sequence[Candidate],
    evaluate: Callable[[Sequence[Candidate]], Sequence[float]],
    passes: Callable[[float], bool],
) -> tuple[Candidate | None, dict[Candidate, float]]:
    """Evaluate every candidate (one batch) and return the best passing one, ranked as in
    :func:`smallest_passing`, with all scores.

    Raises:
        InputError: as :func:`smallest_passing`.
    """
    groups = _group(candidates)
    run = _Evaluator(evaluate)
    everything = [c for sel in sorted(groups) for c in groups[sel]]
    if everything:
        run(everything)
    return _winner(run.scores, passes), run.scores
