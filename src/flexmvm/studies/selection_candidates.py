"""The candidates of a selection study (studies.selection module doc): its grid (node
selections of a rod, or region families of any body, x mode counts) and every candidate's
case, the interface kind's patch sets included."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

from flexmvm.scenarios import ModelKind, Scenario
from flexmvm.studies.grid import check_study_scheme
from flexmvm.studies.interface import interface_cases
from flexmvm.studies.node_grid import NodeGrid
from flexmvm.studies.region_families import RegionFamily, RegionGrid
from flexmvm.studies.runner import Case
from flexmvm.studies.search import Candidate

__all__ = ["candidate_cases", "study_grid"]


def study_grid(
    sc: Scenario,
    body: str,
    layers: Iterable[int],
    laps: Iterable[int],
    modes: Iterable[int],
    kind: ModelKind,
    regions: Sequence[RegionFamily] | None,
    centre_m: Sequence[float] | None,
) -> NodeGrid | RegionGrid:
    """The grid step: region families x ``modes`` (any body) with ``regions``, else the rod's
    ``layers`` x ``laps`` x ``modes``; checked against the mesh (InputError)."""
    if regions:
        check_study_scheme(sc, body)
        return RegionGrid(sc, body, regions, modes, centre_m, kind)
    return NodeGrid(sc, body, layers, laps, modes, kind, centre_m)


def candidate_cases(
    sc: Scenario,
    body: str,
    grid: NodeGrid | RegionGrid,
    hist: Path,
    patches: Sequence[Sequence[float]] | None,
    interface_modes: Iterable[int],
    where: dict,
    echo: Callable[[str], Any],
) -> tuple[dict[Candidate, Case], list[Case]]:
    """Every candidate's case against reference ``hist``: the grid's, then the interface
    kind's of ``patches`` x ``interface_modes`` (placed as ``where``; also returned apart)."""
    case_of = {grid.candidate(c): c for c in grid.cases(sc, hist)}
    t0 = time.perf_counter()
    if_cases = (
        interface_cases(sc, body, patches, interface_modes, reference=hist, **where)
        if patches
        else []
    )
    pools = sorted({c.params["mode_pool"] for c in if_cases} - {None})
    if pools:
        echo(
            f"interface kind: modes chosen from the lowest {', '.join(map(str, pools))} "
            f"free-free modes (mode_pool of every mode count of a patch set; "
            f"{time.perf_counter() - t0:.1f} s)"
        )
    for c in if_cases:
        case_of[Candidate.interface(c.params["patch_radii_m"], c.params["modes"])] = c
    return case_of, if_cases
