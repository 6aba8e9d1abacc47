"""Turn a validated Scenario into a System, initial states, probes and a time grid: a plain
function of the Scenario and of the setup cache it builds through (assembly/build_cache.py:
meshes, FE models, bases and body parts, cached per process and on disk). It puts the parts
together in order; each part is built by its module: a body (assembly/body_build.py), a
contact and a probe (contact_build.py), a joint (joint_build.py), supports (supports.py),
loads (load_build.py), the initial velocities (initial_velocities.py), a sag (sag.py), the
plastic parts (plastic_parts.py); mesh lookups (retained nodes, contact surfaces):
mesh_lookup.py; solver choices (elimination orders): solver_choice.py.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.assembly.body_build import BodyInfo, build_body, initial_state
from flexmvm.assembly.build_cache import SetupCache, default_setup
from flexmvm.assembly.cache_keys import mesh_key
from flexmvm.assembly.contact_build import contact_provider, probe
from flexmvm.assembly.cost import step_sizes
from flexmvm.assembly.drive_build import joint_label
from flexmvm.assembly.initial_velocities import check_joint_velocities, with_rigid_motions
from flexmvm.assembly.joint_build import joint_constraints
from flexmvm.assembly.load_build import build_loads
from flexmvm.assembly.mesh_lookup import check_contact_surfaces, contact_nodes, contact_surfaces
from flexmvm.assembly.moving_region import driver_hook, moving_body_info
from flexmvm.assembly.plastic_parts import plastic_parts
from flexmvm.assembly.sag import quasi_static_sag
from flexmvm.assembly.solver_choice import with_elimination_order
from flexmvm.assembly.supports import support_joints
from flexmvm.bodies.body import FlexibleBody
from flexmvm.integrate.moving_region import MovingRegion, MovingRegions
from flexmvm.integrate.run_result import Probe, TimeGrid
from flexmvm.integrate.state import BodyState
from flexmvm.integrate.system import System
from flexmvm.scenarios.plasticity_schema import refuse_dynamic


@dataclass
class BuiltScenario:
    """A scenario built: the System, each body's initial state, the probes, the time grid and
    what was built for each body."""

    system: System
    states: list[BodyState]
    probes: list[Probe]
    grid: TimeGrid
    info: list[BodyInfo]
    # the moving regions' run-time state, the run's switches (integrate/moving_region.py): the
    # MovingRegion of the one moving body, MovingRegions over several; None: none
    switches: MovingRegion | MovingRegions | None = None


def build_scenario(sc, setup: SetupCache | None = None) -> BuiltScenario:
    """Meshes, FE models, bases, bodies, joints, contacts and probes of a Scenario, built
    through ``setup`` (default: the process-wide default_setup())."""
    refuse_dynamic(sc)
    setup = default_setup() if setup is None else setup
    bodies: list[FlexibleBody] = []
    infos: list[BodyInfo] = []
    states: list[BodyState] = []
    regions: list[MovingRegion] = []
    for cfg in sc.bodies:
        check_contact_surfaces(sc, cfg.name, setup.mesh(mesh_key(cfg)))
        massless = None
        if any(c.redistribute_mass for c in sc.contacts):
            massless = contact_nodes(sc, cfg.name, setup.mesh(mesh_key(cfg)))
        sizes = step_sizes(sc.time.dt_s, sc.time.dt_max_s)
        surfaces = contact_surfaces(sc, cfg.name)
        if cfg.model.moves:  # a moving region (assembly/moving_region.py)
            body, info, region = moving_body_info(cfg, sc, setup, len(bodies))
            regions.append(region)
        else:
            body, info = build_body(cfg, setup, massless, surfaces, sc.supports, sizes)
        bodies.append(body)
        infos.append(info)
        states.append(initial_state(body, cfg.placement))
    index = {cfg.name: i for i, cfg in enumerate(sc.bodies)}
    grid = TimeGrid.from_config(sc.time)
    contacts = tuple(
        contact_provider(
            c.model_copy(update={"slave": s, "master": m}),
            k,
            bodies,
            infos,
            index,
            grid.theta_rule(),
        )
        for k, c in enumerate(sc.contacts)
        for s, m in c.pairs  # two_pass: also the reverse pair, same law and options
    )
    groups = [
        joint_constraints(j, k, bodies, infos, index, states) for k, j in enumerate(sc.joints)
    ]
    supported = support_joints(sc.supports, index, states)
    joints = [joint for group in (*groups, *supported) for joint in group]
    states = with_rigid_motions(sc, bodies, states, groups)
    probes = [probe(p, f"probes[{k}]", infos, index) for k, p in enumerate(sc.probes)]
    grid.ticks()
    grid.contact_output_ticks()
    bodies = [with_elimination_order(b, setup) for b in bodies]
    loads = build_loads(sc, bodies, infos, index, states)  # [[loads]], [[springs]]
    system = System(
        tuple(bodies),
        tuple(joints),
        contacts,
        np.asarray(sc.gravity_mps2, float),
        loads,
        plastic_parts(sc, infos),  # full-FE plastic bodies (integrate.plastic_bodies)
    )
    for k, cfg in enumerate(sc.bodies):  # joint lengths stay those of the undeformed placement
        if cfg.placement.sagged:
            states[k] = quasi_static_sag(system, states, k, f"bodies[{cfg.name}].placement")
    labels = [joint_label(j, k) for k, j in enumerate(sc.joints)]
    labels += [f"supports[{k}]" for k in range(len(sc.supports))]
    check_joint_velocities(system.bodies, states, groups + supported, labels)
    return BuiltScenario(system, states, probes, grid, infos, driver_hook(regions))
