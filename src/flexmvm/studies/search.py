"""Find the smallest reduced model that reaches a target score without running every case.

The selection study (seed §3.2) asks for the model with the fewest DOF whose contact force
reaches a target NCC, over a grid of node selections x mode counts (20 x 7 = 140 runs), and,
with ``--patches``, over the interface kind's patch-radius sets x mode counts beside them
(studies/interface.py). Each candidate costs one expensive simulation; this module finds the
same answer as running the whole grid (:func:`brute_force`) with far fewer runs
(:func:`smallest_passing`).

Families. A candidate belongs to one *family*: a node selection ``(layers, laps)`` of a rod or
a region family of any body (a ball radius or a node set, studies/region_families.py; node kind: one
study has either, never both) or a patch-radius set (interface kind); within a family only
the mode count varies.

Assumption (Rayleigh-Ritz): within a family the score is non-decreasing in the number of
modes, because adding modes enlarges the trial subspace (node selection: the fixed-interface
modes in frequency order; interface: the modes in participation order, so a larger count
keeps the smaller count's modes as long as the ranking of the smaller pool is a prefix of
the larger one's); so ``passes(score)`` is false up to some mode count and true from there
on. Candidates of one family must have DOF strictly increasing with the mode count (each mode
adds one generalised coordinate).

Strategy of :func:`smallest_passing`, one search over the families of both kinds:

1. Keep ``best_dof`` = the smallest DOF of any passing candidate evaluated so far (inf at
   start), whatever its kind: a passing 18-DOF interface model closes every node selection
   above 18 DOF and vice versa. Only candidates with ``dof <= best_dof`` can still win
   (``<=`` keeps DOF ties, which the score then decides).
2. Open the families in order of the DOF of their cheapest candidate (at most ``max_open``
   at a time; all by default); a family whose cheapest candidate has ``dof > best_dof`` is
   closed without any run.
3. Each open family searches the smallest passing mode count among its candidates with
   ``dof <= best_dof``: everything below a failing candidate fails, everything above a
   passing one passes. While no candidate within that cap is known to pass, the family
   probes its largest one (one failing run closes the family: most families of a study
   cannot reach the target below the winner's DOF); once one passes, it bisects below it.
   In each round the probes of all open families are evaluated together, in one call of
   ``evaluate`` (so a Dask runner runs the batch in parallel); then ``best_dof`` is lowered
   and every search range is cut to ``dof <= best_dof``.
4. When no search is open, the winner is the evaluated passing candidate of smallest DOF;
   ties go to the higher score, then to the node kind before the interface kind, then to
   fewer static coordinates ``dof - modes`` (node DOF of a selection, patch vectors of an
   interface set), then to the smaller ``(selection, modes)`` (node kind) or
   ``(patch radii, modes)`` (interface kind). The brute-force answer uses the same order,
   so both agree whenever the assumption holds (tests/test_search.py checks 200 random
   monotone tables of node selections and 200 of both kinds).

What the search proves beyond the winner: every family's first passing candidate with
``dof <= winner dof`` is known, so a kind's best evaluated candidate is that kind's own
smallest model when its DOF equals the winner's (:func:`kind_exact`); a kind that lost has
no passing model up to the winner's DOF, and models above it were not searched.

Each round costs one ``evaluate`` call, so ``max_open`` trades rounds against runs: with
every family open, the first round runs one candidate of each, most of them in families that
a passing candidate of a cheaper family closes a round later; with few open, a passing
candidate closes the others before they cost a run, but the rounds are many and a cluster's
workers idle in rounds smaller than the cluster. ``max_open=1`` is the sequential search.
studies.selection opens SEARCH_OPEN_PER_SLOT families per case the cluster runs at once
(replays of the seed study's table: docs/notes/2026-11-27-comment-measurements.md).
"""

from __future__ import annotations

import bisect
import itertools
import math
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import StrEnum

from flexmvm.errors import InputError

__all__ = [
    "Candidate",
    "FamilyKind",
    "best_passing",
    "brute_force",
    "kind_exact",
    "rank_key",
    "smallest_passing",
]


class FamilyKind(StrEnum):
    """The kind of a candidate's family; the order of the members is the tie order."""

    NODES = "nodes"  # a node selection (layers, laps) + modes (Craig-Bampton, ...)
    INTERFACE = "interface"  # a patch-radius set + modes by participation


_KIND_ORDER = {FamilyKind.NODES: 0, FamilyKind.INTERFACE: 1}


