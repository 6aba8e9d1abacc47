"""A scenario body as a moving region (issue 53 item 1; integrate/moving_region.py,
reduction/kinds/mvm_moving.py): ``model.kind = "mvm-moving"`` with ``[bodies.model.moving]``
(scenarios/moving_schema.py). Its FE model and reference condition (its supports, or its
reference) come from the setup cache, the windows are made along the node set ``path`` and
the body starts on the window nearest its first contact (the path's start by default);
build_scenario keeps the MovingRegion as the run's ``switches`` (simulate); several moving
bodies, one MovingRegions over their regions (``driver_hook``)."""

from __future__ import annotations

import time

import numpy as np

from flexmvm.assembly.body_build import BodyInfo
from flexmvm.assembly.body_reference import reference_label
from flexmvm.assembly.build_cache import SetupCache
from flexmvm.assembly.cache_keys import mesh_key, mesh_source
from flexmvm.assembly.supports import bedded_key, clamp_label
from flexmvm.errors import InputError, MeshError
from flexmvm.integrate.moving_region import MovingRegion, MovingRegions
from flexmvm.reduction.kinds.mvm_moving import (
    GlobalFactor,
    MovingWindows,
    basis_signature,
    moving_windows,
)
from flexmvm.setup_cache.moving_entries import (
    StoredWindows,
    load_moving,
    moving_key,
    save_moving,
)


def moving_setup(cfg, supports, setup) -> MovingWindows:
    """The windows of body ``cfg`` (its model's ``moving`` and ``modes``) on its FE model
    under its supports' condition (or its reference's), through ``setup``."""
    return _windows(cfg, supports, setup)[0]


def _windows(cfg, supports, setup) -> tuple[MovingWindows, str | None, StoredWindows | None]:
    """(windows, the setup-cache entry's key (None: not cached), the entry when stored):
    moving_setup's windows, their factor from the entry when there is one."""
    mv, where = cfg.model.moving, f"bodies[{cfg.name}].model.moving"
    mesh = setup.mesh(mesh_key(cfg))
    fe_key = bedded_key(mesh_key(cfg), cfg, supports)
    fe = setup.fe_model(fe_key, cfg.material_obj())
    label = clamp_label(cfg, mesh, supports) or reference_label(
        cfg.model.reference, mesh, (), f"bodies[{cfg.name}].model.reference"
    )
    reference = setup.reference_condition(fe_key, mesh, label)
    try:
        path = mesh.node_set(mv.path)
    except MeshError as exc:
        raise InputError(f"{where}.path: {exc}") from None
    source, modes = mesh_source(fe_key), cfg.model.modes
    key = None
    if source is not None:
        shape = {"spacing_m": mv.spacing_m, "half_width_m": mv.half_width_m}
        shape["s_range_m"] = None if mv.s_range_m is None else list(mv.s_range_m)
        held = reference.fixed_dofs
        key = moving_key(source, cfg.material_obj(), label, held, path, modes, shape)
    stored = None if key is None else load_moving(key, fe.n_dof, modes)
    factor = None
    if stored is not None:
        factor = GlobalFactor.stored(fe, reference, stored.phi, stored.freqs_hz, stored.columns)
    windows = moving_windows(
        fe, reference, path, modes, mv.spacing_m, mv.half_width_m, mv.s_range_m, factor
    )
    return windows, key, stored


def moving_body(cfg, supports, setup, index: int, start_s: float | None = None):
    """(the first window's body, its MovingRegion) of body ``cfg``, the ``index``-th of its
    scenario (the region's ``setup_cpu_s``: CPU [s]). Made now: every window's basis and parts,
    stored in the setup cache's ``moving-`` entry (setup_cache/moving_entries.py), then the
    statics released; from a stored entry: the parts read, the first window's basis made, and
    each other window's when the contact first reaches it (from the stored static columns,
    kept: one revolution of the cam visits 14 of its follower's 24 windows)."""
    c0 = time.process_time()
    windows, key, stored = _windows(cfg, supports, setup)
    start = 0 if start_s is None else windows.nearest(start_s)
    region = MovingRegion(index, windows, cfg.name, start, cfg.model.moving.outside)
    if stored is not None:
        region.parts.update(stored.parts)
        region.signatures.update(stored.signatures)
    else:
        for k in range(len(windows.centres)):
            region.body(k)
        if key is not None:
            f, n = windows.factor, len(windows.centres)
            signatures = {k: basis_signature(windows.basis(k).psi) for k in range(n)}
            save_moving(key, f.phi, f.freqs_hz, f.columns, region.parts, signatures)
        windows.factor.release()  # every window made: the run needs no more statics
    body = region.body(start)
    region.setup_cpu_s = time.process_time() - c0
    return body, region


def covered_nodes(region: MovingRegion, path_nodes: np.ndarray) -> np.ndarray:
    """The nodes the windows cover together and the path's held nodes (on a support, left out
    of the windows) within the covered interval: the validity guard's covered nodes."""
    w = region.windows
    X = w.factor.fe.mesh.nodes[path_nodes]
    s = (X - w.path.origin) @ w.path.axis
    lo, hi = w.covered
    held = path_nodes[(s >= lo) & (s <= hi) & ~np.isin(path_nodes, w.path.nodes)]
    return np.unique(np.concatenate([held, *(w.nodes(k) for k in range(len(w.centres)))]))


def moving_body_info(cfg, sc, setup: SetupCache, index: int):
    """(body, BodyInfo, MovingRegion) of the moving region ``cfg``, the index-th body of
    scenario ``sc``."""
    body, region = moving_body(cfg, sc.supports, setup, index)
    mesh = setup.mesh(mesh_key(cfg))
    covered = covered_nodes(region, mesh.node_set(cfg.model.moving.path))
    info = BodyInfo(
        cfg.name,
        cfg.model.kind,
        mesh,
        cfg.material_obj(),
        body.nv,
        len(covered),
        cfg.model.modes,
        None,
        covered,
    )
    return body, info, region


def driver_hook(regions: list[MovingRegion]) -> MovingRegion | MovingRegions | None:
    """The run's ``switches``: None without a moving region, the region itself for one (its
    switches, centres and guard read off it), MovingRegions over several."""
    if not regions:
        return None
    return regions[0] if len(regions) == 1 else MovingRegions(regions)
