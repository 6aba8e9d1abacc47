"""The setup cache: what building a System from a Scenario computes once and reuses.

A SetupCache owns
- the per-process caches (ProcessCaches: bounded LRU caches of rod meshes, meshes, FE models,
  bases and body parts, keyed by their defining data), so a study that runs many variants of
  one scenario builds each body once;
- the disk cache behind them (flexmvm.setup_cache: FE models, bases, dense body parts, free-free
  mode pools, patch statics, elimination orders across processes). An FE model is only loaded
  or assembled when a basis or body part has to be computed: a warm run reads bases and parts,
  not M and K;
- the policies: the caches' bounds and the Craig-Bampton mode floor.

It is passed explicitly (assembly.build.build_scenario(sc, setup)); ``default_setup()`` is the
process-wide instance behind ``fm.clear_caches``, ``fm.set_cache_sizes`` and
``fm.cache_sizes``, and what a build uses when given none. A mode floor is a view
(``setup.with_mode_floor(n)``) sharing its caches, not a switch.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import time
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from flexmvm import setup_cache
from flexmvm.assembly.body_reference import support
from flexmvm.assembly.cache_keys import (
    ContactMass,
    MergedFile,
    MeshKey,
    SpringBeds,
    interface_inputs,
    mesh_key,
    mesh_source,
    plain_key,
)
from flexmvm.bodies.build import BodyParts, body_parts
from flexmvm.errors import InputError
from flexmvm.fe.assembly import FEModel, assemble
from flexmvm.fe.mass_redistribution import redistribute_mass
from flexmvm.fe.modes import free_modes
from flexmvm.fe.spring_bed import beds_stiffness, with_spring_bed
from flexmvm.materials import Material
from flexmvm.mesh.io import read_mesh
from flexmvm.mesh.mesh import Mesh
from flexmvm.mesh.rod import RodMesh, RodSpec, rod_mesh
from flexmvm.reduction.basis import Basis, build_basis
from flexmvm.reduction.interface import (
    FreeModes,
    InterfaceSources,
    InterfaceSpec,
    Patch,
    participation_pool,
    relieved_statics,
)
from flexmvm.reduction.kinds import ModelKind, kind_spec
from flexmvm.reduction.rod_reference import rod_reference
from flexmvm.reduction.truncation import modal_residual

#: The per-process caches by what they hold, with their default bounds (entries).
CACHE_SIZES = {"meshes": 8, "fe_models": 8, "bases": 64, "body_parts": 16}


#: The set-up's stages as they happen (mesh read, FE assembly, basis, invariants: the ones
#: built, not those read from the disk cache), at INFO; `flexmvm run` prints them
SETUP_LOG = logging.getLogger("flexmvm.setup")


def timed(what: str, make):
    """make() with its wall time logged on SETUP_LOG as "what: N s"."""
    t0 = time.perf_counter()
    out = make()
    SETUP_LOG.info("%s: %.1f s", what, time.perf_counter() - t0)
    return out


def checked_sizes(sizes: Mapping[str, int]) -> dict[str, int]:
    """``sizes`` if every name is a cache's and every bound an integer >= 0; InputError (one
    line) otherwise."""
    unknown = set(sizes) - set(CACHE_SIZES)
    if unknown:
        raise InputError(
            f"cache sizes: unknown {sorted(unknown)}; expected some of {', '.join(CACHE_SIZES)}"
        )
    bad = {k: v for k, v in sizes.items() if not isinstance(v, int) or v < 0}
    if bad:
        raise InputError(f"cache sizes: expected integers >= 0, got {bad}")
    return dict(sizes)


class ProcessCaches:
    """The per-process LRU caches of a SetupCache, each bounded by ``sizes`` (entries; 0: no
    caching). Attributes ``rod_mesh``, ``mesh`` (meshes), ``fe_model``, ``basis``,
    ``body_parts``: the cached lookups (functools.lru_cache, with ``cache_info()``); none
    depends on a mode floor, so every view of one SetupCache shares them."""

    def __init__(self, sizes: Mapping[str, int]) -> None:
        self.sizes = dict(sizes)
        for name in self.sizes:
            self._bound(name)

    def _bound(self, name: str) -> None:
        """A new, empty cache ``name`` of the bound in ``sizes``."""
        lru = functools.lru_cache(maxsize=self.sizes[name])
        if name == "meshes":
            self.rod_mesh = lru(rod_mesh)
            self.mesh = functools.lru_cache(maxsize=self.sizes[name])(self._mesh)
        elif name == "fe_models":
            self.fe_model = lru(self._fe_model)
        elif name == "bases":
            self.basis = lru(self._basis)
        else:
            self.body_parts = lru(self._body_parts)

    def resize(self, sizes: Mapping[str, int]) -> None:
        """New bounds for the caches named (which are emptied); the others are kept."""
        self.sizes.update(checked_sizes(sizes))
        for name in sizes:
            self._bound(name)

    def clear(self) -> None:
        """Empty every cache."""
        for fn in (self.rod_mesh, self.mesh, self.fe_model, self.basis, self.body_parts):
            fn.cache_clear()

    def _mesh(self, key: MeshKey) -> Mesh:
        """The mesh of a rod spec (generated) or of a mesh file path."""
        if isinstance(key, (ContactMass, SpringBeds)):
            return self.mesh(key.key)
        if isinstance(key, MergedFile):
            return timed(
                f"mesh {Path(key.path).name} read", lambda: read_mesh(key.path, merge_nodes=True)
            )
        if isinstance(key, RodSpec):
            return self.rod_mesh(key).mesh
        return timed(f"mesh {Path(key).name} read", lambda: read_mesh(key))

    def _fe_model(self, key: MeshKey, material: Material) -> FEModel:
        """The FE model (M, K) of mesh key ``key`` in ``material``: the disk cache, else
        assembled; for a ContactMass key the model of its mesh with the mass of the contact
        nodes redistributed (M_scalar and M; K unchanged)."""
        if isinstance(key, ContactMass):
            fe = self.fe_model(key.key, material)
            m_scalar = redistribute_mass(fe.M_scalar, fe.mesh.nodes, key.nodes)
            return dataclasses.replace(
                fe, M_scalar=m_scalar, M=sp.csr_matrix(sp.kron(m_scalar, sp.identity(3)))
            )
        if isinstance(key, SpringBeds):  # K + the beds' stiffness (assembly/supports.py)
            fe = self.fe_model(key.key, material)
            return with_spring_bed(fe, beds_stiffness(fe.mesh, key.beds))

        def build(mesh: Mesh, material: Material) -> FEModel:
            return timed(
                f"FE model assembled ({3 * mesh.n_nodes:,} DOF, {material.name})",
                lambda: assemble(mesh, material),
            )

        return setup_cache.cached_fe(mesh_source(key), self.mesh(key), material, build)

    def reference_condition(self, key: MeshKey, mesh: Mesh, ref_set: str):
        """A rod's default (end_b) reference is rod_reference; otherwise the support of
        reference label ``ref_set`` (body_reference.support: a 3-2-1 on the named set, or far
        from the contact surfaces of an automatic label)."""
        key = plain_key(key)
        if isinstance(key, RodSpec) and ref_set == "end_b":
            return rod_reference(self.rod_mesh(key))
        return support(mesh, ref_set)

    def _basis(
        self,
        key: MeshKey,
        material: Material,
        kind: ModelKind,
        retained: tuple,
        modes: int,
        ref_set: str,
        interface: InterfaceSpec | None = None,
    ) -> Basis:
        """The basis of these arguments: disk cache, else built from the FE model."""
        ref = self.reference_condition(key, self.mesh(key), ref_set)
        nodes = np.array(retained, dtype=np.int64)

        def build() -> Basis:
            fe = self.fe_model(key, material)
            sources = (
                self.interface_sources(key, material, fe, ref_set, ref, interface.surface)
                if interface is not None
                else None
            )
            return timed(
                f"basis {kind.value} built ({nodes.size} retained nodes, {modes} modes)",
                lambda: build_basis(
                    fe,
                    kind,
                    ref,
                    retained_nodes=nodes,
                    n_modes=modes,
                    interface=interface,
                    sources=sources,
                ),
            )

        return setup_cache.cached_basis(
            mesh_source(key),
            material,
            kind,
            ref_set,
            ref,
            nodes,
            modes,
            build,
            extra=interface_inputs(interface),
        )

    def _body_parts(
        self,
        key: MeshKey,
        material: Material,
        kind: ModelKind,
        retained: tuple,
        modes: int,
        ref_set: str,
        interface: InterfaceSpec | None = None,
    ) -> BodyParts:
        """Parts of the basis self.basis(same arguments): disk cache, else computed from the
        FE model (loaded only then)."""
        basis = self.basis(key, material, kind, retained, modes, ref_set, interface)
        return setup_cache.cached_body(
            mesh_source(key),
            material,
            kind,
            ref_set,
            basis.reference,
            np.array(retained, dtype=np.int64),
            modes,
            basis.psi.shape[1],
            lambda: timed(
                f"inertia invariants of the {kind.value} body ({basis.nq} coordinates)",
                lambda: body_parts(self.fe_model(key, material), basis),
            ),
            extra=interface_inputs(interface),
        )

    def free_modes(self, key: MeshKey, material: Material, fe: FEModel) -> FreeModes:
        """k -> the lowest k free-free modes of ``fe`` (mesh key ``key``): the disk cache's
        ``freemodes`` entry, else fe.modes.free_modes on one BLAS thread, as build_basis
        solves (stored)."""
        from threadpoolctl import threadpool_limits

        def solve(k: int):
            with threadpool_limits(limits=1, user_api="blas"):
                return free_modes(fe, k)

        source = mesh_source(key)
        return lambda k: setup_cache.cached_free_modes(
            source, material, k, fe.n_dof, lambda: solve(k)
        )

    def interface_sources(
        self, key: MeshKey, material: Material, fe: FEModel, ref_set: str, ref, surface: str
    ) -> InterfaceSources:
        """An interface basis's mode pool and patch statics through the disk cache: keyed
        without the mode count, so the bases of one patch set and pool share them."""
        source = mesh_source(key)

        def statics(patch: Patch, radii: tuple[float, ...], loads: np.ndarray) -> np.ndarray:
            return setup_cache.cached_patch_statics(
                source,
                material,
                ref_set,
                ref,
                surface,
                patch.node,
                radii,
                fe.n_dof,
                lambda: relieved_statics(fe, ref, loads),
            )

        return InterfaceSources(self.free_modes(key, material, fe), statics)


class SetupCache:
    """Caches and policies of setup (module doc). ``sizes``: bounds of the per-process caches
    (CACHE_SIZES by default); ``mode_floor``: within a view of floor n, a Craig-Bampton basis
    of k < n modes is the first k columns of the n-mode one (cached), so a study over mode
    counts computes one eigen solve per node selection. Exact up to the eigensolver
    tolerance; within a degenerate pair (a rod's two bending planes) the cut may keep a
    different vector of the same eigenspace."""

    def __init__(
        self,
        sizes: Mapping[str, int] | None = None,
        *,
        mode_floor: int = 0,
        caches: ProcessCaches | None = None,
    ) -> None:
        self.caches = (
            caches
            if caches is not None
            else ProcessCaches(CACHE_SIZES | checked_sizes(sizes or {}))
        )
        self.mode_floor = int(mode_floor)

    def with_mode_floor(self, n_modes: int) -> SetupCache:
        """A view of these caches under mode floor ``n_modes`` (class doc)."""
        return SetupCache(mode_floor=n_modes, caches=self.caches)

    def sizes(self) -> dict[str, int]:
        """The bound (entries) of each per-process cache: meshes, fe_models, bases, body_parts."""
        return dict(self.caches.sizes)

    def set_sizes(self, **sizes: int) -> None:
        """Bound the per-process caches: ``set_sizes(fe_models=2, bases=8)``; 0 disables one.
        The caches named are emptied. InputError for an unknown name or a negative bound."""
        self.caches.resize(sizes)

    def clear(self, disk: bool = False) -> None:
        """Empty the per-process caches; ``disk`` also empties the disk cache (what
        ``flexmvm cache clear`` removes)."""
        self.caches.clear()
        if disk:
            setup_cache.clear()

    def rod_mesh(self, spec: RodSpec) -> RodMesh:
        """The (cached) RodMesh of a rod spec."""
        return self.caches.rod_mesh(spec)

    def mesh(self, key: MeshKey) -> Mesh:
        """The (cached) mesh of a mesh key."""
        return self.caches.mesh(key)

    def fe_model(self, key: MeshKey, material: Material) -> FEModel:
        """The (cached) FE model of a mesh key in ``material`` (ProcessCaches._fe_model)."""
        return self.caches.fe_model(key, material)

    def basis(
        self,
        key: MeshKey,
        material: Material,
        kind: ModelKind,
        retained: tuple,
        modes: int,
        ref_set: str,
        interface: InterfaceSpec | None = None,
    ) -> Basis:
        """The basis of mesh key ``key`` in ``material``: ``kind``, retained node ids,
        ``modes``, reference label; under a mode floor above ``modes`` a Craig-Bampton basis
        is cut from the floor's."""
        floor = self.mode_floor
        if not kind_spec(kind).cuts_modes or modes >= floor:
            return self.caches.basis(key, material, kind, retained, modes, ref_set, interface)
        big = self.caches.basis(key, material, kind, retained, floor, ref_set)
        nb = 3 * len(big.retained_nodes) + big.n_static
        return dataclasses.replace(
            big,
            psi=np.ascontiguousarray(big.psi[:, : nb + modes]),
            n_modes=modes,
            mode_freqs_hz=big.mode_freqs_hz[:modes].copy(),
        )

    def body_parts(
        self,
        key: MeshKey,
        material: Material,
        kind: ModelKind,
        retained: tuple,
        modes: int,
        ref_set: str,
        interface: InterfaceSpec | None = None,
    ) -> BodyParts:
        """Invariants and k_hat of the body whose basis is self.basis(same arguments); under a
        mode floor cut from the floor's parts, as the basis is cut."""
        floor = self.mode_floor
        if not kind_spec(kind).cuts_modes or modes >= floor:
            return self.caches.body_parts(key, material, kind, retained, modes, ref_set, interface)
        big = self.caches.body_parts(key, material, kind, retained, floor, ref_set)
        n_static = self.caches.basis(key, material, kind, retained, floor, ref_set).n_static
        return big.leading(3 * len(retained) + n_static + modes)

    def truncation(
        self,
        fe_key: MeshKey,
        key: MeshKey,
        material: Material,
        kind: ModelKind,
        retained: tuple,
        modes: int,
        ref_set: str,
        interface: InterfaceSpec | None = None,
    ) -> dict:
        """The truncation guard (reduction.truncation.modal_residual) of the basis
        self.basis(key, ...) on the FE model of ``fe_key``: the disk cache (keyed by the
        basis's inputs, the FE model's and the mode floor the basis is cut from), else
        computed; a warm run then neither loads the FE model for it nor factors its K_ii."""
        args = (key, material, kind, retained, modes, ref_set, interface)
        cut = kind_spec(kind).cuts_modes and modes < self.mode_floor
        extra = (interface_inputs(interface) or {}) | {
            "guard_fe_model": mesh_source(fe_key),
            "mode_floor": self.mode_floor if cut else 0,
        }
        return setup_cache.cached_truncation(
            mesh_source(key),
            material,
            kind,
            ref_set,
            self.basis(*args).reference,
            np.array(retained, dtype=np.int64),
            modes,
            lambda: modal_residual(self.fe_model(fe_key, material), self.basis(*args)),
            extra=extra,
        )

    def reference_condition(self, key: MeshKey, mesh: Mesh, ref_set: str):
        """The reference condition of label ``ref_set`` (ProcessCaches.reference_condition)."""
        return self.caches.reference_condition(key, mesh, ref_set)

    def free_modes_source(self, cfg) -> tuple[FEModel, FreeModes]:
        """(FE model, k -> its lowest k free-free modes through the disk cache) of a
        scenario's body ``cfg``: the source interface bases take their mode pool from
        (reduction.interface.FreeModes)."""
        key, material = mesh_key(cfg), cfg.material_obj()
        fe = self.fe_model(key, material)
        return fe, self.caches.free_modes(key, material, fe)

    def interface_mode_pool(self, cfg, spec: InterfaceSpec, modes: int) -> int:
        """The mode pool from which an interface basis of ``spec`` with ``modes`` modes of body
        ``cfg`` takes its modes (reduction.interface.participation_pool): with ``mode_pool``
        = this, every smaller mode count of the spec shares its eigen solve (disk cache), and
        the ``modes`` one is the default's basis. InputError (one line) if the pool cannot
        hold ``modes`` excited modes."""
        fe, free = self.free_modes_source(cfg)
        return participation_pool(fe, spec, modes, free)

    def elimination_order(
        self, pattern: sp.spmatrix, compute: Callable[[sp.spmatrix], np.ndarray | None]
    ) -> np.ndarray | None:
        """compute(pattern) through the disk cache, keyed by the sparsity pattern alone
        (setup_cache.cached_elimination_order)."""
        return setup_cache.cached_elimination_order(pattern, compute)


_DEFAULT = SetupCache()


def default_setup() -> SetupCache:
    """The process-wide SetupCache (fm.clear_caches, fm.set_cache_sizes, fm.cache_sizes; a
    build given no setup)."""
    return _DEFAULT


def clear_caches(disk: bool = False) -> None:
    """Empty this process's caches of meshes, FE models, bases and body parts (a notebook that
    has run many models frees their memory); ``disk`` also empties the setup cache on disk
    (flexmvm.setup_cache: what ``flexmvm cache clear`` removes)."""
    _DEFAULT.clear(disk)


def cache_sizes() -> dict[str, int]:
    """The bound (entries) of each per-process cache: meshes, fe_models, bases, body_parts."""
    return _DEFAULT.sizes()


def set_cache_sizes(**sizes: int) -> None:
    """Bound the per-process caches: ``set_cache_sizes(fe_models=2, bases=8)``; 0 disables one.
    The caches named are emptied. InputError for an unknown name or a negative bound."""
    _DEFAULT.set_sizes(**sizes)