@dataclass(frozen=True)
class Candidate:
    """One reduced model of a selection study, a member of one family (module doc).

    Attributes:
        selection: node selection ``(layers, laps)`` (seed's i-j scheme), both >= 1; None for
            an interface candidate.
        modes: number of modes of the basis (>= 0).
        dof: number of generalised coordinates of the model (>= 1), the cost to minimise.
        patch_radii_m: the interface kind's patch-radius set [m] (distinct radii > 0, may be
            empty: modes only); None for a node selection.
        region: a region family of a mesh body (studies/region_families.py): ``("ball", radius_m)``
            or ``("set", node_set_name)``, a node family like ``selection`` (its DOF 3 x
            nodes + modes). Exactly one of ``selection``, ``patch_radii_m`` and ``region``
            is given.

    Raises:
        InputError: a field has the wrong type or range, or both or neither family is given.
    """

    selection: tuple[int, int] | None
    modes: int
    dof: int
    patch_radii_m: tuple[float, ...] | None = None
    region: tuple[str, float | str] | None = None

    def __post_init__(self) -> None:
        given = [v is not None for v in (self.selection, self.patch_radii_m, self.region)]
        if sum(given) != 1:
            raise InputError(
                f"Candidate selection {self.selection!r}, patch_radii_m {self.patch_radii_m!r}, "
                f"region {self.region!r}: expected exactly one (a node selection, an "
                "interface patch set or a region family)"
            )
        if self.region is not None:
            reg = tuple(self.region)
            ok = len(reg) == 2 and (
                (
                    reg[0] == "ball"
                    and isinstance(reg[1], float)
                    and math.isfinite(reg[1])
                    and reg[1] > 0
                )
                or (reg[0] == "set" and isinstance(reg[1], str) and reg[1])
            )
            if not ok:
                raise InputError(
                    f"Candidate region {self.region!r}: expected ('ball', radius "
                    "> 0 [m]) or ('set', node-set name)"
                )
            object.__setattr__(self, "region", reg)
        elif self.selection is not None:
            sel = tuple(self.selection)
            if len(sel) != 2 or not all(isinstance(v, int) and v >= 1 for v in sel):
                raise InputError(
                    f"Candidate selection {self.selection!r}: expected (layers, laps) >= 1"
                )
            object.__setattr__(self, "selection", sel)
        else:
            try:
                radii = tuple(float(a) for a in self.patch_radii_m or ())
            except (TypeError, ValueError):
                radii = (-1.0,)
            if not all(math.isfinite(a) and a > 0 for a in radii) or len(set(radii)) != len(radii):
                raise InputError(
                    f"Candidate patch_radii_m {self.patch_radii_m!r}: expected "
                    "distinct radii > 0 [m]"
                )
            object.__setattr__(self, "patch_radii_m", radii)
        if not isinstance(self.modes, int) or self.modes < 0:
            raise InputError(f"Candidate modes {self.modes!r}: expected an integer >= 0")
        if not isinstance(self.dof, int) or self.dof < 1:
            raise InputError(f"Candidate dof {self.dof!r}: expected an integer >= 1")

    @classmethod
    def interface(cls, patch_radii_m, modes: int) -> Candidate:
        """An interface candidate: one coordinate per patch vector and per mode."""
        radii = tuple(patch_radii_m)
        return cls(None, modes, len(radii) + modes, patch_radii_m=radii)

    @property
    def kind(self) -> FamilyKind:
        return FamilyKind.INTERFACE if self.patch_radii_m is not None else FamilyKind.NODES

    @property
    def family(self) -> tuple:
        """Sortable, hashable key of the family: (kind order, selection or patch radii)."""
        member = next(m for m in (self.selection, self.patch_radii_m, self.region) if m is not None)
        return (_KIND_ORDER[self.kind], member)

    @property
    def family_label(self) -> str:
        if self.selection is not None:
            return f"selection {self.selection}"
        if self.region is not None:
            what, value = self.region
            if what == "ball":
                return f"region ball {float(value) * 1e3:g} mm"
            return f"region set {value}"
        radii = self.patch_radii_m or ()
        return "patch set (" + ", ".join(f"{a * 1e3:g}" for a in radii) + ") mm"


def rank_key(candidate: Candidate, score: float) -> tuple:
    """Order of passing candidates, best first: fewer DOF, higher score, the node kind before
    the interface kind, fewer static coordinates (``dof - modes``), then the family and
    ``modes`` so the choice is deterministic."""
    kind, member = candidate.family
    return (candidate.dof, -score, kind, candidate.dof - candidate.modes, member, candidate.modes)


