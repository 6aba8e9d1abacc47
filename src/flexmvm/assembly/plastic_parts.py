"""The plastic parts of a built scenario (integrate.plastic_bodies): the J2 body of every body
whose material has a ``plasticity`` table (scenarios/plasticity_schema.py), with the cells a
reduced body may let yield (those whose nodes its basis retains)."""

from __future__ import annotations

import numpy as np

from flexmvm.errors import InputError
from flexmvm.integrate.plastic_bodies import PlasticPart
from flexmvm.plasticity.body import PlasticBody
from flexmvm.scenarios.plasticity_schema import PlasticOutside, plasticity_of


def plastic_parts(scenario, infos) -> tuple[PlasticPart, ...]:
    """The PlasticPart of every plastic body of ``scenario`` (infos: the built BodyInfo of
    each body, in order: its mesh and elastic material)."""
    parts = []
    for k, (cfg, info) in enumerate(zip(scenario.bodies, infos)):
        plastic = plasticity_of(cfg)
        if plastic is None:
            continue
        model = PlasticBody.build(info.mesh, info.material, plastic)
        allowed = None
        if cfg.model.kind.retains_nodes:  # the cells whose nodes are all retained
            kept = np.zeros(info.mesh.n_nodes, bool)
            kept[info.covered_nodes] = True
            allowed = tuple(kept[bl.nodes].all(axis=1) for bl in model.blocks)
            if not any(a.any() for a in allowed):
                raise InputError(
                    f"bodies[{cfg.name}].model: no cell has all its nodes retained "
                    f"({len(info.covered_nodes)} nodes kept), so none can yield: keep a region "
                    "that holds whole cells around the contact"
                )
        stop = cfg.model.plastic_outside is PlasticOutside.STOP
        parts.append(PlasticPart(k, model, allowed, cfg.model.plastic_tangent, stop))
    return tuple(parts)
