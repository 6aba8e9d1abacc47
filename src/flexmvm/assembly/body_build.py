"""One body of a scenario built through the setup cache (assembly/build_cache.py): its FE model,
basis and body by its model kind, its cost guard, geometric stiffening and truncation guard, its
initial state, and what was built for it (BodyInfo: summaries, outputs, the guards)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.assembly.body_reference import reference_label
from flexmvm.assembly.build_cache import SetupCache, timed
from flexmvm.assembly.cache_keys import ContactMass, MeshKey, mesh_key, mesh_source
from flexmvm.assembly.cost import BodyCost, cached_full_factor, check_cost, reduced_cost
from flexmvm.assembly.cost_sparse import MASSLESS_COLUMNS, ring_cost, ring_shape
from flexmvm.assembly.mesh_lookup import retained_nodes
from flexmvm.assembly.stiffened_body import stiffened
from flexmvm.assembly.supports import bedded_key, clamp_label
from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.build import ModelKind, body_from_parts, rigid_body_from_fe
from flexmvm.integrate.state import BodyState
from flexmvm.materials import Material
from flexmvm.mesh.mesh import Mesh
from flexmvm.mesh.rod import RodMesh, RodSpec
from flexmvm.reduction.interface import Patch, contact_patch, patch_nodes
from flexmvm.reduction.kinds import kind_spec
from flexmvm.reduction.kinds.mvm_sparse import RingCraigBampton
from flexmvm.setup_cache.ring_parts import cached_ring_parts

#: the kinds whose modes are fixed-interface (Craig-Bampton) modes: the truncation guard's
TRUNCATION_GUARDED = (ModelKind.MVM, ModelKind("mvm-sparse"))


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
    # the validity guard (runs/guard.py): nodes where the basis leaves a contact free
    # (MVM kinds: the retained nodes; interface: the patch surface's nodes within the largest
    # patch radius); None: not guarded (full FE, modal, rigid). patch: the interface kind's
    # expected contact point.
    covered_nodes: np.ndarray | None = None
    patch: Patch | None = None
    # the truncation guard (reduction/truncation.py): a Craig-Bampton body's modal residual
    truncation: dict | None = None


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
    scenario's, of which a clamp of this body replaces its reference (assembly.supports). A
    rigid body has no reference condition (nothing to support: no elastic coordinates).
    ``sizes``: the run's step sizes (assembly.cost.step_sizes), for its cost guard.
    Meshes, FE models, bases and body parts come through ``setup``."""
    where = f"bodies[{cfg.name}]"
    material = cfg.material_obj()
    plain = mesh_key(cfg)
    rod = setup.rod_mesh(plain) if isinstance(plain, RodSpec) else None  # a rod's key: its spec
    mesh = setup.mesh(plain)
    fe_key = bedded_key(plain, cfg, supports)  # K with the body's spring beds
    key: MeshKey = fe_key
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
            key = ContactMass(fe_key, tuple(int(i) for i in nodes))
    cost = body_cost(
        cfg, setup, (mesh, key, fe_key, ref_set), retained, modes, massless, sizes, surfaces
    )
    if cost is not None:
        check_cost(cost, cfg.model.allow_costly, f"{where}.model")
    args = (key, material, kind, retained, modes, ref_set, interface)
    body = kind_body(spec, cfg, setup, mesh, args, fe_key)
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
    truncation = truncation_of(setup, args, fe_key) if kind in TRUNCATION_GUARDED else None
    return body, BodyInfo(
        cfg.name, kind, mesh, material, body.nv, n_ret, modes, rod, covered, patch, truncation
    )


def body_cost(
    cfg,
    setup: SetupCache,
    where: tuple,
    retained: tuple,
    modes: int,
    massless,
    sizes: int,
    surfaces: tuple[str, ...] = (),
) -> BodyCost | None:
    """The cost guard's estimate (assembly.cost) of ``cfg``'s reduced body before it is
    built, ``where`` = (mesh, its FE key with the redistributed mass, the FE key, the reference
    set): the full-FE factor's counts through the cache; kind mvm-sparse from its ring and
    its contact ``surfaces``' nodes (assembly.cost_sparse), the other costed kinds from their
    dense columns; None: not costed (full FE, modal, rigid, interface)."""
    mesh, key, fe_key, ref_set = where
    spec = kind_spec(cfg.model.kind)
    ring = isinstance(spec, RingCraigBampton)
    columns = spec.cost_columns(len(retained), modes)
    if columns is None and not ring:
        return None
    fixed = setup.reference_condition(key, mesh, ref_set).fixed_dofs
    load_fe = lambda: setup.fe_model(fe_key, cfg.material_obj())
    # mvm-sparse: the minimum-degree analysis (its K_EE's factor's order) for its set-up and
    # for full FE: the integrator's dissection order costs as much set-up memory as full FE
    # itself on a big part (8.6 GB on the 263,685-DOF plate, where its full FE peaks at 8.9 GB)
    # and holds ~1.9 x more (assembly.cost.full_factor)
    full = cached_full_factor(mesh_source(fe_key), fixed, load_fe, integrator_order=not ring)
    if ring:
        light = massless is not None and np.intersect1d(massless, retained).size > 0
        extra = modes + (MASSLESS_COLUMNS if light else 0)
        touched = [mesh.facet_set(name).nodes for name in surfaces]
        contact = np.unique(np.concatenate(touched)) if touched else None
        shape = ring_shape(mesh, np.asarray(retained, np.int64), fixed, extra, contact)
        return ring_cost(cfg.name, mesh.n_nodes, shape, full, sizes)
    assert columns is not None
    return reduced_cost(cfg.name, mesh.n_nodes, columns, full.k_nnz, full=full, sizes=sizes)


def truncation_of(setup: SetupCache, args: tuple, fe_key) -> dict | None:
    """The truncation guard (reduction/truncation.modal_residual) of the Craig-Bampton basis
    setup.basis(*args) on the FE model of ``fe_key``, through the setup cache
    (SetupCache.truncation); None without retained nodes."""
    if not args[3]:
        return None
    return setup.truncation(fe_key, *args)


def kind_body(spec, cfg, setup: SetupCache, mesh: Mesh, args: tuple, fe_key) -> FlexibleBody:
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
