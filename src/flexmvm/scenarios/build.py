"""Turn a validated Scenario into a System, initial states, probes and a time grid.

Meshes, FE models, bases and body parts (inertia invariants, k_hat) are cached per process
(keyed by their defining data), so a study that runs many variants of one scenario builds each
body once; FE models, bases and dense body parts are also cached on disk across processes
(flexmvm.setup_cache), behind the per-process caches. An FE model is only loaded or assembled
when a basis or body part has to be computed: a warm run reads bases and parts, not M and K.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from flexmvm import setup_cache
from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.build import (
    BodyParts,
    ModelKind,
    body_from_parts,
    body_parts,
    rigid_body_from_fe,
)
from flexmvm.constraints.joints import (
    BodyPoint,
    DistanceJoint,
    JointType,
    NodeSetPoint,
    PrescribedMotion,
    SphericalJoint,
    fixed_joint,
    ground_joint,
    revolute_joint,
)
from flexmvm.contact.geometry import MasterSurface
from flexmvm.contact.pairs import PointToSurfaceContact
from flexmvm.errors import InputError, MeshError
from flexmvm.fe import ldl
from flexmvm.fe.assembly import FEModel, assemble
from flexmvm.fe.mass_redistribution import redistribute_mass
from flexmvm.fe.modes import free_modes
from flexmvm.fe.ordering import elimination_order, iteration_pattern
from flexmvm.integrate.run_result import Probe, TimeGrid
from flexmvm.integrate.state import BodyState
from flexmvm.integrate.system import System
from flexmvm.materials import Material
from flexmvm.mesh.io import read_mesh
from flexmvm.mesh.mesh import Mesh
from flexmvm.mesh.rod import RodMesh, RodSpec, rod_mesh
from flexmvm.reduction.basis import Basis, BasisKind, build_basis
from flexmvm.reduction.interface import (
    FreeModes,
    InterfaceSources,
    InterfaceSpec,
    Patch,
    contact_patch,
    participation_pool,
    patch_nodes,
    relieved_statics,
)
from flexmvm.reduction.rod_reference import rod_reference
from flexmvm.scenarios.body_reference import reference_label, support
from flexmvm.scenarios.cost import check_cost, reduced_cost
from flexmvm.scenarios.sag import quasi_static_sag

DEFAULT_SEARCH_RADIUS_M = 2e-4  # broad-phase margin beyond the distance closed in one step


@dataclass(frozen=True)
class BodyInfo:
    """What was built for one body (for summaries and outputs)."""

    name: str
    model: ModelKind
    mesh: Mesh
    material: Material
    dof: int                 # generalized coordinates: 6 frame + nq
    n_retained_nodes: int
    n_modes: int
    rod: RodMesh | None
    # the validity guard (scenarios/guard.py): nodes where the basis leaves a contact free
    # (MVM kinds: the retained nodes; interface: the patch surface's nodes within the largest
    # patch radius); None: not guarded (full FE, modal, rigid). patch: the interface kind's
    # expected contact point.
    covered_nodes: np.ndarray | None = None
    patch: Patch | None = None


@dataclass
class BuiltScenario:
    system: System
    states: list[BodyState]
    probes: list[Probe]
    grid: TimeGrid
    info: list[BodyInfo]


@functools.lru_cache(maxsize=8)
def cached_rod_mesh(spec: RodSpec) -> RodMesh:
    return rod_mesh(spec)


@dataclass(frozen=True)
class ContactMass:
    """The mesh key (a RodSpec or a mesh file path) of a body whose contact nodes ``nodes``
    carry no mass (fe/mass_redistribution.py): a key of its own for every cache."""

    key: RodSpec | str
    nodes: tuple[int, ...]


def _mesh_source(key) -> dict | None:
    """Disk-cache key inputs of a rod spec or a mesh file (None: file unreadable, no caching),
    with the massless contact nodes of a ContactMass key."""
    if isinstance(key, ContactMass):
        inner = _mesh_source(key.key)
        return None if inner is None else inner | {"massless_nodes": list(key.nodes)}
    if isinstance(key, RodSpec):
        return setup_cache.rod_source(key)
    return setup_cache.file_source(key)


@functools.lru_cache(maxsize=8)
def _mesh(key) -> Mesh:
    """The mesh of a rod spec (generated) or of a mesh file path."""
    if isinstance(key, ContactMass):
        return _mesh(key.key)
    return cached_rod_mesh(key).mesh if isinstance(key, RodSpec) else read_mesh(key)


@functools.lru_cache(maxsize=8)
def fe_model_for(key, material: Material) -> FEModel:
    """The FE model (M, K) of a rod spec or mesh file path ``key`` in ``material``: per-process
    cache, then the disk cache, else assembled; for a ContactMass key the model of its mesh
    with the mass of the contact nodes redistributed (M_scalar and M; K unchanged)."""
    if isinstance(key, ContactMass):
        fe = fe_model_for(key.key, material)
        m_scalar = redistribute_mass(fe.M_scalar, fe.mesh.nodes, key.nodes)
        return dataclasses.replace(fe, M_scalar=m_scalar,
                                   M=sp.csr_matrix(sp.kron(m_scalar, sp.identity(3))))
    return setup_cache.cached_fe(_mesh_source(key), _mesh(key), material, assemble)


def reference_condition(key, mesh: Mesh, ref_set: str):
    """A rod's default (end_b) reference is rod_reference; otherwise the support of reference
    label ``ref_set`` (body_reference.support: a 3-2-1 on the named set, or far from the
    contact surfaces of an automatic label)."""
    if isinstance(key, ContactMass):
        key = key.key
    if isinstance(key, RodSpec) and ref_set == "end_b":
        return rod_reference(cached_rod_mesh(key))
    return support(mesh, ref_set)


_MODE_FLOOR = [0]


@contextlib.contextmanager
def craig_bampton_mode_floor(n_modes: int):
    """Within this block a Craig-Bampton basis of k < n_modes modes is the first k columns of
    the n_modes one (cached): a study over mode counts computes one eigen solve per node
    selection. Exact up to the eigensolver tolerance; within a degenerate pair (a rod's two
    bending planes) the cut may keep a different vector of the same eigenspace."""
    old = _MODE_FLOOR[0]
    _MODE_FLOOR[0] = int(n_modes)
    try:
        yield
    finally:
        _MODE_FLOOR[0] = old


def basis_for(key, material: Material, kind: BasisKind, retained: tuple, modes: int, ref_set: str,
              interface: InterfaceSpec | None = None) -> Basis:
    floor = _MODE_FLOOR[0]
    if kind is not BasisKind.CRAIG_BAMPTON or modes >= floor:
        return _basis_cached(key, material, kind, retained, modes, ref_set, interface)
    big = _basis_cached(key, material, kind, retained, floor, ref_set)
    nb = 3 * len(big.retained_nodes) + big.n_static
    return dataclasses.replace(big, psi=np.ascontiguousarray(big.psi[:, : nb + modes]),
                               n_modes=modes, mode_freqs_hz=big.mode_freqs_hz[:modes].copy())


def _extra(interface: InterfaceSpec | None) -> dict | None:
    return None if interface is None else interface.key()


@functools.lru_cache(maxsize=64)
def _basis_cached(key, material: Material, kind: BasisKind, retained: tuple, modes: int,
                  ref_set: str, interface: InterfaceSpec | None = None) -> Basis:
    ref = reference_condition(key, _mesh(key), ref_set)
    nodes = np.array(retained, dtype=np.int64)

    def build() -> Basis:
        fe = fe_model_for(key, material)
        sources = (_interface_sources(key, material, fe, ref_set, ref, interface.surface)
                   if interface is not None else None)
        return build_basis(fe, kind, ref, retained_nodes=nodes, n_modes=modes,
                           interface=interface, sources=sources)

    return setup_cache.cached_basis(_mesh_source(key), material, kind, ref_set, ref, nodes,
                                    modes, build, extra=_extra(interface))


def _free_modes_source(key, material: Material, fe: FEModel):
    """k -> the lowest k free-free modes of ``fe`` (mesh key ``key``): the setup cache's
    ``freemodes`` entry, else fe.modes.free_modes on one BLAS thread, as build_basis solves
    (stored)."""
    from threadpoolctl import threadpool_limits

    def solve(k: int):
        with threadpool_limits(limits=1, user_api="blas"):
            return free_modes(fe, k)

    source = _mesh_source(key)
    return lambda k: setup_cache.cached_free_modes(source, material, k, fe.n_dof,
                                                   lambda: solve(k))


def free_modes_source(cfg) -> tuple[FEModel, FreeModes]:
    """(FE model, k -> its lowest k free-free modes through the setup cache) of a scenario's
    body ``cfg``: the source interface bases take their mode pool from
    (reduction.interface.FreeModes)."""
    key, material = _mesh_key(cfg), cfg.material_obj()
    fe = fe_model_for(key, material)
    return fe, _free_modes_source(key, material, fe)


def _interface_sources(key, material: Material, fe: FEModel, ref_set: str, ref,
                       surface: str) -> InterfaceSources:
    """An interface basis's mode pool and patch statics through the setup cache: keyed
    without the mode count, so the bases of one patch set and pool share them."""
    source = _mesh_source(key)

    def statics(patch: Patch, radii: tuple[float, ...], loads: np.ndarray) -> np.ndarray:
        return setup_cache.cached_patch_statics(
            source, material, ref_set, ref, surface, patch.node, radii, fe.n_dof,
            lambda: relieved_statics(fe, ref, loads))

    return InterfaceSources(_free_modes_source(key, material, fe), statics)


def interface_mode_pool(cfg, spec: InterfaceSpec, modes: int) -> int:
    """The mode pool from which an interface basis of ``spec`` with ``modes`` modes of body
    ``cfg`` (a scenario's body) takes its modes (reduction.interface.participation_pool):
    with ``mode_pool`` = this, every smaller mode count of the spec shares its eigen solve
    (setup cache), and the ``modes`` one is the default's basis. The eigen solves it makes
    are stored for the bases that follow. InputError (one line) if the pool cannot hold
    ``modes`` excited modes."""
    fe, free = free_modes_source(cfg)
    return participation_pool(fe, spec, modes, free)


def body_parts_for(key, material: Material, kind: BasisKind, retained: tuple, modes: int,
                   ref_set: str, interface: InterfaceSpec | None = None) -> BodyParts:
    """Invariants and k_hat of the body whose basis is basis_for(same arguments); under a
    Craig-Bampton mode floor cut from the floor's parts, as the basis is cut."""
    floor = _MODE_FLOOR[0]
    if kind is not BasisKind.CRAIG_BAMPTON or modes >= floor:
        return _parts_cached(key, material, kind, retained, modes, ref_set, interface)
    big = _parts_cached(key, material, kind, retained, floor, ref_set)
    n_static = _basis_cached(key, material, kind, retained, floor, ref_set).n_static
    return big.leading(3 * len(retained) + n_static + modes)


@functools.lru_cache(maxsize=16)
def _parts_cached(key, material: Material, kind: BasisKind, retained: tuple, modes: int,
                  ref_set: str, interface: InterfaceSpec | None = None) -> BodyParts:
    """Parts of the basis _basis_cached(same arguments): disk cache, else computed from the FE
    model (loaded only then)."""
    basis = _basis_cached(key, material, kind, retained, modes, ref_set, interface)
    return setup_cache.cached_body(
        _mesh_source(key), material, kind, ref_set, basis.reference,
        np.array(retained, dtype=np.int64), modes, basis.psi.shape[1],
        lambda: body_parts(fe_model_for(key, material), basis), extra=_extra(interface))


#: The per-process caches by what they hold, with their default bounds (entries).
_CACHE_SIZES = {"meshes": 8, "fe_models": 8, "bases": 64, "body_parts": 16}


def _caches() -> dict[str, list]:
    return {"meshes": [cached_rod_mesh, _mesh], "fe_models": [fe_model_for], "bases": [_basis_cached],
            "body_parts": [_parts_cached]}


def clear_caches(disk: bool = False) -> None:
    """Empty this process's caches of meshes, FE models, bases and body parts (a notebook that
    has run many models frees their memory); ``disk`` also empties the setup cache on disk
    (flexmvm.setup_cache: what ``flexmvm cache clear`` removes)."""
    for fns in _caches().values():
        for fn in fns:
            fn.cache_clear()
    if disk:
        setup_cache.clear()


def cache_sizes() -> dict[str, int]:
    """The bound (entries) of each per-process cache: meshes, fe_models, bases, body_parts."""
    return dict(_CACHE_SIZES)


def set_cache_sizes(**sizes: int) -> None:
    """Bound the per-process caches: ``set_cache_sizes(fe_models=2, bases=8)``; 0 disables one.
    The caches named are emptied. InputError for an unknown name or a negative bound."""
    global cached_rod_mesh, _mesh, fe_model_for, _basis_cached, _parts_cached
    unknown = set(sizes) - set(_CACHE_SIZES)
    if unknown:
        raise InputError(f"cache sizes: unknown {sorted(unknown)}; expected some of "
                         f"{', '.join(_CACHE_SIZES)}")
    bad = {k: v for k, v in sizes.items() if not isinstance(v, int) or v < 0}
    if bad:
        raise InputError(f"cache sizes: expected integers >= 0, got {bad}")
    _CACHE_SIZES.update(sizes)

    def rewrap(fn, name):
        fn.cache_clear()
        return functools.lru_cache(maxsize=_CACHE_SIZES[name])(fn.__wrapped__)

    if "meshes" in sizes:
        cached_rod_mesh, _mesh = rewrap(cached_rod_mesh, "meshes"), rewrap(_mesh, "meshes")
    if "fe_models" in sizes:
        fe_model_for = rewrap(fe_model_for, "fe_models")
    if "bases" in sizes:
        _basis_cached = rewrap(_basis_cached, "bases")
    if "body_parts" in sizes:
        _parts_cached = rewrap(_parts_cached, "body_parts")


def retained_nodes(model, mesh: Mesh, rod: RodMesh | None, where: str) -> np.ndarray:
    """The node ids ``model`` (a ModelConfig) retains on ``mesh`` (``rod``: the body's RodMesh,
    for an i-j selection): its selection or region; InputError (one line) if it selects none.
    The selection study counts its candidates' nodes with it (studies/regions.py)."""
    return _retained_nodes(model, mesh, rod, where)


def _retained_nodes(model, mesh: Mesh, rod: RodMesh | None, where: str) -> np.ndarray:
    if model.selection_ij is not None:
        if rod is None:
            raise InputError(f"{where}.selection: an i-j selection needs a [bodies.rod] body")
        return rod.selection(*model.selection_ij)
    reg = model.region
    if reg is None:
        raise InputError(f"{where}: model {model.kind.value!r} needs a selection or a region")
    X = mesh.nodes
    if reg.node_set is not None:
        ids = mesh.node_set(reg.node_set)
    elif reg.ball is not None:
        ids = np.nonzero(np.linalg.norm(X - np.asarray(reg.ball.centre_m), axis=1) <= reg.ball.radius_m)[0]
    elif reg.box is not None:
        lo, hi = np.asarray(reg.box.min_m), np.asarray(reg.box.max_m)
        ids = np.nonzero(np.all((X >= lo) & (X <= hi), axis=1))[0]
    else:
        ids = np.asarray(reg.node_ids, dtype=np.int64)
        if ids.size and ids.max() >= len(X):
            raise InputError(f"{where}.region.node_ids: node {int(ids.max())} is outside the mesh "
                             f"(0..{len(X) - 1})")
    if len(ids) == 0:
        raise InputError(f"{where}.region: selects no node of the mesh")
    return np.asarray(ids, dtype=np.int64)


def _mesh_key(cfg) -> RodSpec | str:
    return cfg.rod.spec() if cfg.rod is not None else str(cfg.mesh_file)


def contact_nodes(sc, body: str, mesh: Mesh) -> np.ndarray:
    """Nodes of ``body`` on the surfaces of the contacts that redistribute their mass
    (``redistribute_mass``): the slave face's nodes, or the master facets' nodes."""
    ids = []
    for k, c in enumerate(sc.contacts):
        if not c.redistribute_mass:
            continue
        for who, surface in ((c.slave_body, c.slave_surface), (c.master_body, c.master_surface)):
            if who == body:
                try:
                    ids.append(mesh.facet_set(surface).nodes)
                except MeshError as exc:
                    raise InputError(f"contacts[{k}]: {exc}") from None
    return np.unique(np.concatenate(ids)) if ids else np.zeros(0, np.int64)


def contact_surfaces(sc, body: str) -> tuple[str, ...]:
    """The facet sets of ``body`` named in the scenario's contacts, as slave or master."""
    names = [surface for c in sc.contacts
             for who, surface in ((c.slave_body, c.slave_surface), (c.master_body, c.master_surface))
             if who == body]
    return tuple(dict.fromkeys(names))


def _build_body(cfg, massless: np.ndarray | None = None,
                surfaces: tuple[str, ...] = ()) -> tuple[FlexibleBody, BodyInfo]:
    """The body of ``cfg``; ``massless``: its contact nodes whose mass is redistributed
    (retained ones only for the MVM kinds, none for a modal or rigid model); ``surfaces``: its
    contact surfaces, which an automatic reference keeps away from. A rigid body has no
    reference condition (nothing to support: no elastic coordinates)."""
    where = f"bodies[{cfg.name}]"
    material = cfg.material_obj()
    key = _mesh_key(cfg)
    rod = cached_rod_mesh(key) if cfg.rod is not None else None
    mesh = _mesh(key)
    kind = cfg.model.kind
    if kind.basis is None:
        body = rigid_body_from_fe(cfg.name, fe_model_for(key, material))
        return body, BodyInfo(cfg.name, kind, mesh, material, 6, 0, 0, rod)
    ref_set = reference_label(cfg.model.reference, mesh, surfaces, f"{where}.model.reference")
    retained: tuple = ()
    if kind.retains_nodes:
        retained = tuple(int(i) for i in _retained_nodes(cfg.model, mesh, rod, f"{where}.model"))
    modes = cfg.model.modes if kind.uses_modes or kind is ModelKind.INTERFACE else 0
    interface = cfg.model.interface_spec() if kind is ModelKind.INTERFACE else None
    if massless is not None and massless.size and kind.basis is not None \
            and (kind is ModelKind.FULL or kind.retains_nodes):
        nodes = massless if kind is ModelKind.FULL else np.intersect1d(massless, retained)
        if nodes.size:
            key = ContactMass(key, tuple(int(i) for i in nodes))
    if kind.retains_nodes:
        fe = fe_model_for(_mesh_key(cfg), material)
        cost = reduced_cost(cfg.name, mesh.n_nodes, 3 * len(retained) + modes, fe.K.nnz)
        check_cost(cost, cfg.model.allow_costly, f"{where}.model")
    args = (key, material, kind.basis, retained, modes, ref_set, interface)
    body = body_from_parts(cfg.name, mesh, basis_for(*args), body_parts_for(*args))
    n_ret = len(retained) if kind.retains_nodes else (mesh.n_nodes if kind is ModelKind.FULL
                                                      else 0)
    covered, patch = None, None
    if kind.retains_nodes:
        covered = np.array(retained, dtype=np.int64)
    elif interface is not None:
        patch = contact_patch(mesh, interface.surface, interface.centre_m)
        covered = patch_nodes(mesh, interface.surface, patch, max(interface.radii_m, default=0.0))
    return body, BodyInfo(cfg.name, kind, mesh, material, body.nv, n_ret, modes, rod,
                          covered, patch)


def _initial_state(body: FlexibleBody, placement) -> BodyState:
    A = placement.rotation.matrix()
    v = np.zeros(body.nv)
    v[:3] = placement.velocity_mps
    v[3:6] = placement.angular_velocity_radps
    return BodyState(np.asarray(placement.position_m, float), np.asarray(A, float),
                     np.zeros(body.nq), v)


def _nearest_node(mesh: Mesh, point, where: str, tol: float) -> int:
    d = np.linalg.norm(mesh.nodes - np.asarray(point, float), axis=1)
    k = int(np.argmin(d))
    if d[k] > tol:
        raise InputError(f"{where}: point {list(point)} is {d[k]:.3g} m from the nearest node of "
                         f"the body (off the body; tolerance {tol:.3g} m)")
    return k


# A joint point is on the body when it lies in a cell's node bounding box grown by this
# fraction of the box's diagonal (curved cell faces bulge beyond their nodes' box).
CELL_BOX_PAD = 0.05


def _host_node(mesh: Mesh, point: np.ndarray, where: str) -> int:
    """The node nearest `point` among the cells whose (padded) node box holds it; InputError
    when no cell does (the point is off the body)."""
    best, best_d = -1, np.inf
    for block in mesh.cells:
        xc = mesh.nodes[block.connectivity]                     # (cells, nodes per cell, 3)
        lo, hi = xc.min(axis=1), xc.max(axis=1)
        pad = CELL_BOX_PAD * np.linalg.norm(hi - lo, axis=1)[:, None]
        inside = np.all((point >= lo - pad) & (point <= hi + pad), axis=1)
        ids = np.unique(block.connectivity[inside])
        if ids.size:
            d = np.linalg.norm(mesh.nodes[ids] - point, axis=1)
            if d.min() < best_d:
                best, best_d = int(ids[np.argmin(d)]), float(d.min())
    if best < 0:
        d = float(np.linalg.norm(mesh.nodes - point, axis=1).min())
        raise InputError(f"{where}: point {point.tolist()} m (body frame) is off the body: in no "
                         f"cell, {d:.3g} m from the nearest node")
    return best


def _body_point(index, body: FlexibleBody, info: BodyInfo, point, where) -> BodyPoint:
    """The body point at `point` (body frame, reference configuration) exactly: a rigid body's
    frame point, else the nearest node of its cell with the offset to the point, carried by
    that node's displacement and the frame's rotation (joints.BodyPoint)."""
    p = np.asarray(point, float)
    node = _host_node(info.mesh, p, where)
    if body.nq == 0:
        return BodyPoint(index, local=tuple(float(x) for x in p))
    off = p - info.mesh.nodes[node]
    if not np.any(off):
        return BodyPoint(index, node=node)
    return BodyPoint(index, node=node, offset_m=tuple(float(x) for x in off))


def _node_set_point(index, body: FlexibleBody, info: BodyInfo, name: str,
                    where: str) -> NodeSetPoint:
    """The centroid of node set `name` of the body (constraints.joints.NodeSetPoint)."""
    try:
        ids = info.mesh.node_set(name)
    except MeshError as exc:
        raise InputError(f"{where}: {exc}") from None
    return NodeSetPoint.of(index, body, ids)


def build_scenario(sc) -> BuiltScenario:
    """Meshes, FE models, bases, bodies, joints, contacts and probes of a Scenario."""
    bodies, infos, states = [], [], []
    for cfg in sc.bodies:
        massless = None
        if any(c.redistribute_mass for c in sc.contacts):
            massless = contact_nodes(sc, cfg.name, _mesh(_mesh_key(cfg)))
        body, info = _build_body(cfg, massless, contact_surfaces(sc, cfg.name))
        bodies.append(body)
        infos.append(info)
        states.append(_initial_state(body, cfg.placement))
    index = {cfg.name: i for i, cfg in enumerate(sc.bodies)}
    t = sc.time
    grid = TimeGrid(t.t_end_s, t.dt_s, t.dt_max_s, t.output_dt_s, t.theta, t.output_contact_dt_s,
                    t.hf_damping_time_s)
    contacts = tuple(_contact(c, k, bodies, infos, index, grid.theta_rule())
                     for k, c in enumerate(sc.contacts))
    joints = []
    for k, j in enumerate(sc.joints):
        joints.extend(_joint(j, f"joints[{k}]", bodies, infos, index, states))
    probes = [_probe(p, f"probes[{k}]", infos, index) for k, p in enumerate(sc.probes)]
    grid.ticks()
    grid.contact_output_ticks()
    bodies = [_with_elimination_order(b) for b in bodies]
    system = System(tuple(bodies), tuple(joints), contacts, np.asarray(sc.gravity_mps2, float))
    for k, cfg in enumerate(sc.bodies):  # joint lengths stay those of the undeformed placement
        if cfg.placement.sagged:
            states[k] = quasi_static_sag(system, states, k, f"bodies[{cfg.name}].placement")
    return BuiltScenario(system, states, probes, grid, infos)


def _with_elimination_order(body: FlexibleBody) -> FlexibleBody:
    """A full-FE body with the elimination order of its iteration matrices (fe.ordering,
    ~1.7 s for a 25,000-DOF rod), kept in the setup cache under their sparsity pattern."""
    if not (body.nq >= ldl.SPLIT_MIN_N and body.is_sparse and sp.issparse(body.k_hat)):
        return body
    pattern = iteration_pattern(body.inv.M_qq, body.k_hat,
                                body.c_hat if sp.issparse(body.c_hat) else None)
    order = setup_cache.cached_elimination_order(pattern, elimination_order)
    # an empty order: made, none found (the solver then takes SuperLU's minimum degree
    # without looking again)
    return dataclasses.replace(body, elimination_order=(order if order is not None
                                                        else np.zeros(0, np.int64)))


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
    return PointToSurfaceContact(bodies, s, slave_nodes, m, master, c.kind,
                                 radius, name=f"{c.slave}->{c.master}",
                                 slave_surface=MasterSurface.from_facet_set(slave_facets),
                                 friction_coefficient=c.friction_coefficient,
                                 law=c.law, theta=theta,
                                 **({} if c.penetration_recovery is None
                                    else {"beta": c.penetration_recovery}))


def _probe(p, where, infos, index) -> Probe:
    b = index[p.body]
    mesh = infos[b].mesh
    if p.node_set is not None:
        try:
            ids = mesh.node_set(p.node_set)
        except MeshError as exc:
            raise InputError(f"{where}.node_set: {exc}") from None
        return Probe(p.name, b, int(ids[0]))
    tol = 0.05 * float(np.ptp(mesh.nodes, axis=0).min() or 1.0)
    return Probe(p.name, b, _nearest_node(mesh, p.point_m, f"{where}.point_m", tol))


def _joint(j, where, bodies, infos, index, states):
    b = index[j.body]
    t = j.type
    if t is JointType.GROUND:
        return ground_joint(b, states)
    if j.node_set is not None:
        p1 = _node_set_point(b, bodies[b], infos[b], j.node_set, f"{where}.node_set")
    else:
        p1 = _body_point(b, bodies[b], infos[b], j.point_m, f"{where}.point_m")
    if t is JointType.PRESCRIBED:
        x0 = p1.position(bodies, states)
        return [PrescribedMotion(p1, tuple(x0), tuple(j.velocity_mps))]
    if j.body2 is not None:
        b2 = index[j.body2]
        p2 = _body_point(b2, bodies[b2], infos[b2], j.point2_m, f"{where}.point2_m")
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
        return revolute_joint(p1, p2, j.axis, states)
    return fixed_joint(p1, p2, states)
