"""A run written by ``flexmvm run`` or ``fm.write_run``, read back: ``read_run(path)``.

The histories (contact force, probes, energies, momenta, frames, at every output) are read
into a RunResult when the folder is opened; the fields (q and q_dot of each body, at the field
outputs) stay in results.h5 until asked for (``fields``, ``elastic``), one body at a time. A
folder written without fields (``--no-fields``) has only history.csv: its curves (t, force,
probe velocities) are there, nothing else.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from flexmvm.errors import InputError
from flexmvm.integrate.run_result import FieldPrecision, ProbeHistory, RunResult
from flexmvm.results.history import read_history
from flexmvm.results.summary_keys import with_current_keys

__all__ = ["FieldFrames", "WrittenRun", "read_run"]


@dataclass(frozen=True)
class FieldFrames:
    """One body's fields as written: t (k,) [s] and rows (k,) of the run's outputs, q and
    q_dot (k, nq) in the precision written (float32 by default: 7 digits)."""

    t: np.ndarray
    rows: np.ndarray
    q: np.ndarray
    q_dot: np.ndarray | None


def _json_attr(f: h5py.File, key: str, default=None):
    value = f.attrs.get(key)
    return default if value is None else json.loads(value)


def _frames(f: h5py.File, names: list[str], n: int) -> tuple[np.ndarray, ...]:
    """(frame_r (n, nb, 3), frame_A (n, nb, 3, 3), frame_v (n, nb, 6)): the frame histories
    (/bodies/<name>/frame); a file written before them: the field rows, NaN elsewhere."""
    r = np.full((n, len(names), 3), np.nan)
    A = np.full((n, len(names), 3, 3), np.nan)
    v = np.full((n, len(names), 6), np.nan)
    for b, name in enumerate(names):
        g = f[f"bodies/{name}"]
        if "frame" in g:
            r[:, b], A[:, b], v[:, b] = g["frame/r"], g["frame/A"], g["frame/velocity"]
        else:
            rows = g["time_index"][()]
            r[rows, b], A[rows, b], v[rows, b] = g["r"], g["A"], g["frame_velocity"]
    return r, A, v


def _histories(f: h5py.File) -> RunResult:
    """The run's histories from an open results.h5 (fields not read: q, q_dot empty)."""
    if f.attrs.get("format") != "flexmvm-run":
        raise InputError(f"{f.filename}: not a flexmvm results.h5 (no format = flexmvm-run)")
    t = f["time"][()]
    n = len(t)
    names = _json_attr(f, "body_names") or sorted(f["bodies"])
    probes = _json_attr(f, "probe_names") or sorted(f["probes"])
    px = np.stack([f[f"probes/{p}/position"][()] for p in probes], axis=1) if probes else None
    pv = np.stack([f[f"probes/{p}/velocity"][()] for p in probes], axis=1) if probes else None
    r, A, v = _frames(f, names, n)
    nq = [int(f[f"bodies/{name}"].attrs["nq"]) for name in names]
    precision = f.attrs.get("field_precision", FieldPrecision.FLOAT64.value)
    return RunResult(
        t=t,
        body_names=list(names),
        frame_r=r,
        frame_v=v,
        probe_names=list(probes),
        probe_axes=list(_json_attr(f, "probe_axes") or []),
        probe_x=px if px is not None else np.zeros((n, 0, 3)),
        probe_v=pv if pv is not None else np.zeros((n, 0, 3)),
        contact_force=f["contact_force"][()],
        joint_force=f["joint_force"][()],
        kinetic=f["energy/kinetic"][()],
        strain=f["energy/strain"][()],
        potential=f["energy/potential"][()],
        momentum=f["momentum/linear"][()],
        angular_momentum=f["momentum/angular"][()],
        q=[np.zeros((0, k)) for k in nq],
        q_dot=[np.zeros((0, k)) for k in nq],
        frame_A=A,
        contact_intervals=[tuple(row) for row in f["contact_intervals"][()]],
        max_penetration_m=float(f.attrs.get("max_penetration_m", 0.0)),
        n_steps=int(f.attrs.get("n_steps", 0)),
        n_factorizations=int(f.attrs.get("n_factorizations", 0)),
        wall_time_s=float(f.attrs.get("wall_time_s", 0.0)),
        drive_torque={k: d[()] for k, d in f["drive_torque"].items()},
        field_index=np.zeros(0, dtype=int),
        field_precision=FieldPrecision(precision),
        scenario=json.loads(f["scenario"][()]) if "scenario" in f else None,
    )


