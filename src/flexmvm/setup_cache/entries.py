"""The entries of the setup cache's disk store (store.py): FE models, bases, body parts, the
free-free mode pool, patch statics and elimination orders. Each has a key function (its
inputs, under the code version) and a ``cached_<entry>`` that returns the stored entry when it
decodes to the shapes expected, else calls its ``build`` and stores the result.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Mapping

import numpy as np
import scipy.sparse as sp

from flexmvm.bodies.build import BodyParts
from flexmvm.bodies.invariants import InertiaInvariants
from flexmvm.fe.assembly import FEModel
from flexmvm.materials import Material
from flexmvm.mesh.mesh import Mesh
from flexmvm.reduction.basis import Basis
from flexmvm.reduction.kinds import ModelKind, kind_spec
from flexmvm.reduction.reference_condition import ReferenceCondition
from flexmvm.setup_cache.mapped import decoded_mapped
from flexmvm.setup_cache.store import (
    BODY_SOURCES,
    code_version,
    csr_arrays,
    csr_from,
    decoded,
    make_key,
    material_inputs,
    save,
)

#: Kinds whose stored sparse basis is memory-mapped when read (setup_cache.mapped): the ring
#: basis of kind mvm-sparse, whose exterior rows a run reads only at its contact surfaces and
#: probes (a field output reads them all, at each output)
MAPPED_KINDS = (ModelKind("mvm-sparse"),)


def cached_elimination_order(
    a: sp.spmatrix, compute: Callable[[sp.spmatrix], np.ndarray | None]
) -> np.ndarray | None:
    """compute(a), an elimination order of the sparse matrix a (fe.ordering.dissection_order,
    ~1.7 s for a 25,000-DOF rod), kept under a key of a's sparsity pattern alone (an order
    depends on nothing else: every step size's W = M + (theta h)^2 K of a body has one
    pattern). None (no order) is kept too."""
    csr = sp.csr_matrix(a)
    csr.sort_indices()
    digest = hashlib.sha256(np.ascontiguousarray(csr.indptr, np.int64).tobytes())
    digest.update(np.ascontiguousarray(csr.indices, np.int64).tobytes())
    n = csr.shape[0]
    key = make_key("order", {"n": n, "pattern_sha256": digest.hexdigest()})

    def decode(arrays):
        order = np.asarray(arrays["order"], np.int64)
        if not order.size:
            return ()  # stored "no order"
        if order.shape != (n,) or not np.array_equal(np.sort(order), np.arange(n)):
            raise ValueError("not a permutation")
        return order

    got = decoded(key, decode)
    if got is not None:
        return got if len(got) else None
    order = compute(a)
    save(key, {"order": np.zeros(0, np.int64) if order is None else order})
    return order


def fe_key(source: Mapping, material: Material) -> str:
    """Entry name of the consistent-mass FE model of mesh ``source`` in ``material``."""
    return make_key("fe", {"mesh": source, "material": material_inputs(material)})


def _fe_from(arrays: Mapping[str, np.ndarray], mesh: Mesh, material: Material) -> FEModel:
    M, K, Ms = csr_from(arrays, "M"), csr_from(arrays, "K"), csr_from(arrays, "M_scalar")
    n = 3 * mesh.n_nodes
    if M.shape != (n, n) or K.shape != (n, n) or Ms.shape != (n // 3, n // 3):
        raise ValueError("stored FE model does not match the mesh")
    mass, volume = (float(x) for x in arrays["mass_volume"])
    return FEModel(mesh, material, M, K, Ms, mass, volume)


def cached_fe(
    source: Mapping | None,
    mesh: Mesh,
    material: Material,
    build: Callable[[Mesh, Material], FEModel],
) -> FEModel:
    """The FE model of ``mesh`` (described by ``source``) from the cache, else built and stored.

    source: rod_source(spec) or file_source(path); None disables caching for this model.
    build: e.g. flexmvm.fe.assembly.assemble (consistent mass).
    """
    if source is None:
        return build(mesh, material)
    key = fe_key(source, material)
    hit = decoded(key, lambda arrays: _fe_from(arrays, mesh, material))
    if hit is not None:
        return hit
    fe = build(mesh, material)
    save(
        key,
        {
            **csr_arrays("M", fe.M),
            **csr_arrays("K", fe.K),
            **csr_arrays("M_scalar", fe.M_scalar),
            "mass_volume": np.array([fe.mass, fe.volume]),
        },
    )
    return fe


def basis_inputs(
    source: Mapping,
    material: Material,
    kind: ModelKind,
    reference_set: str,
    reference: ReferenceCondition,
    retained: np.ndarray,
    n_modes: int,
    extra: Mapping | None = None,
) -> dict:
    """Key inputs shared by a basis and the body parts built on it; ``extra``: the further
    parameters of a kind (an interface basis: InterfaceSpec.key(), its patch and mode
    choice), left out when None so that the keys of the other kinds do not change."""
    inputs = {
        "mesh": source,
        "material": material_inputs(material),
        "kind": kind.value,
        "reference": {"set": reference_set, "fixed_dofs": reference.fixed_dofs.tolist()},
        "retained": [int(k) for k in retained],
        "n_modes": int(n_modes),
    }
    return inputs if extra is None else inputs | {"extra": dict(extra)}


def basis_key(
    source: Mapping,
    material: Material,
    kind: ModelKind,
    reference_set: str,
    reference: ReferenceCondition,
    retained: np.ndarray,
    n_modes: int,
    version: str | None = None,
    extra: Mapping | None = None,
) -> str:
    """Entry name of a basis: its FE model's inputs, kind, reference, retained nodes, modes
    and the kind's further parameters ``extra``."""
    inputs = basis_inputs(
        source, material, kind, reference_set, reference, retained, n_modes, extra
    )
    return make_key("basis", inputs, version)


