"""The validity checks of a run: the guard of reduced bases (issue 12, part 3) and the energy
rise of a run beyond the work of its loads and drives (issue 12, part 4).

A reduced basis leaves the contact free only where it was built for it: the retained nodes of
an MVM model (Craig-Bampton, seed eq. 4), the contact patch (the patch surface's nodes within
the largest patch radius) of an interface model. Elsewhere on the surface a node moves only
as its constraint modes, patch vectors and modes let it, and a contact there meets a
surface the basis holds stiff. After a run, the guard adds up the normal contact impulse
each row carried (RunResult.contact_row_impulses: the driver's per-row record), assigns it
to the nodes of each body it acted on (the slave node; a master facet's nodes, equal
shares) and reports per guarded body the fraction carried outside the covered nodes, the
first time that happened and a model that would cover the loaded nodes: for a rod the
smallest i-j selection holding them, for an interface model the patch radius reaching them,
otherwise a ball region around them.
"""

from __future__ import annotations

import numpy as np

from flexmvm.results.summary_keys import with_current_keys

#: A guarded body whose contact impulse falls outside its covered nodes by more than this
#: fraction of its total contact impulse gets a console warning (the record is always kept).
WARN_FRACTION = 0.01


def _node_impulses(result, system) -> dict[int, dict[int, list[float]]]:
    """body index -> {node: [impulse [N s], first time [s]]} from the per-row record."""
    providers = {c.name: c for c in system.contacts}
    out: dict[int, dict[int, list[float]]] = {}

    def add(body: int, node: int, x: float, t: float) -> None:
        entry = out.setdefault(body, {}).get(node)
        if entry is None:
            out[body][node] = [x, t]
        else:
            entry[0] += x
            entry[1] = min(entry[1], t)

    for key, (x, t) in result.contact_row_impulses.items():
        c = providers.get(key[0])
        if c is None:
            continue
        add(int(c.slave), int(key[1]), x, t)
        facet = np.unique(c.surface.connectivity[int(key[2])])
        for node in facet:
            add(int(c.master), int(node), x / len(facet), t)
    return out


def _suggestion(info, loaded: np.ndarray) -> str:
    """A model of body ``info`` covering the nodes ``loaded``."""
    X = info.mesh.nodes[loaded]
    if info.patch is not None:
        from flexmvm.reduction.interface import tangent_distance

        r = float(tangent_distance(X, info.patch).max())
        return (
            f"patch_radii_m reaching {r:.3g} m (the loaded nodes' distance from the patch centre)"
        )
    if info.rod is not None:
        i = int(info.rod.node_layer[loaded].max())
        j = int(info.rod.node_lap[loaded].max())
        return f"selection = '{i}-{j}'"
    c = X.mean(axis=0)
    r = float(np.linalg.norm(X - c, axis=1).max())
    return f"region ball centre_m = [{c[0]:.4g}, {c[1]:.4g}, {c[2]:.4g}], radius_m = {r:.3g}"


def contact_guard(result, built) -> dict:
    """{body name: {model, covered_nodes, contact_impulse_Ns, impulse_fraction_outside,
    first_outside_t_s, nodes_loaded, nodes_loaded_outside, cover}} for every guarded body
    (an MVM or interface model) that carried contact; cover: a model that would hold every
    loaded node free (None when none was outside)."""
    per_body = _node_impulses(result, built.system)
    report = {}
    for b, info in enumerate(built.info):
        if info.covered_nodes is None or b not in per_body:
            continue
        nodes = np.array(sorted(per_body[b]), dtype=np.int64)
        x = np.array([per_body[b][k][0] for k in nodes])
        t = np.array([per_body[b][k][1] for k in nodes])
        outside = ~np.isin(nodes, info.covered_nodes)
        total = float(x.sum())
        frac = float(x[outside].sum() / total) if total > 0 else 0.0
        report[info.name] = {
            "model": info.model.value,
            "covered_nodes": len(info.covered_nodes),
            "contact_impulse_Ns": total,
            "impulse_fraction_outside": frac,
            "first_outside_t_s": float(t[outside].min()) if outside.any() else None,
            "nodes_loaded": len(nodes),
            "nodes_loaded_outside": int(outside.sum()),
            "cover": _suggestion(info, nodes) if outside.any() else None,
        }
    return report


def outside_fraction(summary: dict, body: str) -> float | None:
    """The guarded ``body``'s fraction of contact impulse outside its covered nodes in a run's
    summary (None: not guarded, or no contact)."""
    g = summary.get("reduced_contact_guard", {}).get(body)
    return None if g is None else float(g["impulse_fraction_outside"])


def outside_validity(fraction: float | None, threshold: float = WARN_FRACTION) -> bool:
    """True if a run whose guard fraction is ``fraction`` is outside its model's validity
    (the fraction exceeds ``threshold``; None, unguarded or unknown, is not)."""
    return fraction is not None and fraction > threshold


#: A run whose total energy rises above its start, beyond the work of its loads, drives and
#: spin (runs.run.energy_gain), by more than this share gets a warning. Nothing in it can add energy: the Moreau-Jean step with theta >= 1/2
#: and frictionless or Coulomb contact, joints and gravity (in the potential) keep or lose it;
#: what could was the velocity law's penetration recovery when it pushed a penetrated node out
#: at beta (-g) / h whatever its mass: on reduced bodies whose contact reached the edge of the
#: retained nodes it fed chatter (PA6 on 1-4 gained 2.6 %), and it lifted clean runs' energy by
#: up to 1.3e-3 against 1.1e-2 to 5.6 in those that chattered (docs/notes: the material study
#: before the cap); capped by the pair's closing speed (contact/pairs.py) it adds none. 0.5 %
#: lies between: a gain above it is a defect to report, not round-off.
ENERGY_GAIN_WARN = 5e-3


