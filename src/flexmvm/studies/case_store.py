"""Stored cases of a study: a :class:`Case` (a file-name-safe key and JSON :class:`Params`)
and its record ``out_dir/cases/<key>.json`` = ``{"key", "params", "result", "result_sha256",
"version"}``, checked before it is reused (studies/runner.py module doc): readable, of the
current ``version``, the params of the case (else another study: refused) and the result
whose SHA-256 was written with it.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import warnings
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from flexmvm.errors import InputError
from flexmvm.results.atomic import canonical_json
from flexmvm.runs.provenance import stamp_mismatch

__all__ = [
    "CASES_DIR",
    "Case",
    "Params",
    "announce_stale",
    "case_path",
    "collect",
    "error_path",
    "load_stored",
    "read_record",
    "result_sha256",
]

_KEY_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,199}")
CASES_DIR = "cases"


class Params(Mapping[str, Any]):
    """Read-only, hashable, picklable mapping of JSON parameters.

    Built from any JSON-serialisable mapping; values are stored in their JSON form (tuples
    become lists, numpy scalars Python numbers), and a nested list or dict is returned as a
    copy so the parameters cannot change after construction. Equality and hash follow the
    canonical JSON text, so ``1`` and ``1.0`` are different parameters, as in the stored file.

    Raises:
        InputError: a key is not a string, or a value is not JSON (NaN/inf included).
    """

    __slots__ = ("_canonical", "_data")

    def __init__(self, data: Mapping[str, Any]) -> None:
        if not isinstance(data, Mapping):
            raise InputError(f"case params: received {type(data).__name__}, expected a mapping")
        bad = [k for k in data if not isinstance(k, str)]
        if bad:
            raise InputError(f"case params: received key {bad[0]!r}, expected string keys")
        canonical = canonical_json(dict(data))
        self._canonical = canonical
        self._data: dict[str, Any] = json.loads(canonical)

    def __getitem__(self, key: str) -> Any:
        value = self._data[key]
        return json.loads(json.dumps(value)) if isinstance(value, (list, dict)) else value

    def __iter__(self) -> Iterator[str]:
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Params):
            return self._canonical == other._canonical
        if isinstance(other, Mapping):
            return self._data == dict(other)
        return NotImplemented

    def __hash__(self) -> int:
        return hash(self._canonical)

    def __reduce__(self) -> tuple[Any, ...]:
        return (Params, (self._data,))

    def __repr__(self) -> str:
        return f"Params({self._canonical})"

    def to_dict(self) -> dict[str, Any]:
        """A fresh plain ``dict`` of the parameters (JSON form)."""
        return json.loads(self._canonical)

    @property
    def canonical(self) -> str:
        """Canonical JSON text (sorted keys, no spaces beyond ``json.dumps`` defaults)."""
        return self._canonical


@dataclass(frozen=True)
class Case:
    """One run of a study: a stable, file-name-safe ``key`` and JSON ``params``.

    ``key`` names the stored file (``cases/<key>.json``); it must match
    ``[A-Za-z0-9][A-Za-z0-9._-]*`` (at most 200 characters), e.g. ``"l2-j3-m13"``. ``params``
    is converted to a read-only, hashable :class:`Params`, so cases can be set members and
    dictionary keys and are cheap to send to Dask workers.

    Raises:
        InputError: the key is not file-name-safe, or the params are not JSON.
    """

    key: str
    params: Mapping[str, Any]

    def __post_init__(self) -> None:
        if not isinstance(self.key, str) or not _KEY_RE.fullmatch(self.key):
            raise InputError(
                f"case key {self.key!r}: expected a file-name-safe string "
                "[A-Za-z0-9][A-Za-z0-9._-]* of at most 200 characters"
            )
        if not isinstance(self.params, Params):
            object.__setattr__(self, "params", Params(self.params))


def case_path(out_dir: str | os.PathLike[str], key: str) -> Path:
    """Path of the stored result of case ``key``: ``out_dir/cases/<key>.json``."""
    return Path(out_dir) / CASES_DIR / f"{key}.json"


def error_path(out_dir: str | os.PathLike[str], key: str) -> Path:
    """Path of the failure record of case ``key``: ``out_dir/cases/<key>.error.txt``."""
    return Path(out_dir) / CASES_DIR / f"{key}.error.txt"


def read_record(path: Path) -> dict[str, Any] | None:
    """The stored ``{"key", "params", "result"}`` record, or None if absent or unreadable."""
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return None
    if not isinstance(record, dict) or not {"key", "params", "result"} <= record.keys():
        return None
    if not isinstance(record["params"], dict) or not isinstance(record["result"], dict):
        return None
    return record


def result_sha256(result: Mapping[str, Any]) -> str:
    """SHA-256 (hex) of a result's canonical JSON: what a stored record is checked against."""
    return hashlib.sha256(canonical_json(dict(result)).encode()).hexdigest()