def body_key(
    source: Mapping,
    material: Material,
    kind: ModelKind,
    reference_set: str,
    reference: ReferenceCondition,
    retained: np.ndarray,
    n_modes: int,
    version: str | None = None,
    extra: Mapping | None = None,
) -> str:
    """Entry name of a body's parts: the inputs of its basis, under the BODY_SOURCES version."""
    inputs = basis_inputs(
        source, material, kind, reference_set, reference, retained, n_modes, extra
    )
    return make_key("body", inputs, code_version(BODY_SOURCES) if version is None else version)


def _basis_from(
    arrays: Mapping[str, np.ndarray],
    kind: ModelKind,
    reference: ReferenceCondition,
    retained: np.ndarray,
    n_modes: int,
) -> Basis:
    psi = csr_from(arrays, "psi") if "psi_shape" in arrays else arrays["psi"]
    nodes, freqs = arrays["retained_nodes"], arrays["mode_freqs_hz"]
    if not kind_spec(kind).nodal and not np.array_equal(nodes, retained):
        raise ValueError("stored retained nodes differ")
    if freqs.shape != (n_modes,) or psi.ndim != 2:
        raise ValueError("stored basis is malformed")
    return Basis(kind, psi, nodes.astype(np.int64), n_modes, reference, freqs)


def cached_basis(
    source: Mapping | None,
    material: Material,
    kind: ModelKind,
    reference_set: str,
    reference: ReferenceCondition,
    retained: np.ndarray,
    n_modes: int,
    build: Callable[[], Basis],
    extra: Mapping | None = None,
) -> Basis:
    """The basis from the cache, else ``build()`` stored; source None: build, no caching.
    extra: the kind's further parameters (basis_key)."""
    if source is None:
        return build()
    key = basis_key(
        source, material, kind, reference_set, reference, retained, n_modes, extra=extra
    )

    def decode(arrays):
        return _basis_from(arrays, kind, reference, retained, n_modes)

    if kind in MAPPED_KINDS:  # its exterior rows stay on disk until a run reads them
        hit = decoded_mapped(key, decode, ("psi_data", "psi_indices"))
    else:
        hit = decoded(key, decode)
    if hit is not None:
        return hit
    basis = build()
    psi = (
        csr_arrays("psi", basis.psi)
        if sp.issparse(basis.psi)
        else {"psi": np.ascontiguousarray(basis.psi)}
    )
    save(key, {**psi, "retained_nodes": basis.retained_nodes, "mode_freqs_hz": basis.mode_freqs_hz})
    return basis


def free_modes_key(
    source: Mapping, material: Material, n_modes: int, version: str | None = None
) -> str:
    """Entry name of the lowest ``n_modes`` free-free modes (six rigid-body modes included) of
    mesh ``source`` in ``material`` (fe.modes.free_modes, default shift)."""
    return make_key(
        "freemodes",
        {"mesh": source, "material": material_inputs(material), "free_modes": int(n_modes)},
        version,
    )


