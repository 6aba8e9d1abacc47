"""The studies as library calls: a Scenario (or a scenario file) in, a table out, nothing
written unless a directory is given. The cases are stored as the command line stores them
(``DIR/cases/<key>.json``, resumable); without ``out_dir`` they go to a temporary directory
removed at the end."""

from __future__ import annotations

import contextlib
import dataclasses
import tempfile
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from flexmvm.metrics.ncc import Target
from flexmvm.scenarios import ModelKind, Scenario, load_scenario
from flexmvm.studies import materials as material_studies
from flexmvm.studies.main_guard import in_process_by_default
from flexmvm.studies.materials import SEED_ORDER, MaterialStudy
from flexmvm.studies.options import BasisSpec, StudyOptions, split_settings, with_settings
from flexmvm.studies.region_families import RegionFamily
from flexmvm.studies.selection import SelectionStudy, select_models

__all__ = ["material_study", "select"]


@contextlib.contextmanager
def _directory(out_dir: str | Path | None) -> Iterator[Path]:
    if out_dir is not None:
        yield Path(out_dir)
        return
    with tempfile.TemporaryDirectory(prefix="flexmvm-study-") as tmp:
        yield Path(tmp)


def _scenario(scenario: Scenario | str | Path) -> Scenario:
    return scenario if isinstance(scenario, Scenario) else load_scenario(scenario)


def select(
    scenario: Scenario | str | Path,
    body: str,
    *,
    basis: BasisSpec | None = None,
    target: Target | float = 0.99,
    search: bool = False,
    out_dir: str | Path | None = None,
    options: StudyOptions | None = None,
    **settings: Any,
) -> SelectionStudy:
    """Selection study of ``body`` (studies/selection.py): every ``layers`` x ``laps`` x
    ``modes`` Craig-Bampton model of it against its full-FE reference, the other bodies as in
    the scenario (``kind``: the candidates' model, Craig-Bampton by default, or the seed's
    eq. (4) readings mvm-seed / mvm-seed-fixed). ``target``: a Target or the force NCC to
    reach; ``search``: the pruned search instead of the whole grid. Runs on a local Dask
    cluster of ``workers`` processes (default: one per core), on ``scheduler``, or in this
    process with ``serial``; called from a script without ``if __name__ == "__main__":``
    with neither ``workers`` nor ``scheduler`` given, in this process too, with a one-line
    InProcessStudyWarning saying what to add (spawned workers would re-run the script).
    ``patches`` (patch-radius sets [m]) adds the interface kind's
    grid patches x ``interface_modes`` (``interface_rows``; summary ``interface`` and
    ``best_overall``), in the same brute force or the same search as the node selections.
    A body of any mesh: ``radii_m`` (ball radii [m] about ``centre_m``, default the body's
    region ball centre or the expected contact point, studies/region_families.py) and/or
    ``node_sets`` (node-set names of its mesh) replace ``layers`` x ``laps``; rows then carry
    ``region``. ``patch_surface``: the facet set of the interface kind's patches (default: a
    mesh body's contact surface, about the regions' centre).
    The candidates are ``basis`` (studies.options.BasisSpec) and where they run ``options``
    (studies.options.StudyOptions; no progress bars by default); every name above but
    ``radii_m``, ``node_sets`` and ``workers`` (StudyOptions' n_workers) is one of their
    fields, given as a keyword argument (``settings``) over the objects' own.
    Returns the table (``rows``), the smallest model reaching the
    target (``best``) and the summary."""
    settings = dict(settings)
    if "workers" in settings:
        settings["n_workers"] = settings.pop("workers")
    radii_m, node_sets = settings.pop("radii_m", None), settings.pop("node_sets", None)
    run_kw, basis_kw = split_settings(settings, "select")
    opts = with_settings(options, StudyOptions(), run_kw, "select")
    target = target if isinstance(target, Target) else Target(float(target))
    serial = in_process_by_default(opts.scheduler, opts.n_workers, opts.serial)
    regions = (
        [RegionFamily(radius_m=float(r)) for r in radii_m or ()]
        + [RegionFamily(node_set=str(n)) for n in node_sets or ()]
    ) or None
    if regions is not None:
        basis_kw["regions"] = regions
    spec = with_settings(basis, BasisSpec(), basis_kw, "select")
    with _directory(out_dir) as out:
        return select_models(
            _scenario(scenario),
            body,
            out,
            spec,
            target,
            search,
            dataclasses.replace(opts, serial=serial),
        )


def material_study(
    scenario: Scenario | str | Path,
    body: str = "b2",
    *,
    materials: Iterable[str] = SEED_ORDER,
    selections: Sequence[tuple[int, int]] | str = ((1, 1), (2, 2)),
    modes: Iterable[int] = range(7, 44, 12),
    out_dir: str | Path | None = None,
    kind: ModelKind | str = ModelKind.MVM,
    options: StudyOptions | None = None,
    **settings: Any,
) -> MaterialStudy:
    """Material study (studies/materials.py): ``body`` made of each of ``materials`` (keys of
    SEED_MATERIALS: W, Cu, Al, PA6), each ``kind`` model (Craig-Bampton by default, or the
    seed's eq. (4) readings mvm-seed / mvm-seed-fixed) of ``selections`` x ``modes`` against
    that material's full-FE reference. Returns the rows and the summary (per-material mean
    NCC, the seed's ordering); where it runs as :func:`select` (``options``, or ``workers``,
    ``scheduler``, ``serial``, ``progress`` as keyword arguments)."""
    settings = dict(settings)
    if "workers" in settings:
        settings["n_workers"] = settings.pop("workers")
    opts = with_settings(options, StudyOptions(), settings, "material_study")
    serial = in_process_by_default(opts.scheduler, opts.n_workers, opts.serial)
    with _directory(out_dir) as out:
        return material_studies.material_study(
            _scenario(scenario),
            out,
            body,
            materials,
            selections,
            modes,
            kind,
            dataclasses.replace(opts, serial=serial),
        )