#: A run whose step adds no energy (every contact on the position law, theta >= 1/2: summary
#: ``contact_laws_add_no_energy``) that gains more than this is warned of: its stable runs
#: measured at theta = 1/2 kept the energy to 1e-6 of the start, the unstable ones (both rods
#: Craig-Bampton below h = 0.5 us) gained 4.6e-4 and more (docs/contact_law.md).
CONSERVING_ENERGY_GAIN_WARN = 1e-4


def energy_gain_warning(summary: dict, threshold: float = ENERGY_GAIN_WARN) -> str | None:
    """The console line for a run whose energy rose by more than ``threshold`` (by more than
    CONSERVING_ENERGY_GAIN_WARN for an energy-conserving scheme), or None."""
    gain = summary.get("energy_gain_rel_max")
    if gain is None:
        return None
    summary = with_current_keys(summary)  # a stored summary may have the old key
    if summary.get("contact_laws_add_no_energy") and gain > min(
        threshold, CONSERVING_ENERGY_GAIN_WARN
    ):
        return (
            f"the total energy rose by {100 * gain:.2g} % of its start with every contact "
            "on the position law, whose step adds none (~1e-6 at theta = 1/2): an "
            "alternation at the step's scale grew (as both rods Craig-Bampton did below "
            "h = 0.5 us before closed pairs kept their geometry, docs/contact_law.md); "
            "damp it: a shorter time.hf_damping_time_s, or theta = 0.55"
        )
    if gain <= threshold:
        return None
    return (
        f"the total energy rose by {100 * gain:.2g} % of its start beyond the work of the "
        "loads and drives: the contact added energy (penetration recovery pushing penetrated nodes "
        'out, chatter); try penetration_recovery = 0 on the contact, law = "position", or '
        "a reduced model covering the contact patch with a ring to spare"
    )


#: The entries validity_fields adds to a study row (and its CSV columns), in column order.
VALIDITY_KEYS = ("guard_outside_fraction", "energy_gain_rel_max", "plastic_cells_outside")


def plastic_cells_outside(summary: dict, body: str) -> int | None:
    """The most cells of the reduced plastic ``body`` outside its retained region that reached
    the yield stress in one step (summary ``plastic.<body>.cells_yield_outside_retained``,
    runs.plastic_summary); None: not a plastic body (0 for a full-FE one: it retains all)."""
    entry = summary.get("plastic", {}).get(body)
    if entry is None or "cells_yield_outside_retained" not in entry:
        return None
    return int(entry["cells_yield_outside_retained"])


def validity_fields(summary: dict, body: str) -> dict:
    """A study row's validity entries (VALIDITY_KEYS) from a run's summary:
    guard_outside_fraction (of ``body``), energy_gain_rel_max (None: unknown, or a run with
    applied loads) and plastic_cells_outside (of ``body``, None: not a reduced plastic body)."""
    return dict(
        zip(
            VALIDITY_KEYS,
            (
                outside_fraction(summary, body),
                summary.get("energy_gain_rel_max"),
                plastic_cells_outside(summary, body),
            ),
            strict=True,
        )
    )


def invalid_reason(row: dict) -> str | None:
    """Why a study row (validity_fields) is outside its model's validity, or None: contact
    on nodes the basis holds stiff above WARN_FRACTION of the impulse, an energy rise
    above ENERGY_GAIN_WARN (chatter), or a reduced plastic body whose cells outside the
    retained region reached the yield stress (the plastic guard: its zone left the region,
    where the linear rest cannot yield). Missing entries (rows stored before the checks
    existed) pass."""
    frac = row.get("guard_outside_fraction")
    if frac is not None and outside_validity(frac):
        return f"guard: {100 * frac:.0f} % of the contact impulse on nodes held stiff"
    cells = row.get("plastic_cells_outside")
    if cells is not None and int(cells) > 0:
        return f"plastic guard: {int(cells)} cells outside the retained region reached yield"
    gain = row.get("energy_gain_rel_max")
    if gain is not None and gain > ENERGY_GAIN_WARN:
        return f"energy rose by {100 * gain:.2g} % (chatter)"
    return None


def guard_warnings(report: dict, threshold: float = WARN_FRACTION) -> list[str]:
    """One line per guarded body whose outside fraction exceeds ``threshold``."""
    lines = []
    for name, g in report.items():
        if g["impulse_fraction_outside"] > threshold:
            lines.append(
                f"body {name} ({g['model']}): {100 * g['impulse_fraction_outside']:.1f} % of "
                f"its contact impulse fell on {g['nodes_loaded_outside']} surface node(s) the "
                f"reduced basis holds stiff, first at t = {g['first_outside_t_s']:.3g} s; "
                f"the run is outside the model's validity; cover at least the loaded nodes: "
                f"{g['cover']} (summary.json reduced_contact_guard)"
            )
    return lines


__all__ = [
    "CONSERVING_ENERGY_GAIN_WARN",
    "ENERGY_GAIN_WARN",
    "VALIDITY_KEYS",
    "WARN_FRACTION",
    "contact_guard",
    "energy_gain_warning",
    "guard_warnings",
    "invalid_reason",
    "outside_fraction",
    "outside_validity",
    "plastic_cells_outside",
    "validity_fields",
]
