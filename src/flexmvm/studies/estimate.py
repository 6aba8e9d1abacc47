"""The a-priori estimate of a selection study, without any FE time integration, from the 1D
wave(-Hertz) theory of the scenario (flexmvm.theory.scenario.theory_pulse): an MVM model of the
study body (:func:`estimate_selection`, rule in studies/selection.py module doc) or an
interface model of it (:func:`estimate_interface`).

Interface rule (issue 12; reduction/interface.py): one patch vector at the Hertz contact
radius ``a`` of the theory at the window's peak force (the static response of the face to
the expected Hertz pressure), plus the free-free modes that this Hertz load excites (modal
force above EXCITED_RTOL of the largest, the participation choice's rule) with frequency
below ``f_max = k / T_c``, ``T_c`` the theory's contact duration clipped to the window (as
for node selections). On the seed case the rule gives a model of a few DOF whose force peak
is too high (docs/interface_basis.md): a starting point for ``--search``, not an answer.
"""

from __future__ import annotations

import statistics
from collections.abc import Iterable, Sequence

import numpy as np

from flexmvm.errors import InputError
from flexmvm.metrics.ncc import Target
from flexmvm.scenarios import Scenario
from flexmvm.studies.grid import rod_of
from flexmvm.studies.report import target_dict

__all__ = ["contact_surface", "estimate_interface", "estimate_selection", "median_ncc"]


def estimate_selection(
    sc: Scenario,
    body: str,
    target: Target | None = None,
    *,
    k: float = 3.0,
    modes: Sequence[int] = tuple(range(7, 44, 6)),
) -> dict:
    """A-priori MVM model of ``body`` without a full-FE run (module doc: the rule).

    Returns {layers, laps, nodes, modes, dof, f_max_hz, contact_duration_s, window_s,
    contact_radius_m, n_modes_below_f_max, rule}. ``target`` is recorded only: the rule does
    not depend on the NCC level (k sets the bandwidth).
    """
    from flexmvm.assembly.build_cache import default_setup
    from flexmvm.reduction.basis import BasisKind

    if not k > 0:
        raise InputError(f"k: expected a number > 0, got {k!r}")
    rod = rod_of(sc, body)
    from flexmvm.theory.scenario import theory_pulse

    pulse = theory_pulse(sc, body)
    window = min(pulse["contact_duration_s"], sc.time.t_end_s)
    f_max = k / window
    a = pulse["contact_radius_m"]
    face = np.flatnonzero(rod.node_layer == 1)
    X = rod.mesh.nodes
    r = np.hypot(X[face, 1], X[face, 2])
    laps = 1
    for j in range(2, rod.n_laps + 1):
        ring = r[rod.node_lap[face] == j]
        if ring.size and float(ring.min()) <= a:
            laps = j
    sel = tuple(int(i) for i in rod.selection(1, laps))
    cfg = sc.body(body)
    if cfg.rod is None:
        raise InputError(f"body {body!r}: the modal estimate needs a rod body")
    grid = sorted(int(m) for m in modes)
    basis = default_setup().basis(
        cfg.rod.spec(),
        cfg.material_obj(),
        BasisKind.CRAIG_BAMPTON,
        sel,
        grid[-1],
        cfg.model.reference,
    )
    n_below = int(np.count_nonzero(basis.mode_freqs_hz < f_max))
    m = next((g for g in grid if g >= n_below), grid[-1])
    nodes = len(sel)
    return {
        "layers": 1,
        "laps": laps,
        "nodes": nodes,
        "modes": m,
        "dof": 3 * nodes + m,
        "f_max_hz": f_max,
        "k": k,
        "window_s": window,
        "n_modes_below_f_max": n_below,
        "grid_max_modes_insufficient": n_below > grid[-1],
        "first_mode_hz": float(basis.mode_freqs_hz[0]),
        "target": None if target is None else target_dict(target),
        **{f"theory_{k2}": v for k2, v in pulse.items()},
        "rule": "modes: fixed-interface modes below k/T_c (T_c = 1D wave-Hertz contact "
        "duration clipped to the window), rounded up to the grid; nodes: layer 1, "
        "the laps inside the Hertz contact radius at the window's peak force",
    }


def contact_surface(sc: Scenario, body: str) -> str:
    """The facet set of ``body`` in its (first) contact."""
    for c in sc.contacts:
        if body in (c.slave_body, c.master_body):
            return c.slave_surface if c.slave_body == body else c.master_surface
    raise InputError(f"body {body!r} is in no contact of the scenario; the estimate needs one")