def _group(candidates: Sequence[Candidate]) -> dict[tuple, list[Candidate]]:
    """Candidates per family, sorted by modes; checks uniqueness and increasing DOF."""
    groups: dict[tuple, list[Candidate]] = {}
    for c in candidates:
        if not isinstance(c, Candidate):
            raise InputError(f"received {type(c).__name__}, expected Candidate objects")
        groups.setdefault(c.family, []).append(c)
    for items in groups.values():
        items.sort(key=lambda c: c.modes)
        for a, b in itertools.pairwise(items):
            if a.modes == b.modes:
                raise InputError(f"{a.family_label}: {a.modes} modes appears twice; expected once")
            if b.dof <= a.dof:
                raise InputError(
                    f"{a.family_label}: dof {a.dof} at {a.modes} modes but {b.dof} at "
                    f"{b.modes}; expected dof strictly increasing with modes"
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


class _FamilySearch:
    """Search for the first passing candidate of one family (module doc, strategy 3): the
    largest candidate under the DOF cap while none there is known to pass, then bisection.

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
        if self.hi >= cap:  # no pass known under the cap: its largest candidate decides
            return self.items[end - 1]
        return self.items[(self.lo + end) // 2]

    def record(self, candidate: Candidate, passed: bool) -> None:
        index = self.items.index(candidate)
        if passed:
            self.hi = index
        else:
            self.lo = index + 1


def best_passing(
    scores: dict[Candidate, float], passes: Callable[[float], bool], kind: FamilyKind | None = None
) -> Candidate | None:
    """The first passing candidate of ``scores`` by :func:`rank_key` (of ``kind`` only, if
    given), or None."""
    passing = [
        (rank_key(c, s), c)
        for c, s in scores.items()
        if (kind is None or c.kind is kind) and passes(s)
    ]
    return min(passing, key=lambda item: item[0])[1] if passing else None


def smallest_passing(
    candidates: Sequence[Candidate],
    evaluate: Callable[[Sequence[Candidate]], Sequence[float]],
    passes: Callable[[float], bool],
    *,
    max_open: int | None = None,
) -> tuple[Candidate | None, dict[Candidate, float]]:
    """The passing candidate of fewest DOF, found by a search per family (module doc).

    Args:
        candidates: the grid, node selections and/or interface patch sets; per family, unique
            mode counts with DOF strictly increasing.
        evaluate: scores of a batch of candidates, in order (e.g. NCC against the full FE
            force); called once per round with at most one candidate per open family.
        passes: whether a score reaches the target (e.g. ``lambda r: r >= 0.99``); must be
            monotone in the score for the search to be exact.
        max_open: number of families searched at once (None: all).

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
    queue = deque(sorted(groups, key=lambda fam: (groups[fam][0].dof, fam)))
    run = _Evaluator(evaluate)
    best_dof = math.inf
    searches: list[_FamilySearch] = []
    while queue or searches:
        while queue and (max_open is None or len(searches) < max_open):
            fam = queue.popleft()
            if groups[fam][0].dof <= best_dof:
                searches.append(_FamilySearch(groups[fam]))
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
    return best_passing(run.scores, passes), run.scores


def brute_force(
    candidates: Sequence[Candidate],
    evaluate: Callable[[Sequence[Candidate]], Sequence[float]],
    passes: Callable[[float], bool],
) -> tuple[Candidate | None, dict[Candidate, float]]:
    """Evaluate every candidate (one batch) and return the best passing one, ranked as in
    :func:`smallest_passing`, with all scores.

    The batch takes the families in turn (each one's fewest modes, then each one's next, ...),
    so that a cluster's workers start on different families: the cases of one node selection
    share one Craig-Bampton basis, built by the first of them that finds it missing from the
    setup cache, and two of them started together would both build it.

    Raises:
        InputError: as :func:`smallest_passing`.
    """
    groups = _group(candidates)
    run = _Evaluator(evaluate)
    families = [groups[fam] for fam in sorted(groups)]
    everything = [
        items[rank]
        for rank in range(max((len(g) for g in families), default=0))
        for items in families
        if rank < len(items)
    ]
    if everything:
        run(everything)
    return best_passing(run.scores, passes), run.scores


def kind_exact(
    kind: FamilyKind,
    winner: Candidate | None,
    scores: dict[Candidate, float],
    passes: Callable[[float], bool],
    candidates: Sequence[Candidate] | None = None,
) -> bool:
    """Whether ``best_passing(scores, passes, kind)`` (None if nothing of ``kind`` passed) is
    that kind's own answer over its whole grid, after :func:`smallest_passing` returned
    ``(winner, scores)`` for the grid ``candidates`` (module doc): true when no candidate
    passes at all, when the kind's best has the winner's DOF, or when nothing of ``kind``
    passed and none of its candidates has more DOF than the winner (the search covered them
    all); false otherwise (the search does not look past the winner's DOF; with
    ``candidates`` None the grid is taken to extend past it). After :func:`brute_force` every
    kind is exact."""
    if winner is None:
        return True
    own = [c.dof for c, s in scores.items() if c.kind is kind and passes(s)]
    if own:
        return min(own) == winner.dof
    return candidates is not None and all(c.dof <= winner.dof for c in candidates if c.kind is kind)
