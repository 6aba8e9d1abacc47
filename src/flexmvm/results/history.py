"""The history CSV shared by runs and theory: t_s,contact_force_N,<probe>_vx_mps,...

A stored history is checked before it is reused: history_record gives what is kept beside it
(the SHA-256 of the bytes written, the number of samples, the first and last time) and
history_problem says in words what is wrong with a file against that record and the window
it must cover (a history cut short, an edited one), or None.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from flexmvm.errors import InputError
from flexmvm.results.atomic import file_sha256, write_text_atomic


def write_history(path: Path, t, force, probe_v: dict[str, np.ndarray], axis: str = "x") -> Path:
    """Write the history CSV atomically: t_s,contact_force_N,<probe>_v<axis>_mps,... with
    floats in repr form (they read back bit for bit)."""
    columns = {f"{name}_v{axis}_mps": v for name, v in probe_v.items()}
    return write_history_columns(path, t, force, columns)


def write_history_columns(path: Path, t, force, columns: dict[str, np.ndarray]) -> Path:
    """Write the history CSV atomically: t_s,contact_force_N and the named columns (their
    headers as given, e.g. <probe>_vz_mps), floats in repr form (they read back bit for bit).
    read_history reads its <probe>_vx_mps columns."""
    cols = [np.asarray(t, float), np.asarray(force, float)] + [
        np.asarray(v, float) for v in columns.values()
    ]
    header = ["t_s", "contact_force_N", *columns]
    buf = io.StringIO()
    buf.write(",".join(header) + "\n")
    for row in np.column_stack(cols):
        buf.write(",".join(repr(float(x)) for x in row) + "\n")
    write_text_atomic(path, buf.getvalue())
    return Path(path)


def read_history(path: Path) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """(t, contact_force, {probe: vx}) from a history CSV; InputError if it is not one."""
    path = Path(path)
    try:
        with open(path) as fh:
            header = fh.readline().strip().split(",")
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except (OSError, ValueError) as exc:
        raise InputError(f"{path}: not a readable history CSV ({exc})") from None
    if header[:2] != ["t_s", "contact_force_N"] or data.shape[1] != len(header):
        raise InputError(f"{path}: expected header t_s,contact_force_N,<probe>_vx_mps,...")
    probes = {
        h[: -len("_vx_mps")]: data[:, i] for i, h in enumerate(header) if h.endswith("_vx_mps")
    }
    return data[:, 0], data[:, 1], probes


def history_record(path: Path) -> dict:
    """What a stored history keeps beside it to be checked: {sha256 (of the file's bytes),
    rows (samples), t_first_s, t_last_s}. InputError if it is not a history CSV."""
    t, _, _ = read_history(path)
    return {
        "sha256": file_sha256(path),
        "rows": len(t),
        "t_first_s": float(t[0]) if len(t) else None,
        "t_last_s": float(t[-1]) if len(t) else None,
    }


def _us(t: float) -> str:
    return f"{1e6 * t:.6g}"


def history_problem(path: Path, record: dict | None, t_end_s: float | None = None) -> str | None:
    """None if the history CSV at ``path`` is the one ``record`` (history_record) describes
    and covers [0, t_end_s]; else what is wrong, one line without the path, e.g. "7 of 31
    samples (expected window 0..30 us)". ``record`` None: only readability and the window."""
    try:
        t, _, _ = read_history(path)
    except InputError:
        return "not a readable history CSV"
    rec = record if isinstance(record, dict) else {}
    t_end = t_end_s if t_end_s is not None else rec.get("t_last_s")
    rows = rec.get("rows")
    short = len(t) == 0 or (t_end is not None and float(t[-1]) < t_end * (1 - 1e-9) - 1e-15)
    if short or (rows is not None and len(t) != rows):
        have = f"{len(t)} of {rows} samples" if rows is not None else f"{len(t)} samples"
        span = f", last at {_us(float(t[-1]))} us" if len(t) else ""
        window = f" (expected window 0..{_us(t_end)} us)" if t_end is not None else ""
        return f"{have}{span}{window}"
    if rec.get("sha256") is not None and file_sha256(path) != rec["sha256"]:
        return "content differs from the SHA-256 recorded when it was written"
    return None
