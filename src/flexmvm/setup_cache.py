"""Disk cache of what setup builds: FE models (M, K, M_scalar), reduction bases (psi), the
parts of bodies with dense bases (inertia invariants and k_hat, flexmvm.bodies.build.BodyParts)
and the two expensive parts of an interface basis that do not depend on its mode count: the
free-free mode pool (``freemodes-``: frequencies and M-normalised modes of the lowest k free-free
modes, keyed by mesh, material and k; 36 MB for the seed rod's 178) and the patch vectors'
static responses (``patchstatic-``: keyed by mesh, material, reference, surface, patch node and
radii), so bases that differ only in ``modes`` (and share a ``mode_pool``) share them; and the
elimination orders of large iteration matrices (``order-``: keyed by their sparsity pattern).

An entry is one ``.npz`` file (``np.savez``, no pickles; sparse matrices as their CSR
arrays) named ``<kind>-<key>.npz``. The key is a SHA-256 of the canonical JSON of every input
the entry depends on (mesh: rod spec or mesh-file content hash; material E, nu, rho; basis
kind, retained nodes, modes, reference set and DOFs) and of the code version, a hash of the
source files that produce it (CODE_SOURCES; body parts: BODY_SOURCES, which adds the body
modules, so editing them rebuilds only body entries). Entries are written atomically, with the
SHA-256 of their arrays (names, dtypes, shapes, bytes) as one more array (CHECKSUM). An entry
is used only if it passes its check: readable, that checksum matches, every float array finite
(nothing setup stores holds NaN or inf) and its decoder accepts its shapes. One that fails is
evicted (deleted), announced in one line (``setup cache basis-....npz: holds NaN or inf in
psi: evicted and rebuilt``) and rebuilt; an unwritable cache directory is ignored.

Location: ``$FLEXMVM_CACHE_DIR`` if set, else the platform user cache directory
(``~/.cache/flexmvm`` on Linux). ``FLEXMVM_NO_CACHE=1`` bypasses the cache (no read, no
write). Rod meshes are not stored: generating one takes ~10 ms, no more than reading it back.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import os
import sys
import zipfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from enum import Enum
from pathlib import Path

import numpy as np
import scipy.sparse as sp

import flexmvm
from flexmvm.bodies.build import BodyParts
from flexmvm.bodies.invariants import InertiaInvariants
from flexmvm.errors import InputError, announce_recompute
from flexmvm.fe.assembly import FEModel
from flexmvm.materials import Material
from flexmvm.mesh.mesh import Mesh
from flexmvm.reduction.basis import Basis, BasisKind
from flexmvm.reduction.reference import ReferenceCondition
from flexmvm.results.atomic import atomic_path, canonical_json

ENV_DIR = "FLEXMVM_CACHE_DIR"
ENV_OFF = "FLEXMVM_NO_CACHE"
SUFFIX = ".npz"

#: Package modules whose source makes up the code version (paths relative to flexmvm/).
CODE_SOURCES = ("mesh", "fe", "reduction", "materials.py")

#: Code version of body entries: what produces the basis, plus the body modules.
BODY_SOURCES = CODE_SOURCES + ("bodies/invariants.py", "bodies/build.py")

#: Format of the stored arrays; bump when the layout of an entry changes.
FORMAT = 2

#: Name of the array holding an entry's checksum (checksum()).
CHECKSUM = "__sha256__"

#: What reading or decoding a corrupt, truncated or foreign entry raises (treated as a miss).
_UNREADABLE = (OSError, EOFError, ValueError, KeyError, TypeError, IndexError,
               zipfile.BadZipFile)


@dataclass(frozen=True)
class CacheInfo:
    """Summary of the cache directory: path, number of entries, total size [MB]."""

    path: Path
    n_entries: int
    size_mb: float


def cache_dir() -> Path:
    """The cache directory: $FLEXMVM_CACHE_DIR, else the platform user cache dir + flexmvm."""
    env = os.environ.get(ENV_DIR, "").strip()
    if env:
        return Path(env).expanduser()
    home = Path.home()
    if sys.platform == "win32":
        return Path(os.environ.get("LOCALAPPDATA") or home / "AppData" / "Local") / "flexmvm"
    if sys.platform == "darwin":
        return home / "Library" / "Caches" / "flexmvm"
    return Path(os.environ.get("XDG_CACHE_HOME") or home / ".cache") / "flexmvm"


def enabled() -> bool:
    """False when $FLEXMVM_NO_CACHE is set to 1/true/yes/on."""
    return os.environ.get(ENV_OFF, "").strip().lower() not in ("1", "true", "yes", "on")


@functools.lru_cache(maxsize=4)
def code_version(sources: tuple[str, ...] = CODE_SOURCES) -> str:
    """SHA-256 (16 hex digits) of the package source files ``sources`` (default CODE_SOURCES)."""
    root = Path(flexmvm.__file__).parent
    digest = hashlib.sha256()
    for name in sources:
        path = root / name
        for f in sorted(path.rglob("*.py")) if path.is_dir() else [path]:
            digest.update(f.relative_to(root).as_posix().encode() + b"\0")
            digest.update(f.read_bytes())
    return digest.hexdigest()[:16]


def make_key(kind: str, inputs: Mapping, version: str | None = None) -> str:
    """Entry name ``<kind>-<32 hex>`` of ``inputs`` (JSON-able) under a code version."""
    doc = {"format": FORMAT, "kind": kind, "inputs": inputs,
           "code": code_version() if version is None else version}
    return f"{kind}-{hashlib.sha256(canonical_json(doc).encode()).hexdigest()[:32]}"


def rod_source(spec) -> dict:
    """Key inputs of a generated rod mesh: every RodSpec field (enums by value)."""
    return {"rod": {k: (v.value if isinstance(v, Enum) else v)
                    for k, v in dataclasses.asdict(spec).items()}}


def file_source(path: str | os.PathLike[str]) -> dict | None:
    """Key inputs of a mesh file: SHA-256 of its content; None if it cannot be read."""
    try:
        return {"file_sha256": hashlib.sha256(Path(path).read_bytes()).hexdigest()}
    except OSError:
        return None


def material_inputs(material: Material) -> dict:
    """Key inputs of a material: E [Pa], nu [-], rho [kg/m^3] (the name changes nothing)."""
    return {"E": float(material.E), "nu": float(material.nu), "rho": float(material.rho)}


def checksum(arrays: Mapping[str, np.ndarray]) -> str:
    """SHA-256 (hex) of an entry's arrays: each name, dtype, shape and C-order bytes, in
    name order (the CHECKSUM array itself left out)."""
    digest = hashlib.sha256()
    for name in sorted(n for n in arrays if n != CHECKSUM):
        a = np.ascontiguousarray(arrays[name])
        digest.update(f"{name}\0{a.dtype.str}\0{a.shape}\0".encode())
        digest.update(a.tobytes())
    return digest.hexdigest()


def entry_problem(arrays: Mapping[str, np.ndarray]) -> str | None:
    """Why the arrays read from an entry cannot be used (one line), or None: no checksum, a
    checksum that differs from its content, a float array holding NaN or inf."""
    for name in sorted(arrays):
        a = arrays[name]
        if a.dtype.kind in "fc" and not np.all(np.isfinite(a)):
            return f"holds NaN or inf in {name}"
    if CHECKSUM not in arrays:
        return "no checksum (written by another version or another program)"
    if str(arrays[CHECKSUM]) != checksum(arrays):
        return "content differs from its checksum"
    return None


def _evict(path: Path, why: str) -> None:
    """Delete a failing entry and say so in one line."""
    try:
        path.unlink()
    except OSError:  # gone already, or a read-only cache: rebuilt all the same
        pass
    announce_recompute(f"setup cache {path.name}: {why}: evicted and rebuilt")


def load(key: str) -> dict[str, np.ndarray] | None:
    """The arrays of entry ``key`` (CHECKSUM left out), or None if absent or disabled; an
    entry that is unreadable or fails its check (entry_problem) is evicted, announced, None."""
    if not enabled():
        return None
    path = cache_dir() / (key + SUFFIX)
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {name: z[name] for name in z.files}
    except (FileNotFoundError, NotADirectoryError):
        return None
    except _UNREADABLE as exc:  # a corrupt or foreign file: evicted, rebuilt and overwritten
        _evict(path, f"unreadable ({type(exc).__name__})")
        return None
    why = entry_problem(arrays)
    if why is not None:
        _evict(path, why)
        return None
    arrays.pop(CHECKSUM)
    return arrays


def save(key: str, arrays: Mapping[str, np.ndarray]) -> None:
    """Write entry ``key`` atomically with its checksum; silently skipped if disabled or
    unwritable."""
    if not enabled():
        return
    directory = cache_dir()
    try:
        directory.mkdir(parents=True, exist_ok=True)
        with atomic_path(directory / (key + SUFFIX)) as tmp, open(tmp, "wb") as f:
            np.savez(f, **arrays, **{CHECKSUM: np.array(checksum(arrays))})
    except (OSError, InputError, ValueError):  # a read-only or full disk must not stop a run
        return


def _entries() -> list[Path]:
    directory = cache_dir()
    return sorted(directory.glob("*" + SUFFIX)) if directory.is_dir() else []


def info() -> CacheInfo:
    """Path, number of entries and total size [MB] of the cache directory."""
    files = _entries()
    size = sum(f.stat().st_size for f in files)
    return CacheInfo(cache_dir(), len(files), size / 1e6)


def clear() -> int:
    """Delete every entry (and stray temporary files); returns the number of entries removed."""
    files = _entries()
    for f in files:
        f.unlink(missing_ok=True)
    directory = cache_dir()
    if directory.is_dir():
        for tmp in directory.glob(".*.tmp"):
            tmp.unlink(missing_ok=True)
    return len(files)


def cached_elimination_order(a: sp.spmatrix, compute: Callable[[sp.spmatrix], np.ndarray | None]
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
            return ()                      # stored "no order"
        if order.shape != (n,) or not np.array_equal(np.sort(order), np.arange(n)):
            raise ValueError("not a permutation")
        return order

    got = _decoded(key, decode)
    if got is not None:
        return got if len(got) else None
    order = compute(a)
    save(key, {"order": np.zeros(0, np.int64) if order is None else order})
    return order


def _decoded(key: str, decode: Callable[[Mapping[str, np.ndarray]], object]):
    """decode(arrays of entry ``key``), or None if the entry is absent or malformed."""
    arrays = load(key)
    if arrays is None:
        return None
    try:
        return decode(arrays)
    except _UNREADABLE as exc:
        _evict(cache_dir() / (key + SUFFIX), f"malformed ({exc})")
        return None


def _csr_arrays(prefix: str, a) -> dict[str, np.ndarray]:
    a = sp.csr_matrix(a)
    return {f"{prefix}_data": a.data, f"{prefix}_indices": a.indices,
            f"{prefix}_indptr": a.indptr, f"{prefix}_shape": np.asarray(a.shape, np.int64)}


def _csr(arrays: Mapping[str, np.ndarray], prefix: str) -> sp.csr_matrix:
    shape = tuple(int(n) for n in arrays[f"{prefix}_shape"])
    return sp.csr_matrix((arrays[f"{prefix}_data"], arrays[f"{prefix}_indices"],
                          arrays[f"{prefix}_indptr"]), shape=shape)


def fe_key(source: Mapping, material: Material) -> str:
    """Entry name of the consistent-mass FE model of mesh ``source`` in ``material``."""
    return make_key("fe", {"mesh": source, "material": material_inputs(material)})


def _fe_from(arrays: Mapping[str, np.ndarray], mesh: Mesh, material: Material) -> FEModel:
    M, K, Ms = _csr(arrays, "M"), _csr(arrays, "K"), _csr(arrays, "M_scalar")
    n = 3 * mesh.n_nodes
    if M.shape != (n, n) or K.shape != (n, n) or Ms.shape != (n // 3, n // 3):
        raise ValueError("stored FE model does not match the mesh")
    mass, volume = (float(x) for x in arrays["mass_volume"])
    return FEModel(mesh, material, M, K, Ms, mass, volume)


def cached_fe(source: Mapping | None, mesh: Mesh, material: Material,
              build: Callable[[Mesh, Material], FEModel]) -> FEModel:
    """The FE model of ``mesh`` (described by ``source``) from the cache, else built and stored.

    source: rod_source(spec) or file_source(path); None disables caching for this model.
    build: e.g. flexmvm.fe.assembly.assemble (consistent mass).
    """
    if source is None:
        return build(mesh, material)
    key = fe_key(source, material)
    hit = _decoded(key, lambda arrays: _fe_from(arrays, mesh, material))
    if hit is not None:
        return hit
    fe = build(mesh, material)
    save(key, {**_csr_arrays("M", fe.M), **_csr_arrays("K", fe.K),
               **_csr_arrays("M_scalar", fe.M_scalar),
               "mass_volume": np.array([fe.mass, fe.volume])})
    return fe


def _basis_inputs(source: Mapping, material: Material, kind: BasisKind, reference_set: str,
                  reference: ReferenceCondition, retained: np.ndarray, n_modes: int,
                  extra: Mapping | None = None) -> dict:
    """Key inputs shared by a basis and the body parts built on it; ``extra``: the further
    parameters of a kind (an interface basis: InterfaceSpec.key(), its patch and mode
    choice), left out when None so that the keys of the other kinds do not change."""
    inputs = {"mesh": source, "material": material_inputs(material), "kind": kind.value,
              "reference": {"set": reference_set, "fixed_dofs": reference.fixed_dofs.tolist()},
              "retained": [int(k) for k in retained], "n_modes": int(n_modes)}
    return inputs if extra is None else inputs | {"extra": dict(extra)}


def basis_key(source: Mapping, material: Material, kind: BasisKind, reference_set: str,
              reference: ReferenceCondition, retained: np.ndarray, n_modes: int,
              version: str | None = None, extra: Mapping | None = None) -> str:
    """Entry name of a basis: its FE model's inputs, kind, reference, retained nodes, modes
    and the kind's further parameters ``extra``."""
    inputs = _basis_inputs(source, material, kind, reference_set, reference, retained, n_modes,
                           extra)
    return make_key("basis", inputs, version)


