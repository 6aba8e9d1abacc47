"""Entries read with their large arrays memory-mapped: a run that needs a few rows of a basis
(the contact surface's, a probe's) makes only those pages resident, not the whole basis (a
263,691-DOF plate's ring basis holds GBs of exterior rows). The entry is the store's
(store.save, an uncompressed .npz): a member stored uncompressed is mapped at its offset in
the file; its check (checksum, NaN/inf) reads the file in blocks, so that the check does not
make it resident either.
"""

from __future__ import annotations

import hashlib
import struct
import zipfile
from collections.abc import Callable, Collection, Mapping
from pathlib import Path

import numpy as np

from flexmvm.setup_cache.store import (
    CHECKSUM,
    SUFFIX,
    UNREADABLE,
    array_bytes,
    cache_dir,
    decoded,
    enabled,
    evict,
)

_BLOCK = 1 << 25  # bytes read at a time by the check (32 MB)
_LOCAL_HEADER = struct.Struct("<4s22xHH")  # signature ... file name length, extra length


def _member_array(path: Path, z: zipfile.ZipFile, info: zipfile.ZipInfo) -> np.ndarray:
    """The .npy member ``info`` mapped read-only (np.memmap) when stored uncompressed in C
    order, else read."""
    with z.open(info) as f:
        version = np.lib.format.read_magic(f)
        read_header = (
            np.lib.format.read_array_header_1_0
            if version == (1, 0)
            else np.lib.format.read_array_header_2_0
        )
        shape, fortran, dtype = read_header(f)
        header = f.tell()
    if info.compress_type != zipfile.ZIP_STORED or fortran or dtype.hasobject:
        with z.open(info) as f:
            return np.lib.format.read_array(f, allow_pickle=False)
    with open(path, "rb") as raw:
        raw.seek(info.header_offset)
        sig, n_name, n_extra = _LOCAL_HEADER.unpack(raw.read(_LOCAL_HEADER.size))
    if sig != b"PK\x03\x04":
        raise ValueError("not a zip member header")
    offset = info.header_offset + _LOCAL_HEADER.size + n_name + n_extra + header
    if int(np.prod(shape)) == 0:
        return np.zeros(shape, dtype)
    return np.memmap(path, dtype=dtype, mode="r", offset=offset, shape=shape)


def _stream(a: np.ndarray, digest, finite: list[bool]) -> None:
    """Feed a's bytes to ``digest`` and check them finite: block by block from its file when
    mapped (not making it resident), else whole."""
    if not isinstance(a, np.memmap):
        digest.update(array_bytes(a))
        if a.dtype.kind in "fc" and not np.all(np.isfinite(a)):
            finite[0] = False
        return
    step = max(_BLOCK // a.itemsize, 1) * a.itemsize
    assert a.filename is not None  # a memmap of a file (load_mapped)
    with open(a.filename, "rb") as f:
        f.seek(a.offset)
        left = a.nbytes
        while left:
            block = f.read(min(step, left))
            if not block:
                raise EOFError("mapped array cut short")
            left -= len(block)
            digest.update(block)
            if a.dtype.kind in "fc" and not np.all(np.isfinite(np.frombuffer(block, a.dtype))):
                finite[0] = False


def _problem(arrays: Mapping[str, np.ndarray]) -> str | None:
    """store.entry_problem's checks (the same checksum) without reading mapped arrays into
    memory."""
    if CHECKSUM not in arrays:
        return "no checksum (written by another version or another program)"
    digest, finite = hashlib.sha256(), [True]
    for name in sorted(n for n in arrays if n != CHECKSUM):
        a = arrays[name]
        digest.update(f"{name}\0{a.dtype.str}\0{a.shape}\0".encode())
        _stream(a, digest, finite)
    if not finite[0]:
        return "holds NaN or inf"
    if str(arrays[CHECKSUM]) != digest.hexdigest():
        return "content differs from its checksum"
    return None


def load_mapped(key: str, mapped: Collection[str]) -> dict[str, np.ndarray] | None:
    """store.load with the arrays named in ``mapped`` memory-mapped (read-only)."""
    if not enabled():
        return None
    path = cache_dir() / (key + SUFFIX)
    try:
        with zipfile.ZipFile(path) as z:
            arrays = {}
            for info in z.infolist():
                name = info.filename.removesuffix(".npy")
                if name in mapped:
                    arrays[name] = _member_array(path, z, info)
                else:
                    with z.open(info) as f:
                        arrays[name] = np.lib.format.read_array(f, allow_pickle=False)
        why = _problem(arrays)
    except (FileNotFoundError, NotADirectoryError):
        return None
    except UNREADABLE as exc:
        evict(path, f"unreadable ({type(exc).__name__})")
        return None
    if why is not None:
        evict(path, why)
        return None
    arrays.pop(CHECKSUM)
    return arrays


def decoded_mapped(
    key: str, decode: Callable[[Mapping[str, np.ndarray]], object], mapped: Collection[str]
):
    """store.decoded on load_mapped(key, mapped)."""
    return decoded(key, decode, lambda k: load_mapped(k, mapped))
