"""Option objects of the studies: where the cases run and how the runs are set
(:class:`StudyOptions`, shared by the selection and the material studies and by the study
commands' --scheduler, --workers, --serial, --t-end, --dt, --other, --progress), and the
candidate reduced bases of a selection study (:class:`BasisSpec`). The entry points take these
two frozen objects instead of twenty parameters; :func:`with_settings` still accepts their
fields as keyword arguments (the calls written before them keep working)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

from flexmvm.scenarios import ModelKind
from flexmvm.studies.region_families import RegionFamily

__all__ = ["BasisSpec", "StudyOptions", "split_settings", "with_settings"]


@dataclass(frozen=True)
class StudyOptions:
    """Where a study's cases run and how its runs are set. ``scheduler``: address of a Dask
    scheduler; otherwise a LocalCluster of ``n_workers`` processes (default one per core), or
    this process with ``serial``. ``progress``: progress bars. ``t_end_s``, ``dt_s`` [s]
    override the scenario's end time and contact step and ``other`` the model of the other
    bodies (studies.grid.study_scenario). ``echo``: the console lines (None: none; a stored
    reference or case recomputed is then a warning)."""

    scheduler: str | None = None
    n_workers: int | None = None
    serial: bool = False
    progress: bool = False
    t_end_s: float | None = None
    dt_s: float | None = None
    other: str | None = None
    echo: Callable[[str], Any] | None = None


@dataclass(frozen=True)
class BasisSpec:
    """The candidate reduced bases of a selection study (studies/selection.py): the ``kind``
    model (Craig-Bampton by default, or the seed's eq. (4) readings) of ``layers`` x ``laps``
    node selections, or of the region families ``regions`` (ball radii about ``centre_m`` or
    node sets, studies/region_families.py), x ``modes`` mode counts; ``patches`` (patch-radius
    sets [m]) adds the interface kind's patches x ``interface_modes`` on ``patch_surface``."""

    layers: Iterable[int] = range(1, 5)
    laps: Iterable[int] = range(1, 6)
    modes: Iterable[int] = range(7, 44, 6)
    kind: ModelKind | str = ModelKind.MVM
    patches: Sequence[Sequence[float]] | None = None
    interface_modes: Iterable[int] = (5, 10, 20)
    regions: Sequence[RegionFamily] | None = None
    centre_m: Sequence[float] | None = None
    patch_surface: str | None = None


_T = TypeVar("_T", StudyOptions, BasisSpec)


def _names(cls: type) -> set[str]:
    return {f.name for f in dataclasses.fields(cls)}


def split_settings(settings: Mapping[str, Any], where: str) -> tuple[dict, dict]:
    """({StudyOptions field: value}, {BasisSpec field: value}) of keyword arguments given by
    name; TypeError, as Python's own, for a name of neither."""
    unknown = sorted(set(settings) - _names(StudyOptions) - _names(BasisSpec))
    if unknown:
        raise TypeError(f"{where}() got an unexpected keyword argument {unknown[0]!r}")
    run = {k: v for k, v in settings.items() if k in _names(StudyOptions)}
    return run, {k: v for k, v in settings.items() if k not in run}


def with_settings(obj: _T | None, default: _T, settings: Mapping[str, Any], where: str) -> _T:
    """``obj`` (``default`` if None) with the fields ``settings`` names replaced; TypeError for
    another object or a name that is not one of its fields."""
    base = default if obj is None else obj
    if not isinstance(base, type(default)):
        raise TypeError(
            f"{where}(): expected a {type(default).__name__}, got {type(base).__name__} "
            "(the grid and run settings are keyword arguments or option objects)"
        )
    unknown = sorted(set(settings) - _names(type(default)))
    if unknown:
        raise TypeError(f"{where}() got an unexpected keyword argument {unknown[0]!r}")
    return dataclasses.replace(base, **settings) if settings else base
