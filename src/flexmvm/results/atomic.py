"""Atomic file writes: a reader sees the old file or the complete new one, never a part.

The new content goes to a temporary file in the destination's directory (same file system),
is flushed and fsync'ed, and is then ``os.replace``'d onto the destination, which is atomic on
POSIX and Windows. A crash or a kill mid-write leaves at most a stray ``.<name>.*.tmp`` file
beside the destination, never a truncated destination. Studies rely on this: a case file that
exists is a finished case (docs/architecture.md, "studies").
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import tempfile
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from flexmvm.errors import InputError

__all__ = [
    "atomic_path",
    "canonical_json",
    "file_sha256",
    "nulled_nonfinite",
    "write_bytes_atomic",
    "write_json_atomic",
    "write_text_atomic",
]


def _fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_dir(directory: Path) -> None:
    """Persist the rename itself (POSIX); a no-op where directories cannot be opened."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


# The mode a plain open() gives a new file, 0o666 minus the umask (read once, at import,
# before any writer thread: os.umask can only be read by setting it). mkstemp creates 0o600.
_UMASK = os.umask(0)
os.umask(_UMASK)
FILE_MODE = 0o666 & ~_UMASK


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success it replaces ``path`` atomically.

    The caller writes the complete content to the yielded path (it exists, empty). When the
    ``with`` block ends without an exception the file is fsync'ed and ``os.replace``'d onto
    ``path``; when the block raises, the temporary file is removed and ``path`` is untouched.

    Raises:
        InputError: the parent directory of ``path`` does not exist.
    """
    target = Path(path)
    parent = target.parent
    if not parent.is_dir():
        raise InputError(f"cannot write {target}: directory {parent} does not exist")
    fd, tmp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=parent)
    try:
        os.fchmod(fd, FILE_MODE)  # as open() would have created it, not mkstemp's 0o600
    finally:
        os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        _fsync_file(tmp)
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        raise
    _fsync_dir(parent)


def write_bytes_atomic(path: str | os.PathLike[str], data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def write_text_atomic(path: str | os.PathLike[str], text: str, encoding: str = "utf-8") -> None:
    """Write ``text`` to ``path`` atomically (see :func:`atomic_path`), UTF-8 by default."""
    write_bytes_atomic(path, text.encode(encoding))


def _json_default(obj: Any) -> Any:
    """Numpy scalars and arrays become their Python/list form; anything else is refused."""
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"{type(obj).__name__} is not JSON-serialisable")


def _first_nonfinite(obj: Any, where: str) -> str | None:
    """Location (``a.b[3]``) of the first NaN/inf float in a JSON-like tree, or None."""
    if isinstance(obj, (float, np.floating)):
        return None if math.isfinite(obj) else where
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "fc" and not np.all(np.isfinite(obj)):
            index = tuple(int(i) for i in np.argwhere(~np.isfinite(obj))[0])
            return f"{where}{list(index)}"
        return None
    if isinstance(obj, Mapping):
        for key, value in obj.items():
            found = _first_nonfinite(value, f"{where}.{key}" if where else str(key))
            if found is not None:
                return found
    elif isinstance(obj, (list, tuple)):
        for i, value in enumerate(obj):
            found = _first_nonfinite(value, f"{where}[{i}]")
            if found is not None:
                return found
    return None


def nulled_nonfinite(obj: Any, where: str = "") -> tuple[Any, list[str]]:
    """A copy of a JSON-like tree with every NaN/inf float (numpy arrays included) replaced by
    None, and the locations (``a.b[3]``) replaced, in order. A result that must be kept (a
    failed run's summary) is written this way rather than refused: JSON has no NaN/inf."""
    found: list[str] = []

    def walk(x: Any, at: str) -> Any:
        if isinstance(x, (float, np.floating)):
            if math.isfinite(x):
                return x
            found.append(at or "top level")
            return None
        if isinstance(x, np.ndarray):
            return walk(x.tolist(), at) if x.dtype.kind in "fc" else x
        if isinstance(x, Mapping):
            return {k: walk(v, f"{at}.{k}" if at else str(k)) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [walk(v, f"{at}[{i}]") for i, v in enumerate(x)]
        return x

    return walk(obj, where), found


def canonical_json(obj: Any, indent: int | None = None) -> str:
    """JSON text of ``obj`` with sorted keys; numpy scalars/arrays allowed, NaN/inf refused.

    Two objects with the same canonical JSON (``indent=None``) describe the same data, which
    is how studies compare stored parameters with a case's parameters.

    Raises:
        InputError: ``obj`` holds NaN/inf (names the first location) or a value JSON cannot
            represent.
    """
    where = _first_nonfinite(obj, "")
    if where is not None:
        raise InputError(
            f"cannot write JSON: non-finite number at {where or 'top level'}; "
            "expected finite floats only (NaN/inf are not JSON)"
        )
    try:
        return json.dumps(
            obj, sort_keys=True, indent=indent, allow_nan=False, default=_json_default
        )
    except (TypeError, ValueError) as exc:
        raise InputError(f"cannot write JSON: {exc}; expected JSON-serialisable data") from None


def write_json_atomic(path: str | os.PathLike[str], obj: Any) -> None:
    """Write ``obj`` as JSON (sorted keys, indent 2, trailing newline) to ``path`` atomically.

    Raises:
        InputError: ``obj`` holds NaN/inf or a value JSON cannot represent; nothing is written.
    """
    write_text_atomic(path, canonical_json(obj, indent=2) + "\n")


def write_table_csv(path, columns, rows) -> None:
    """A CSV table atomically: header `columns`, one line per row mapping; floats in repr
    form (exact), missing or None cells empty."""
    import csv
    import io

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow(
            [
                "" if r.get(c) is None else (repr(float(r[c])) if isinstance(r[c], float) else r[c])
                for c in columns
            ]
        )
    write_text_atomic(path, buf.getvalue())


def file_sha256(path: str | Path) -> str:
    """SHA-256 of a file's bytes (hex): the identity of a stored result another one refers to."""
    import hashlib

    return hashlib.sha256(Path(path).read_bytes()).hexdigest()
