"""The history CSV shared by runs and theory: t_s,contact_force_N,<probe>_vx_mps,..."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from flexmvm.errors import InputError
from flexmvm.results.atomic import write_text_atomic


def write_history(path: Path, t, force, probe_v: dict[str, np.ndarray], axis: str = "x") -> Path:
    """Write the history CSV atomically: t_s,contact_force_N,<probe>_v<axis>_mps,... with
    floats in repr form (they read back bit for bit)."""
    cols = [np.asarray(t, float), np.asarray(force, float)] + [np.asarray(v, float) for v in probe_v.values()]
    header = ["t_s", "contact_force_N"] + [f"{name}_v{axis}_mps" for name in probe_v]
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
    probes = {h[: -len("_vx_mps")]: data[:, i] for i, h in enumerate(header) if h.endswith("_vx_mps")}
    return data[:, 0], data[:, 1], probes
