"""The summary entries of a run's plastic bodies (integrate.plastic_bodies): peak equivalent
plastic strain, plastic work, stored hardening energy and the permanent indentation.

The permanent indentation is read on the body's residual field (PlasticReport.
residual_displacement: the static displacement its final plastic strain leaves with no load,
no vibration, relative to its reference condition) at the surface node that carried the
largest contact impulse, along the inward normal of the body's surface there (the mean of the
normals of its facet sets' facets at the node, turned away from the body's centroid): > 0 is
a dent.
"""

from __future__ import annotations

import numpy as np


def _loaded_node(res, system, b: int) -> int | None:
    """The node of body b that carried the largest compressive contact impulse (as a slave
    node, or an equal share of a master facet), None if none."""
    providers = {c.name: c for c in system.contacts}
    impulse: dict[int, float] = {}
    for key, (x, _) in res.contact_row_impulses.items():
        c = providers.get(key[0])
        if c is None:
            continue
        if int(c.slave) == b:
            impulse[int(key[1])] = impulse.get(int(key[1]), 0.0) + x
        if int(c.master) == b:
            facet = np.unique(c.surface.connectivity[int(key[2])])
            for node in facet:
                impulse[int(node)] = impulse.get(int(node), 0.0) + x / len(facet)
    return max(impulse, key=lambda node: impulse[node]) if impulse else None


def inward_normal(mesh, node: int) -> np.ndarray | None:
    """Unit normal (3,) into the body at a surface node: the mean of the normals of the facet
    sets' facets (their corner nodes) holding it, turned away from the body's centroid; None
    if no facet set holds it."""
    X = mesh.nodes
    centre = X.mean(axis=0)
    total = np.zeros(3)
    for fs in mesh.facet_sets.values():
        for facets, corners in ((fs.tris, 3), (fs.quads, 4)):
            held = facets[np.any(facets == node, axis=1)]
            for f in held:
                p = X[f[:corners]]
                n = np.cross(p[1] - p[0], p[2] - p[0])
                n /= np.linalg.norm(n)
                total += n if n @ (p[0] - centre) < 0 else -n
    norm = np.linalg.norm(total)
    return total / norm if norm > 0 else None


def plastic_summary(res, built) -> dict:
    """{"plastic": {body: {...}}} for a run with plastic bodies, {} otherwise (module doc)."""
    if not res.plastic:
        return {}
    names = [b.name for b in built.system.bodies]
    out = {}
    for name, rep in res.plastic.items():
        b = names.index(name)
        node = _loaded_node(res, built.system, b)
        normal = None if node is None else inward_normal(built.info[b].mesh, node)
        dent = None
        if normal is not None and node is not None:
            dent = float(normal @ rep.residual_displacement[3 * node : 3 * node + 3])
        out[name] = {
            "peak_equivalent_plastic_strain": rep.peak_equivalent_plastic_strain,
            # sum over the steps of sigma : d eps_p dx: dissipation and stored hardening [J]
            "plastic_work_J": rep.plastic_work_j,
            "hardening_energy_J": rep.hardening_energy_j,
            "plastic_cells": int(np.count_nonzero(rep.cell_equivalent_plastic_strain)),
            # the residual field at the most loaded contact node, into the body [m]
            "permanent_indentation_m": dent,
            "permanent_indentation_node": node,
            "cells_returned": rep.n_set_cells,
            "steps_retaken_for_the_plastic_set": rep.n_refused,
            # a reduced body's guard: steps at whose midpoint cells that are not all
            # retained reached Y (their elastic stress), and the most such cells
            "steps_yield_outside_retained": rep.n_outside_steps,
            "cells_yield_outside_retained": rep.outside_cells,
        }
    return {"plastic": out}


def plastic_guard_warnings(summary: dict) -> list[str]:
    """One line per reduced plastic body whose elastic rest reached yield (summary's
    ``plastic``): the plastic zone left the retained region."""
    return [
        f"body {name!r}: {entry['cells_yield_outside_retained']} cells outside the retained "
        f"region reached the yield stress in {entry['steps_yield_outside_retained']} steps "
        "(elastic there, plastic in a full model): retain a larger region"
        for name, entry in summary.get("plastic", {}).items()
        if entry["steps_yield_outside_retained"]
    ]