def cached_free_modes(
    source: Mapping | None,
    material: Material,
    n_modes: int,
    n_dof: int,
    build: Callable[[], tuple[np.ndarray, np.ndarray]],
) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies [Hz] (n_modes,), modes (n_dof, n_modes)) from the cache, else ``build()``
    (fe.modes.free_modes(fe, n_modes)) stored; source None: build, no caching."""
    if source is None:
        return build()
    key = free_modes_key(source, material, n_modes)

    def decode(arrays):
        f_hz, modes = arrays["freqs_hz"], arrays["modes"]
        if f_hz.shape != (n_modes,) or modes.shape != (n_dof, n_modes) or modes.dtype != np.float64:
            raise ValueError("stored free-free modes are malformed")
        return f_hz, modes

    hit = decoded(key, decode)
    if hit is not None:
        return hit
    f_hz, modes = build()
    save(key, {"freqs_hz": np.asarray(f_hz), "modes": np.ascontiguousarray(modes)})
    return f_hz, modes


def patch_statics_key(
    source: Mapping,
    material: Material,
    reference_set: str,
    reference: ReferenceCondition,
    surface: str,
    node: int,
    radii_m: tuple[float, ...],
    version: str | None = None,
) -> str:
    """Entry name of the inertia-relieved static responses of the Hertz patch loads of
    ``radii_m`` about node ``node`` of facet set ``surface`` (reduction.interface
    relieved_statics), under the reference condition."""
    return make_key(
        "patchstatic",
        {
            "mesh": source,
            "material": material_inputs(material),
            "reference": {"set": reference_set, "fixed_dofs": reference.fixed_dofs.tolist()},
            "surface": surface,
            "patch_node": int(node),
            "radii_m": [float(a) for a in radii_m],
        },
        version,
    )


def cached_patch_statics(
    source: Mapping | None,
    material: Material,
    reference_set: str,
    reference: ReferenceCondition,
    surface: str,
    node: int,
    radii_m: tuple[float, ...],
    n_dof: int,
    build: Callable[[], np.ndarray],
) -> np.ndarray:
    """The static responses (n_dof, len(radii_m)) from the cache, else ``build()`` stored (one
    entry per radius set: the columns are solved together, so a rebuild gives the same bits);
    source None: build, no caching."""
    if source is None:
        return build()
    key = patch_statics_key(source, material, reference_set, reference, surface, node, radii_m)

    def decode(arrays):
        static = arrays["static"]
        if static.shape != (n_dof, len(radii_m)) or static.dtype != np.float64:
            raise ValueError("stored patch statics are malformed")
        return static

    hit = decoded(key, decode)
    if hit is not None:
        return hit
    static = build()
    save(key, {"static": np.ascontiguousarray(static)})
    return static


def parts_arrays(parts: BodyParts) -> dict[str, np.ndarray]:
    """Arrays of an entry: mass (1,), S0, S1, G0, G1 (3, 3, nq), G2 (3, 3, nq, nq), M_qq, k_hat."""
    inv, nq = parts.inv, parts.inv.nq
    G1 = np.array([[inv.G1[a][b] for b in range(3)] for a in range(3)]).reshape(3, 3, nq)
    G2 = np.array([[inv.G2[a][b] for b in range(3)] for a in range(3)]).reshape(3, 3, nq, nq)
    return {
        "mass": np.array([inv.mass]),
        "S0": inv.S0,
        "S1": inv.S1,
        "G0": inv.G0,
        "G1": G1,
        "G2": G2,
        "M_qq": inv.M_qq,
        "k_hat": parts.k_hat,
    }


def parts_from(arrays: Mapping[str, np.ndarray], nq: int) -> BodyParts:
    a = arrays
    shapes = {
        "mass": (1,),
        "S0": (3,),
        "S1": (3, nq),
        "G0": (3, 3),
        "G1": (3, 3, nq),
        "G2": (3, 3, nq, nq),
        "M_qq": (nq, nq),
        "k_hat": (nq, nq),
    }
    if any(a[name].shape != shape or a[name].dtype != np.float64 for name, shape in shapes.items()):
        raise ValueError("stored body parts are malformed")
    G1 = tuple(tuple(a["G1"][i, j] for j in range(3)) for i in range(3))
    G2 = tuple(tuple(a["G2"][i, j] for j in range(3)) for i in range(3))
    inv = InertiaInvariants(float(a["mass"][0]), a["S0"], a["S1"], a["G0"], G1, G2, a["M_qq"])
    return BodyParts(inv, a["k_hat"])


def cached_body(
    source: Mapping | None,
    material: Material,
    kind: ModelKind,
    reference_set: str,
    reference: ReferenceCondition,
    retained: np.ndarray,
    n_modes: int,
    nq: int,
    build: Callable[[], BodyParts],
    extra: Mapping | None = None,
) -> BodyParts:
    """A body's parts (invariants, k_hat) from the cache, else ``build()`` stored.

    The arguments up to n_modes are those of its basis (cached_basis); nq: its number of
    columns. Only dense parts are stored: a full-FE body (sparse parts, ~0.3 s to compute, as
    long as reading them back) and source None are built, not cached.
    """
    if source is None or kind_spec(kind).nodal:  # sparse parts: not kept
        return build()
    key = body_key(source, material, kind, reference_set, reference, retained, n_modes, extra=extra)
    hit = decoded(key, lambda arrays: parts_from(arrays, nq))
    if hit is not None:
        return hit
    parts = build()
    if parts.inv.Ms is None and not sp.issparse(parts.k_hat):
        save(key, parts_arrays(parts))
    return parts
