"""Turn a validated Scenario into a System, initial states, probes and a time grid: a plain
function of the Scenario and of the setup cache it builds through (scenarios/setup.py: meshes,
FE models, bases and body parts, cached per process and on disk). Mesh lookups (retained
nodes, contact surfaces, joint points): scenarios/mesh_lookup.py; solver choices (elimination
orders): scenarios/solver_choice.py.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.build import ModelKind, body_from_parts, rigid_body_from_fe
from flexmvm.bodies.moving_region import MovingRegion
from flexmvm.constraints.joints import (
    BodyPoint,
    DistanceJoint,
    JointType,
    NodeSetPoint,
    SphericalJoint,
    fixed_joint,
    ground_joint,
)
from flexmvm.constraints.prismatic import prismatic_joint
from flexmvm.contact.geometry import MasterSurface
from flexmvm.contact.pairs import PointToSurfaceContact
from flexmvm.errors import InputError, MeshError
from flexmvm.integrate.run_result import Probe, TimeGrid
from flexmvm.integrate.state import BodyState
from flexmvm.integrate.system import System
from flexmvm.materials import Material
from flexmvm.mesh.mesh import Mesh
from flexmvm.mesh.point_location import tet_weights
from flexmvm.mesh.rod import RodMesh
from flexmvm.reduction.interface import Patch, contact_patch, patch_nodes
from flexmvm.reduction.kinds import kind_spec
from flexmvm.scenarios.body_reference import reference_label
from flexmvm.scenarios.cache_keys import ContactMass, mesh_key, mesh_source
from flexmvm.scenarios.cost import cached_full_factor, check_cost, reduced_cost, step_sizes
from flexmvm.scenarios.drive_build import (
    joint_label,
    joint_name,
    prescribed_joints,
    revolute_joints,
)
from flexmvm.scenarios.initial_motion import check_joint_velocities, with_rigid_motions
from flexmvm.scenarios.load_build import build_loads
from flexmvm.scenarios.mesh_lookup import (
    body_point,
    check_contact_surfaces,
    contact_nodes,
    contact_surfaces,
    nearest_node,
    retained_nodes,
)
from flexmvm.scenarios.moving_region import covered_nodes, moving_body
from flexmvm.scenarios.plasticity_schema import plastic_parts, refuse_dynamic
from flexmvm.scenarios.sag import quasi_static_sag
from flexmvm.scenarios.setup import SetupCache, default_setup, timed
from flexmvm.scenarios.solver_choice import with_elimination_order
from flexmvm.scenarios.stiffening_schema import stiffened
from flexmvm.scenarios.supports import bedded_key, clamp_label, support_joints
from flexmvm.setup_cache.ring_parts import cached_ring_parts

#: the kinds whose modes are fixed-interface (Craig-Bampton) modes: the truncation guard's
TRUNCATION_GUARDED = (ModelKind.MVM, ModelKind("mvm-sparse"))

DEFAULT_SEARCH_RADIUS_M = 2e-4  # broad-phase margin beyond the distance closed in one step


@dataclass(frozen=True)
class BodyInfo:
    """What was built for one body (for summaries and outputs)."""

    name: str
    model: ModelKind
    mesh: Mesh
    material: Material
    dof: int  # generalized coordinates: 6 frame + nq
    n_retained_nodes: int
    n_modes: int
    rod: RodMesh | None
    # the validity guard (scenarios/guard.py): nodes where the basis leaves a contact free
    # (MVM kinds: the retained nodes; interface: the patch surface's nodes within the largest
    # patch radius); None: not guarded (full FE, modal, rigid). patch: the interface kind's
    # expected contact point.
    covered_nodes: np.ndarray | None = None
    patch: Patch | None = None
    # the truncation guard (reduction/truncation.py): a Craig-Bampton body's modal residual
    truncation: dict | None = None


@dataclass
class BuiltScenario:
    """A scenario built: the System, each body's initial state, the probes, the time grid and
    what was built for each body."""

    system: System
    states: list[BodyState]
    probes: list[Probe]
    grid: TimeGrid
    info: list[BodyInfo]
    # a moving region's run-time state, the run's switches (bodies/moving_region.py); None: none
    switches: MovingRegion | None = None


def build_body(
    cfg,
    setup: SetupCache,
    massless: np.ndarray | None = None,
    surfaces: tuple[str, ...] = (),
    supports=(),
    sizes: int = 1,
) -> tuple[FlexibleBody, BodyInfo]:
    """The body of ``cfg``; ``massless``: its contact nodes whose mass is redistributed
    (retained ones only for the MVM kinds, none for a modal or rigid model); ``surfaces``: its
    contact surfaces, which an automatic reference keeps away from; ``supports``: the
    scenario's, of which a clamp of this body replaces its reference (scenarios.supports). A
    rigid body has no reference condition (nothing to support: no elastic coordinates).
    ``sizes``: the run's step sizes (scenarios.cost.step_sizes), for its cost guard.
    Meshes, FE models, bases and body parts come through ``setup``."""
    where = f"bodies[{cfg.name}]"
    material = cfg.material_obj()
    key = mesh_key(cfg)
    rod = setup.rod_mesh(key) if cfg.rod is not None else None
    mesh = setup.mesh(key)
    key = fe_key = bedded_key(key, cfg, supports)  # K with the body's spring beds
    kind = cfg.model.kind
    spec = kind_spec(kind)
    if not spec.has_basis:
        body = rigid_body_from_fe(cfg.name, setup.fe_model(key, material))
        return body, BodyInfo(cfg.name, kind, mesh, material, 6, 0, 0, rod)
    retained: tuple = ()
    if spec.retains_nodes:
        retained = tuple(int(i) for i in retained_nodes(cfg.model, mesh, rod, f"{where}.model"))
    ref_set = clamp_label(cfg, mesh, supports, retained) or reference_label(
        cfg.model.reference, mesh, surfaces, f"{where}.model.reference"
    )
    modes = cfg.model.modes if spec.reads_modes else 0
    interface = cfg.model.interface_spec() if spec.uses_patches else None
    if massless is not None and massless.size and (spec.nodal or spec.retains_nodes):
        nodes = massless if spec.nodal else np.intersect1d(massless, retained)
        if nodes.size:
            key = ContactMass(key, tuple(int(i) for i in nodes))
    columns = spec.cost_columns(len(retained), modes)
    if columns is not None:  # scenarios.cost: the full-FE factor's counts through the cache
        fixed = setup.reference_condition(key, mesh, ref_set).fixed_dofs
        load_fe = lambda: setup.fe_model(fe_key, material)
        full = cached_full_factor(mesh_source(fe_key), fixed, load_fe)
        cost = reduced_cost(cfg.name, mesh.n_nodes, columns, full.k_nnz, full=full, sizes=sizes)
        check_cost(cost, cfg.model.allow_costly, f"{where}.model")
    args = (key, material, kind, retained, modes, ref_set, interface)
    body = _kind_body(spec, cfg, setup, mesh, args, fe_key)
    if cfg.model.geometric_stiffening is not None:  # bodies.stiffening
        fe = setup.fe_model(fe_key, material)
        spec_g, at = cfg.model.geometric_stiffening, f"{where}.model.geometric_stiffening"
        body = stiffened(body, spec_g, fe, setup.basis(*args), at)
    n_ret = len(retained) if spec.retains_nodes else (mesh.n_nodes if spec.nodal else 0)
    covered, patch = None, None
    if spec.retains_nodes:
        covered = np.array(retained, dtype=np.int64)
    elif interface is not None:
        patch = contact_patch(mesh, interface.surface, interface.centre_m)
        covered = patch_nodes(mesh, interface.surface, patch, max(interface.radii_m, default=0.0))
    truncation = _truncation(setup, args, fe_key) if kind in TRUNCATION_GUARDED else None
    return body, BodyInfo(
        cfg.name, kind, mesh, material, body.nv, n_ret, modes, rod, covered, patch, truncation
    )


def _truncation(setup: SetupCache, args: tuple, fe_key) -> dict | None:
    """The truncation guard (reduction/truncation.modal_residual) of the Craig-Bampton basis
    setup.basis(*args) on the FE model of ``fe_key``, through the setup cache
    (SetupCache.truncation); None without retained nodes."""
    if not args[3]:
        return None
    return setup.truncation(fe_key, *args)


def _kind_body(spec, cfg, setup: SetupCache, mesh: Mesh, args: tuple, fe_key) -> FlexibleBody:
    """The body of ``cfg`` on its basis (setup.basis(*args)): the kind's own body_builder
    (name, fe of ``fe_key``, basis, damping, and the setup cache's entry for the parts it
    builds, parts_cache) when it has one, else body_from_parts on the cached parts."""
    if spec.body_builder is not None:
        fe = setup.fe_model(fe_key, args[1])
        basis = setup.basis(*args)
        return timed(
            f"body {cfg.name!r}: its {spec.name} body built ({basis.nq} coordinates)",
            lambda: spec.body_builder(
                cfg.name, fe, basis, damping=cfg.damping_obj(), parts_cache=cached_ring_parts
            ),
        )
    return body_from_parts(
        cfg.name, mesh, setup.basis(*args), setup.body_parts(*args), damping=cfg.damping_obj()
    )


def initial_state(body: FlexibleBody, placement) -> BodyState:
    """The state of ``body`` at its placement: position, rotation, velocities; q = 0."""
    A = placement.rotation.matrix()
    v = np.zeros(body.nv)
    v[:3] = placement.velocity_mps
    v[3:6] = placement.angular_velocity_radps
    return BodyState(
        np.asarray(placement.position_m, float), np.asarray(A, float), np.zeros(body.nq), v
    )


def _node_set_point(
    index, body: FlexibleBody, info: BodyInfo, name: str, where: str
) -> NodeSetPoint:
    """The centroid of node set `name` of the body (constraints.joints.NodeSetPoint)."""
    try:
        ids = info.mesh.node_set(name)
    except MeshError as exc:
        raise InputError(f"{where}: {exc}") from None
    return NodeSetPoint.of(index, body, ids)


def build_scenario(sc, setup: SetupCache | None = None) -> BuiltScenario:
    """Meshes, FE models, bases, bodies, joints, contacts and probes of a Scenario, built
    through ``setup`` (default: the process-wide default_setup())."""
    refuse_dynamic(sc)
    setup = default_setup() if setup is None else setup
    bodies, infos, states, switches = [], [], [], None
    for cfg in sc.bodies:
        check_contact_surfaces(sc, cfg.name, setup.mesh(mesh_key(cfg)))
        massless = None
        if any(c.redistribute_mass for c in sc.contacts):
            massless = contact_nodes(sc, cfg.name, setup.mesh(mesh_key(cfg)))
        sizes = step_sizes(sc.time.dt_s, sc.time.dt_max_s)
        surfaces = contact_surfaces(sc, cfg.name)
        if cfg.model.moves:  # a moving region (scenarios/moving_region.py)
            body, info, switches = _moving(cfg, sc, setup, len(bodies), switches)
        else:
            body, info = build_body(cfg, setup, massless, surfaces, sc.supports, sizes)
        bodies.append(body)
        infos.append(info)
        states.append(initial_state(body, cfg.placement))
    index = {cfg.name: i for i, cfg in enumerate(sc.bodies)}
    t = sc.time
    grid = TimeGrid(
        t.t_end_s,
        t.dt_s,
        t.dt_max_s,
        t.output_dt_s,
        t.theta,
        t.output_contact_dt_s,
        t.hf_damping_time_s,
        field_output_dt_s=t.field_output_dt_s,
        field_precision=t.field_precision,
    )
    contacts = tuple(
        _contact(c, k, bodies, infos, index, grid.theta_rule()) for k, c in enumerate(sc.contacts)
    )
    groups = [_joint(j, k, bodies, infos, index, states) for k, j in enumerate(sc.joints)]
    supported = support_joints(sc.supports, index, states)
    joints = [joint for group in (*groups, *supported) for joint in group]
    states = with_rigid_motions(sc, bodies, states, groups)
    probes = [_probe(p, f"probes[{k}]", infos, index) for k, p in enumerate(sc.probes)]
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
    return BuiltScenario(system, states, probes, grid, infos, switches)


def _moving(cfg, sc, setup: SetupCache, index: int, switches):
    """(body, BodyInfo, MovingRegion) of the moving region ``cfg``, the index-th body;
    InputError for a second one (a run drives one)."""
    if switches is not None:
        raise InputError(
            f"bodies[{cfg.name}].model.moving: a second moving region (body "
            f"{switches.name!r} is one); expected one per scenario"
        )
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


def _contact(c, k, bodies, infos, index, theta):
    """The contact provider of contacts[k]; theta: the scheme's theta of each step size
    (TimeGrid.theta_rule), which the position law's bound needs (the end gap is
    g + h (theta u_N+ + (1 - theta) u_N-))."""
    where = f"contacts[{k}]"
    s, m = index[c.slave_body], index[c.master_body]
    try:
        slave_facets = infos[s].mesh.facet_set(c.slave_surface)
        slave_nodes = slave_facets.nodes
        master = MasterSurface.from_facet_set(infos[m].mesh.facet_set(c.master_surface))
    except MeshError as exc:
        raise InputError(f"{where}: {exc}") from None
    radius = c.search_radius_m if c.search_radius_m is not None else DEFAULT_SEARCH_RADIUS_M
    return PointToSurfaceContact(
        bodies,
        s,
        slave_nodes,
        m,
        master,
        c.kind,
        radius,
        name=f"{c.slave}->{c.master}",
        slave_surface=MasterSurface.from_facet_set(slave_facets),
        friction_coefficient=c.friction_coefficient,
        law=c.law,
        theta=theta,
        **({} if c.penetration_recovery is None else {"beta": c.penetration_recovery}),
    )


def _probe(p, where, infos, index) -> Probe:
    b = index[p.body]
    mesh = infos[b].mesh
    if p.node_set is not None:
        try:
            ids = mesh.node_set(p.node_set)
        except MeshError as exc:
            raise InputError(f"{where}.node_set: {exc}") from None
        return Probe(p.name, b, int(ids[0]), p.axis)
    tol = 0.05 * float(np.ptp(mesh.nodes, axis=0).min() or 1.0)
    d = np.linalg.norm(mesh.nodes - np.asarray(p.point_m, float), axis=1)
    if d.min() > tol:  # no node near: the point interpolated in the tet that holds it
        found = tet_weights(mesh, p.point_m)
        if found is not None:
            nodes, w = found
            near = int(nodes[np.argmax(w)])
            return Probe(p.name, b, near, p.axis, tuple(map(int, nodes)), tuple(map(float, w)))
    return Probe(p.name, b, nearest_node(mesh, p.point_m, f"{where}.point_m", tol), p.axis)


def _joint(j, k, bodies, infos, index, states):
    where, name = f"joints[{k}]", joint_name(j, k)
    b = index[j.body]
    t = j.type
    if t is JointType.GROUND:
        return ground_joint(b, states)
    if j.node_set is not None:
        p1 = _node_set_point(b, bodies[b], infos[b], j.node_set, f"{where}.node_set")
    else:
        p1 = body_point(b, bodies[b], infos[b].mesh, j.point_m, f"{where}.point_m")
    if t is JointType.PRESCRIBED:
        return prescribed_joints(j, name, p1, bodies, states)
    if t is JointType.PRISMATIC:
        return prismatic_joint(p1, j.ground_m, j.axis, bodies, states)
    if j.body2 is not None:
        b2 = index[j.body2]
        at = j.point2_m
        if at is None:  # body2's point where the node set's centroid is at t = 0
            at = states[b2].A.T @ (p1.position(bodies, states) - states[b2].r)
        p2 = body_point(b2, bodies[b2], infos[b2].mesh, at, f"{where}.point2_m")
    elif j.ground_m is not None:
        p2 = np.asarray(j.ground_m, float)
    else:  # a node set's centroid, held where it starts (schema.JointConfig)
        p2 = p1.position(bodies, states)
    if t is JointType.DISTANCE:
        x1 = p1.position(bodies, states)
        x2 = p2.position(bodies, states) if isinstance(p2, BodyPoint) else p2
        length = j.length_m if j.length_m is not None else float(np.linalg.norm(x1 - x2))
        return [DistanceJoint(p1, p2, length)]
    if t is JointType.SPHERICAL:
        return [SphericalJoint(p1, p2)]
    if t is JointType.REVOLUTE:
        return revolute_joints(j, name, p1, p2, states)
    return fixed_joint(p1, p2, states)