def body_key(source: Mapping, material: Material, kind: BasisKind, reference_set: str,
             reference: ReferenceCondition, retained: np.ndarray, n_modes: int,
             version: str | None = None, extra: Mapping | None = None) -> str:
    """Entry name of a body's parts: the inputs of its basis, under the BODY_SOURCES version."""
    inputs = _basis_inputs(source, material, kind, reference_set, reference, retained, n_modes,
                           extra)
    return make_key("body", inputs, code_version(BODY_SOURCES) if version is None else version)


def _basis_from(arrays: Mapping[str, np.ndarray], kind: BasisKind,
                reference: ReferenceCondition, retained: np.ndarray, n_modes: int) -> Basis:
    psi = _csr(arrays, "psi") if "psi_shape" in arrays else arrays["psi"]
    nodes, freqs = arrays["retained_nodes"], arrays["mode_freqs_hz"]
    if kind is not BasisKind.FULL and not np.array_equal(nodes, retained):
        raise ValueError("stored retained nodes differ")
    if freqs.shape != (n_modes,) or psi.ndim != 2:
        raise ValueError("stored basis is malformed")
    return Basis(kind, psi, nodes.astype(np.int64), n_modes, reference, freqs)


def cached_basis(source: Mapping | None, material: Material, kind: BasisKind,
                 reference_set: str, reference: ReferenceCondition, retained: np.ndarray,
                 n_modes: int, build: Callable[[], Basis], extra: Mapping | None = None) -> Basis:
    """The basis from the cache, else ``build()`` stored; source None: build, no caching.
    extra: the kind's further parameters (basis_key)."""
    if source is None:
        return build()
    key = basis_key(source, material, kind, reference_set, reference, retained, n_modes,
                    extra=extra)
    hit = _decoded(key, lambda arrays: _basis_from(arrays, kind, reference, retained, n_modes))
    if hit is not None:
        return hit
    basis = build()
    psi = (_csr_arrays("psi", basis.psi) if sp.issparse(basis.psi)
           else {"psi": np.ascontiguousarray(basis.psi)})
    save(key, {**psi, "retained_nodes": basis.retained_nodes,
               "mode_freqs_hz": basis.mode_freqs_hz})
    return basis


