"""The disk store of the setup cache: where entries live, their keys (SHA-256 of the canonical
JSON of their inputs and of the code version), atomic writes with a checksum, the check an
entry passes before use (evicted, announced and rebuilt when it fails), info and clear. What
the entries hold and how they are decoded: setup_cache/entries.py; the package docstring
describes both.
"""

from __future__ import annotations

import dataclasses
import errno
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
from flexmvm.errors import InputError, announce_recompute
from flexmvm.materials import Material
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
UNREADABLE = (OSError, EOFError, ValueError, KeyError, TypeError, IndexError, zipfile.BadZipFile)


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
    doc = {
        "format": FORMAT,
        "kind": kind,
        "inputs": inputs,
        "code": code_version() if version is None else version,
    }
    return f"{kind}-{hashlib.sha256(canonical_json(doc).encode()).hexdigest()[:32]}"


def rod_source(spec) -> dict:
    """Key inputs of a generated rod mesh: every RodSpec field (enums by value)."""
    return {
        "rod": {
            k: (v.value if isinstance(v, Enum) else v) for k, v in dataclasses.asdict(spec).items()
        }
    }


def file_source(path: str | os.PathLike[str]) -> dict | None:
    """Key inputs of a mesh file: SHA-256 of its content; None if it cannot be read."""
    try:
        return {"file_sha256": hashlib.sha256(Path(path).read_bytes()).hexdigest()}
    except OSError:
        return None


def material_inputs(material: Material) -> dict:
    """Key inputs of a material: E [Pa], nu [-], rho [kg/m^3] (the name changes nothing)."""
    return {"E": float(material.E), "nu": float(material.nu), "rho": float(material.rho)}


def array_bytes(a: np.ndarray) -> memoryview:
    """The C-order bytes of ``a`` (as a.tobytes() gives them) read in place when it is
    C-contiguous: a hash of a basis of GBs made without copying it (its save's peak held the
    copy beside it: +5.6 GB on a 3,000-node region of a 274k-DOF plate)."""
    a = np.ascontiguousarray(a)
    return a.reshape(-1).data.cast("B") if a.size else memoryview(b"")


def checksum(arrays: Mapping[str, np.ndarray]) -> str:
    """SHA-256 (hex) of an entry's arrays: each name, dtype, shape and C-order bytes, in
    name order (the CHECKSUM array itself left out)."""
    digest = hashlib.sha256()
    for name in sorted(n for n in arrays if n != CHECKSUM):
        a = np.ascontiguousarray(arrays[name])  # (ndim >= 1: a 0-d array hashed as (1,))
        digest.update(f"{name}\0{a.dtype.str}\0{a.shape}\0".encode())
        digest.update(array_bytes(a))
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


def evict(path: Path, why: str) -> None:
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
    except UNREADABLE as exc:  # a corrupt or foreign file: evicted, rebuilt and overwritten
        evict(path, f"unreadable ({type(exc).__name__})")
        return None
    why = entry_problem(arrays)
    if why is not None:
        evict(path, why)
        return None
    arrays.pop(CHECKSUM)
    return arrays


def save(key: str, arrays: Mapping[str, np.ndarray]) -> None:
    """Write entry ``key`` atomically with its checksum; skipped if disabled or unwritable,
    said in one line when the disk is full (the next run would make it again unawares: a
    3,000-node region's 8.8 GB basis, 100 s, on every "warm" run of a full disk)."""
    if not enabled():
        return
    directory = cache_dir()
    try:
        directory.mkdir(parents=True, exist_ok=True)
        with atomic_path(directory / (key + SUFFIX)) as tmp, open(tmp, "wb") as f:
            # the arrays' names are not savez's keywords (numpy's stubs cannot tell)
            np.savez(f, **arrays, **{CHECKSUM: np.array(checksum(arrays))})  # type: ignore[arg-type]
    except (OSError, InputError, ValueError) as exc:  # a read-only or full disk: run on
        if isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT):
            size = sum(np.asarray(a).nbytes for a in arrays.values()) / 1e6
            announce_recompute(
                f"setup cache {key}: not written, no space left in {directory} "
                f"({size:,.0f} MB): the next run makes it again"
            )


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


def decoded(
    key: str,
    decode: Callable[[Mapping[str, np.ndarray]], object],
    loader: Callable[[str], Mapping[str, np.ndarray] | None] | None = None,
):
    """decode(arrays of entry ``key``), or None if the entry is absent or malformed (evicted);
    the arrays read by ``loader(key)`` (default: load; setup_cache.mapped: memory-mapped)."""
    arrays = load(key) if loader is None else loader(key)
    if arrays is None:
        return None
    try:
        return decode(arrays)
    except UNREADABLE as exc:
        evict(cache_dir() / (key + SUFFIX), f"malformed ({exc})")
        return None


def csr_arrays(prefix: str, a) -> dict[str, np.ndarray]:
    """The CSR arrays of sparse matrix ``a`` as entry arrays ``<prefix>_data`` ... ``_shape``."""
    a = sp.csr_matrix(a)
    return {
        f"{prefix}_data": a.data,
        f"{prefix}_indices": a.indices,
        f"{prefix}_indptr": a.indptr,
        f"{prefix}_shape": np.asarray(a.shape, np.int64),
    }


def csr_from(arrays: Mapping[str, np.ndarray], prefix: str) -> sp.csr_matrix:
    """The sparse matrix stored by csr_arrays(prefix, ...)."""
    shape = tuple(int(n) for n in arrays[f"{prefix}_shape"])
    return sp.csr_matrix(
        (arrays[f"{prefix}_data"], arrays[f"{prefix}_indices"], arrays[f"{prefix}_indptr"]),
        shape=shape,
    )