def estimate_interface(
    sc: Scenario,
    body: str,
    target: Target | None = None,
    *,
    k: float = 3.0,
    modes: Sequence[int] | None = None,
) -> dict:
    """A-priori interface model of ``body`` without a full-FE run (module doc: the rule):
    ``fm.interface(est["patch_radii_m"], est["modes"])``, patch about the centre of the body's
    contact surface.

    Args:
        sc, body: the scenario and the study body (a rod in a rod-on-rod contact, as the 1D
            theory needs).
        target: recorded only; the rule does not depend on the NCC level.
        k: bandwidth factor, f_max = k / T_c (> 0).
        modes: a grid of mode counts (e.g. ``--interface-modes``): the count is rounded up to
            it (the grid's largest if none is enough: ``grid_max_modes_insufficient``); None
            keeps the count of modes below f_max.

    Returns:
        {patch_radii_m: [a], modes, dof (= 1 + modes), n_modes_below_f_max, mode_freqs_hz (of
        those), kept_mode_freqs_hz (what the participation choice keeps for ``modes``),
        keeps_modes_below_f_max, f_max_hz, k, window_s, patch_surface,
        grid_max_modes_insufficient, target, theory_<key> (theory_pulse), rule}.

    Raises:
        InputError: k <= 0, an empty grid, an unknown body, no rod-on-rod contact of the body,
            or a flat-on-flat contact (St Venant: the theory gives no Hertz radius).
    """
    from flexmvm.theory.scenario import theory_pulse

    if not k > 0:
        raise InputError(f"k: expected a number > 0, got {k!r}")
    grid = None if modes is None else sorted({int(m) for m in modes})
    if grid is not None and (not grid or grid[0] < 0):
        raise InputError(f"modes: expected a grid of mode counts >= 0, got {modes!r}")
    cfg = sc.body(body)
    pulse = theory_pulse(sc, body)
    a = float(pulse["contact_radius_m"])
    if not a > 0:
        raise InputError(
            f"body {body!r}: the 1D theory gives no Hertz contact radius "
            f"(law {pulse['law']}, flat on flat); the interface rule needs one"
        )
    window = min(pulse["contact_duration_s"], sc.time.t_end_s)
    f_max = k / window
    surface = contact_surface(sc, body)
    freqs, kept, m = _interface_modes(cfg, surface, a, f_max, grid)
    n_below = int(freqs.size)
    return {
        "patch_radii_m": [a],
        "modes": m,
        "dof": 1 + m,
        "n_modes_below_f_max": n_below,
        "mode_freqs_hz": [float(f) for f in freqs],
        "kept_mode_freqs_hz": [float(f) for f in kept],
        "keeps_modes_below_f_max": bool(all(np.any(np.abs(kept - f) <= 1e-6 * f) for f in freqs)),
        "f_max_hz": f_max,
        "k": k,
        "window_s": window,
        "patch_surface": surface,
        "grid_max_modes_insufficient": grid is not None and n_below > grid[-1],
        "target": None if target is None else target_dict(target),
        **{f"theory_{k2}": v for k2, v in pulse.items()},
        "rule": "one patch vector at the 1D wave-Hertz contact radius at the window's peak "
        "force; the free-free modes that Hertz load excites below k/T_c (T_c = "
        "contact duration clipped to the window), rounded up to the grid if given",
    }


def _interface_modes(cfg, surface: str, a: float, f_max: float, grid: list[int] | None):
    """(freqs [Hz] of the free-free modes the Hertz load of radius a [m] on ``surface``
    excites below f_max [Hz], kept [Hz]: those the participation choice keeps for the count
    m, m: that count, rounded up to ``grid`` (its largest if none is enough)) of body cfg."""
    from flexmvm.assembly.build_cache import default_setup
    from flexmvm.reduction.interface import (
        InterfaceSpec,
        chosen_modes,
        contact_patch,
        excited_modes_below,
        hertz_load,
    )

    # the setup cache's mode pools, shared with the bases
    fe, free = default_setup().free_modes_source(cfg)
    patch = contact_patch(fe.mesh, surface)
    load = hertz_load(fe.mesh, surface, patch, a)
    freqs, _ = excited_modes_below(fe, load, f_max, free=free)
    n_below = int(freqs.size)
    m = n_below if grid is None else next((g for g in grid if g >= n_below), grid[-1])
    kept = np.zeros(0)
    if m:
        kept = chosen_modes(fe, InterfaceSpec(surface, None, (a,)), m, load, free)[1]
    return freqs, kept, m


def median_ncc(rows: Iterable[dict]) -> float:
    """Median force NCC of rows that have one (used to derive a target splitting a grid)."""
    vals = [r["ncc_force"] for r in rows if "ncc_force" in r]
    if not vals:
        raise InputError("no row has an NCC of the force")
    return float(statistics.median(vals))