#: How a changed entry of a study's ``version`` is said.
_VERSION_WORDS = {"reference_sha256": "compared with another reference history"}


def _version_change(stored: Any, current: Any) -> str | None:
    """None if the stored ``version`` is ``current``; else what differs, in words (a
    ``provenance`` entry by runs.provenance.stamp_mismatch, any other by its name)."""
    if canonical_json(stored) == canonical_json(current):
        return None
    if not isinstance(stored, Mapping) or not isinstance(current, Mapping):
        return "stored without a code version (made before cases were keyed)"
    what = []
    for name in sorted(set(stored) | set(current)):
        a, b = stored.get(name), current.get(name)
        if canonical_json(a) == canonical_json(b):
            continue
        if name == "provenance" and isinstance(b, Mapping):
            what.append(stamp_mismatch(a, b) or "another provenance")
        else:
            what.append(_VERSION_WORDS.get(name, f"another {name}"))
    return "; ".join(what)


def load_stored(case: Case, out_dir: Path, version: Any) -> tuple[dict | None, str | None]:
    """(stored result of ``case``, None), or (None, why it must be recomputed: None if there
    is no stored file, else one line: unreadable, another version, an edited result).

    Raises:
        InputError: the stored file holds other params (or another key) for this key, under
            the same version (another study in the same directory).
    """
    path = case_path(out_dir, case.key)
    record = read_record(path)
    if record is None:
        return None, ("unreadable or incomplete case file" if path.exists() else None)
    if version is not None:
        changed = _version_change(record.get("version"), version)
        if changed is not None:
            return None, changed
    stored = canonical_json(record["params"])
    assert isinstance(case.params, Params)
    if record["key"] != case.key or stored != case.params.canonical:
        raise InputError(
            f"{path}: stored params {stored} differ from case params {case.params.canonical}; "
            "expected the same study (use another out_dir or delete the file)"
        )
    if record.get("result_sha256") != result_sha256(record["result"]):
        return None, "result differs from the SHA-256 written with it (edited or damaged)"
    return record["result"], None


def announce_stale(
    stale: dict[str, list[str]], out_dir: Path, announce: Callable[[str], Any]
) -> None:
    """One line per reason: the first case file, how many others, why, "recomputed"."""
    for why, keys in stale.items():
        more = f" and {len(keys) - 1} other case(s)" if len(keys) > 1 else ""
        announce(f"{case_path(out_dir, keys[0])}{more}: {why}: recomputed")


def collect(out_dir: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """All stored cases of the study in ``out_dir``, as ``{"key", "params", "result"}`` dicts,
    sorted by key. Unreadable case files are skipped with a warning (a rerun recomputes them).

    Raises:
        InputError: ``out_dir/cases`` does not exist.
    """
    cases_dir = Path(out_dir) / CASES_DIR
    if not cases_dir.is_dir():
        raise InputError(f"collect: {cases_dir} does not exist; expected a study directory")
    rows = []
    for path in sorted(cases_dir.glob("*.json")):
        if path.name.startswith("."):
            continue
        record = read_record(path)
        if record is None:
            warnings.warn(f"{path}: unreadable or incomplete case file; skipped", stacklevel=2)
            continue
        rows.append({"key": record["key"], "params": record["params"], "result": record["result"]})
    rows.sort(key=lambda row: row["key"])
    return rows
