"""The a-priori estimate of a selection study: an MVM model of the study body from the 1D
wave(-Hertz) theory, without any FE time integration (studies/selection.py module doc)."""

from __future__ import annotations

import statistics
from collections.abc import Iterable, Sequence

import numpy as np

from flexmvm.errors import InputError
from flexmvm.metrics.ncc import Target
from flexmvm.scenarios import Scenario
from flexmvm.studies.grid import rod_of
from flexmvm.studies.report import target_dict


def estimate_selection(sc: Scenario, body: str, target: Target | None = None, *, k: float = 3.0,
                       modes: Sequence[int] = tuple(range(7, 44, 6))) -> dict:
    """A-priori MVM model of ``body`` without a full-FE run (module doc: the rule).

    Returns {layers, laps, nodes, modes, dof, f_max_hz, contact_duration_s, window_s,
    contact_radius_m, n_modes_below_f_max, rule}. ``target`` is recorded only: the rule does
    not depend on the NCC level (k sets the bandwidth).
    """
    from flexmvm.reduction.basis import BasisKind
    from flexmvm.scenarios.build import basis_for

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
    grid = sorted(int(m) for m in modes)
    basis = basis_for(cfg.rod.spec(), cfg.material_obj(), BasisKind.CRAIG_BAMPTON, sel,
                   grid[-1], cfg.model.reference)
    n_below = int(np.count_nonzero(basis.mode_freqs_hz < f_max))
    m = next((g for g in grid if g >= n_below), grid[-1])
    nodes = len(sel)
    return {"layers": 1, "laps": laps, "nodes": nodes, "modes": m, "dof": 3 * nodes + m,
            "f_max_hz": f_max, "k": k, "window_s": window, "n_modes_below_f_max": n_below,
            "grid_max_modes_insufficient": n_below > grid[-1],
            "first_mode_hz": float(basis.mode_freqs_hz[0]),
            "target": None if target is None else target_dict(target),
            **{f"theory_{k2}": v for k2, v in pulse.items()},
            "rule": "modes: fixed-interface modes below k/T_c (T_c = 1D wave-Hertz contact "
                    "duration clipped to the window), rounded up to the grid; nodes: layer 1, "
                    "the laps inside the Hertz contact radius at the window's peak force"}


def median_ncc(rows: Iterable[dict]) -> float:
    """Median force NCC of rows that have one (used to derive a target splitting a grid)."""
    vals = [r["ncc_force"] for r in rows if "ncc_force" in r]
    if not vals:
        raise InputError("no row has an NCC of the force")
    return float(statistics.median(vals))