def free_modes_key(source: Mapping, material: Material, n_modes: int,
                   version: str | None = None) -> str:
    """Entry name of the lowest ``n_modes`` free-free modes (six rigid-body modes included) of
    mesh ``source`` in ``material`` (fe.modes.free_modes, default shift)."""
    return make_key("freemodes", {"mesh": source, "material": material_inputs(material),
                                  "free_modes": int(n_modes)}, version)


def cached_free_modes(source: Mapping | None, material: Material, n_modes: int, n_dof: int,
                      build: Callable[[], tuple[np.ndarray, np.ndarray]]
                      ) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies [Hz] (n_modes,), modes (n_dof, n_modes)) from the cache, else ``build()``
    (fe.modes.free_modes(fe, n_modes)) stored; source None: build, no caching."""
    if source is None:
        return build()
    key = free_modes_key(source, material, n_modes)

    def decode(arrays):
        f_hz, modes = arrays["freqs_hz"], arrays["modes"]
        if f_hz.shape != (n_modes,) or modes.shape != (n_dof, n_modes) \
                or modes.dtype != np.float64:
            raise ValueError("stored free-free modes are malformed")
        return f_hz, modes

    hit = _decoded(key, decode)
    if hit is not None:
        return hit
    f_hz, modes = build()
    save(key, {"freqs_hz": np.asarray(f_hz), "modes": np.ascontiguousarray(modes)})
    return f_hz, modes


def patch_statics_key(source: Mapping, material: Material, reference_set: str,
                      reference: ReferenceCondition, surface: str, node: int,
                      radii_m: tuple[float, ...], version: str | None = None) -> str:
    """Entry name of the inertia-relieved static responses of the Hertz patch loads of
    ``radii_m`` about node ``node`` of facet set ``surface`` (reduction.interface
    relieved_statics), under the reference condition."""
    return make_key("patchstatic", {
        "mesh": source, "material": material_inputs(material),
        "reference": {"set": reference_set, "fixed_dofs": reference.fixed_dofs.tolist()},
        "surface": surface, "patch_node": int(node), "radii_m": [float(a) for a in radii_m]},
        version)


def cached_patch_statics(source: Mapping | None, material: Material, reference_set: str,
                         reference: ReferenceCondition, surface: str, node: int,
                         radii_m: tuple[float, ...], n_dof: int,
                         build: Callable[[], np.ndarray]) -> np.ndarray:
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

    hit = _decoded(key, decode)
    if hit is not None:
        return hit
    static = build()
    save(key, {"static": np.ascontiguousarray(static)})
    return static


def _parts_arrays(parts: BodyParts) -> dict[str, np.ndarray]:
    """Arrays of an entry: mass (1,), S0, S1, G0, G1 (3, 3, nq), G2 (3, 3, nq, nq), M_qq, k_hat."""
    inv, nq = parts.inv, parts.inv.nq
    G1 = np.array([[inv.G1[a][b] for b in range(3)] for a in range(3)]).reshape(3, 3, nq)
    G2 = np.array([[inv.G2[a][b] for b in range(3)] for a in range(3)]).reshape(3, 3, nq, nq)
    return {"mass": np.array([inv.mass]), "S0": inv.S0, "S1": inv.S1, "G0": inv.G0, "G1": G1,
            "G2": G2, "M_qq": inv.M_qq, "k_hat": parts.k_hat}


def _parts_from(arrays: Mapping[str, np.ndarray], nq: int) -> BodyParts:
    a = arrays
    shapes = {"mass": (1,), "S0": (3,), "S1": (3, nq), "G0": (3, 3), "G1": (3, 3, nq),
              "G2": (3, 3, nq, nq), "M_qq": (nq, nq), "k_hat": (nq, nq)}
    if any(a[name].shape != shape or a[name].dtype != np.float64
           for name, shape in shapes.items()):
        raise ValueError("stored body parts are malformed")
    G1 = tuple(tuple(a["G1"][i, j] for j in range(3)) for i in range(3))
    G2 = tuple(tuple(a["G2"][i, j] for j in range(3)) for i in range(3))
    inv = InertiaInvariants(float(a["mass"][0]), a["S0"], a["S1"], a["G0"], G1, G2, a["M_qq"])
    return BodyParts(inv, a["k_hat"])


def cached_body(source: Mapping | None, material: Material, kind: BasisKind,
                reference_set: str, reference: ReferenceCondition, retained: np.ndarray,
                n_modes: int, nq: int, build: Callable[[], BodyParts],
                extra: Mapping | None = None) -> BodyParts:
    """A body's parts (invariants, k_hat) from the cache, else ``build()`` stored.

    The arguments up to n_modes are those of its basis (cached_basis); nq: its number of
    columns. Only dense parts are stored: a full-FE body (sparse parts, ~0.3 s to compute, as
    long as reading them back) and source None are built, not cached.
    """
    if source is None or kind is BasisKind.FULL:
        return build()
    key = body_key(source, material, kind, reference_set, reference, retained, n_modes,
                   extra=extra)
    hit = _decoded(key, lambda arrays: _parts_from(arrays, nq))
    if hit is not None:
        return hit
    parts = build()
    if parts.inv.Ms is None and not sp.issparse(parts.k_hat):
        save(key, _parts_arrays(parts))
    return parts


__all__ = ["BODY_SOURCES", "CHECKSUM", "CODE_SOURCES", "ENV_DIR", "ENV_OFF", "CacheInfo", "basis_key",
           "body_key", "cache_dir", "cached_basis", "cached_body", "cached_fe",
           "cached_free_modes", "cached_patch_statics", "checksum", "clear", "code_version",
           "enabled", "entry_problem", "fe_key", "file_source", "free_modes_key", "info",
           "load", "make_key", "material_inputs", "patch_statics_key", "rod_source", "save"]