class WrittenRun:
    """A run read back from its folder (read_run): ``result`` its histories (a RunResult whose
    q and q_dot are left in the file; None for a folder without results.h5), ``summary``
    (summary.json), ``scenario`` (the Scenario it ran, when results.h5 keeps it; set by
    flexmvm.read_run, the scenarios stage: this one is below it) and the
    fields of each body from results.h5 on demand (``fields``, ``elastic``). Works where a
    run does: fm.compare, curves, probe."""

    def __init__(self, path: Path, result: RunResult | None, summary: dict, curves):
        self.path, self.result, self.summary = path, result, summary
        self._curves = curves  # history.csv's (t, force, {probe: vx}) of a run without h5
        self.label = path.name
        self.scenario: Any = None  # the Scenario it ran (runs.written_run.read_run)

    @property
    def t(self) -> np.ndarray:
        """Output times [s]."""
        return self.result.t if self.result is not None else self._curves[0]

    @property
    def contact_force(self) -> np.ndarray:
        """Normal contact force at the output times [N]."""
        return self.result.contact_force if self.result is not None else self._curves[1]

    @property
    def scenario_data(self) -> dict | None:
        """The resolved scenario's JSON form as written (None: not kept); the Scenario it
        makes is ``scenario`` (set by flexmvm.read_run)."""
        return None if self.result is None else self.result.scenario

    def _need_h5(self, what: str) -> RunResult:
        if self.result is None:
            raise InputError(f"{self.path}: no results.h5 (written with --no-fields?): no {what}")
        return self.result

    def probe(self, name: str) -> ProbeHistory:
        """Position and velocity history of probe ``name`` (global, [m], [m/s])."""
        return self._need_h5("probe positions").probe(name)

    def curves(self, axis: int | str = 0) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        """(t, contact force, {probe: velocity component ``axis``}) as a run gives them
        (RunResult.curves: 0, 1, 2, "x", "y", "z" or "norm"; without results.h5 x only)."""
        if self.result is None and axis in (0, "x"):
            return self._curves
        return self._need_h5("velocity components but x").curves(axis)

    def fields(self, body: str) -> FieldFrames:
        """Body ``body``'s fields as written (read from results.h5 now)."""
        self._need_h5("fields").body_index(body)
        with h5py.File(self.path / "results.h5", "r") as f:
            g = f[f"bodies/{body}"]
            rows = g["time_index"][()]
            q_dot = g["q_dot"][()] if "q_dot" in g else None
            assert self.result is not None  # _need_h5: a written run has its histories
            return FieldFrames(self.result.t[rows], rows, g["q"][()], q_dot)

    def elastic(self, body: str) -> tuple[np.ndarray, np.ndarray | None]:
        """(q, q_dot) of body ``body`` at its field outputs (fields(body).t)."""
        fr = self.fields(body)
        return fr.q, fr.q_dot

    def dof(self, body: str) -> int:
        """Generalized coordinates of body ``body``: 6 frame + elastic (summary.json)."""
        return int(self.summary["dof"][body])


def read_run(path) -> WrittenRun:
    """The run written in folder ``path`` (``flexmvm run --out``, ``fm.write_run``): its
    histories (results.h5, or history.csv's curves without it), summary.json and the
    scenario it ran; fields stay in results.h5 until asked for. InputError (one line) for a
    folder that holds no written run."""
    d = Path(path)
    if not (d / "history.csv").is_file() and not (d / "results.h5").is_file():
        raise InputError(f"{d}: no written run here; expected history.csv and results.h5")
    try:
        summary = with_current_keys(json.loads((d / "summary.json").read_text()))
    except FileNotFoundError:
        summary = {}
    except (OSError, ValueError) as exc:
        raise InputError(f"{d / 'summary.json'}: not readable JSON ({exc})") from None
    if not (d / "results.h5").is_file():
        return WrittenRun(d, None, summary, read_history(d / "history.csv"))
    try:
        with h5py.File(d / "results.h5", "r") as f:
            result = _histories(f)
    except (OSError, KeyError) as exc:
        raise InputError(f"{d / 'results.h5'}: not a readable run archive ({exc})") from None
    return WrittenRun(d, result, summary, None)
