"""Writers of a RunResult: history CSV, summary JSON, HDF5 archive, ParaView series.

Every file is written atomically (results/atomic.py): a reader sees the previous file or the
complete new one. Units are SI and named in CSV headers and HDF5 ``units`` attributes.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from flexmvm.bodies.body import FlexibleBody
from flexmvm.errors import InputError
from flexmvm.integrate.run_result import RunResult
from flexmvm.materials import Material
from flexmvm.results.atomic import write_json_atomic, write_text_atomic
from flexmvm.results.field_rows import field_selection
from flexmvm.results.fields import (
    StressOperator,
    body_geometry,
    nodal_fields,
    reference_positions,
)
from flexmvm.results.h5 import write_results_h5
from flexmvm.results.history import write_history_columns
from flexmvm.results.run_checks import (
    bodies_by_name,
    check_every,
    check_run,
    field_dtype,
    safe_name,
)
from flexmvm.results.vtu import VtuSeries

__all__ = [
    "MAX_PARAVIEW_STEPS",
    "default_every",
    "write_history_csv",
    "write_paraview_series",
    "write_results_h5",
    "write_summary_json",
]

#: The cap default_every strides to (kept for callers; the series' own default is
#: results.field_rows.DEFAULT_FIELD_FRAMES).
MAX_PARAVIEW_STEPS = 100

_AXES = "xyz"


def write_history_csv(
    path: str | os.PathLike[str], run: RunResult, probe_axis: int | None = 0
) -> None:
    """CSV of the histories, one row per output: ``t_s,contact_force_N`` and per probe its
    global velocity [m/s]: probe_axis 0, 1 or 2 the one column ``<probe>_v<x|y|z>_mps`` (0 = x,
    the rods' axial direction); None every component and the norm,
    ``<probe>_vx_mps,<probe>_vy_mps,<probe>_vz_mps,<probe>_v_mps`` (an impact along y or z
    has its curves there). Floats are written with repr (they read back bit for bit). Raises
    InputError for another probe_axis, a probe name unusable as a header or RunResult arrays
    of inconsistent shapes.
    """
    if probe_axis is not None and (isinstance(probe_axis, bool) or probe_axis not in (0, 1, 2)):
        raise InputError(
            f"probe_axis: expected 0, 1, 2 (x, y, z) or None (all), got {probe_axis!r}"
        )
    check_run(run)
    names = [safe_name("probe", p) for p in run.probe_names]
    v = np.asarray(run.probe_v, dtype=float)
    columns = {}
    for i, name in enumerate(names):
        for k in (0, 1, 2) if probe_axis is None else (probe_axis,):
            columns[f"{name}_v{_AXES[k]}_mps"] = v[:, i, k]
        if probe_axis is None:
            columns[f"{name}_v_mps"] = np.linalg.norm(v[:, i], axis=1)
    write_history_columns(Path(path), run.t, run.contact_force, columns)


def write_summary_json(path: str | os.PathLike[str], summary: Mapping[str, Any]) -> None:
    """The caller's summary as JSON (sorted keys), atomically; InputError on NaN/inf or values
    JSON cannot hold (see results.atomic.canonical_json)."""
    if not isinstance(summary, Mapping):
        raise InputError(f"summary: expected a mapping, got {type(summary).__name__}")
    write_json_atomic(path, dict(summary))


def default_every(n_out: int, max_steps: int = MAX_PARAVIEW_STEPS) -> int:
    """Smallest stride that writes at most max_steps of n_out outputs: ceil(n_out / max_steps)."""
    return max(1, math.ceil(n_out / max_steps))


def _elastic_series(body: FlexibleBody, q: np.ndarray) -> np.ndarray:
    """psi q of every row of q (k, nq): elastic displacements (k, n, 3) [m] in the body frame."""
    n = len(body.X)
    if body.nq == 0:
        return np.zeros((len(q), n, 3))
    return np.asarray(body.psi @ q.T).T.reshape(len(q), n, 3)


def _finish(path: Path, text: str, writes) -> None:
    """Wait for a body's files, then write its collection (last: it lists them)."""
    for w in writes:
        w.result()
    write_text_atomic(path, text)


def _pvd_text(entries: list[tuple[float, str]]) -> str:
    rows = "\n".join(
        f'    <DataSet timestep="{t!r}" group="" part="0" file={quoteattr(name)}/>'
        for t, name in entries
    )
    return (
        '<?xml version="1.0"?>\n'
        '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
        "  <Collection>\n" + rows + "\n  </Collection>\n</VTKFile>\n"
    )


def write_paraview_series(
    out_dir: str | os.PathLike[str],
    run: RunResult,
    bodies: Sequence[FlexibleBody],
    materials: Sequence[Material],
    every: int | None = None,
) -> Path:
    """ParaView time series: ``<out_dir>/<body>_<i:06d>.vtu`` at the field outputs i
    (results.field_rows: every=None: the run's field rows, or about DEFAULT_FIELD_FRAMES (32)
    of a run that kept every output; an integer: every `every`-th field row) and one collection
    ``<out_dir>/<body>.pvd`` per body listing them with their times [s].

    Points are the undeformed body at the initial frame, r0 + A0 X (output 0); point data:
    ``displacement`` (n, 3) global [m] (Warp By Vector gives the deformed body),
    ``velocity`` (n, 3) global [m/s] and ``von_mises`` (n,) [Pa] (results/fields.py: the
    elastic stress of the displacement, plastic strain not subtracted); cell data of a plastic
    body: ``equivalent_plastic_strain`` (n_cells,) [-] (integrate.plastic_bodies). The
    elastic part of the velocity uses the run's q_dot. Point data are written in the run's
    field precision (RunResult.field_precision; points too: float32 resolves 0.1 um at 1 m).
    `bodies` and `materials` follow run.body_names. Each file is written atomically, the .pvd
    last. Returns out_dir (created if missing). Raises InputError on inconsistent inputs or a
    body without a mesh.
    """
    check_run(run)
    bodies = bodies_by_name(run, bodies)
    if len(materials) != len(bodies):
        raise InputError(f"materials: expected {len(bodies)} (one per body), got {len(materials)}")
    every = None if every is None else check_every("every", every)
    rows, pos = field_selection(run, every)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    pending = None
    with ThreadPoolExecutor(max_workers=2) as pool:  # zlib releases the GIL
        for b, (body, material) in enumerate(zip(bodies, materials)):
            name = safe_name("body", body.name)
            q, q_dot = _body_rates(run, b, body, len(run.field_rows))
            entries, writes = _submit_body_series(
                pool, out, name, run, b, body, material, q[pos], q_dot[pos], rows
            )
            # this body's files are written while the next body's fields are computed
            if pending is not None:
                _finish(*pending)
            pending = (out / f"{name}.pvd", _pvd_text(entries), writes)
        if pending is not None:
            _finish(*pending)
    return out


def _body_rates(run: RunResult, b: int, body: FlexibleBody, n: int):
    """(q, q_dot) (n, nq) of body b of the run, as float arrays; InputError on a shape that is
    not the body's."""
    q = np.asarray(run.q[b])
    if q.shape != (n, body.nq):
        raise InputError(f"RunResult.q[{b}]: expected shape {(n, body.nq)}, got {q.shape}")
    q_dot = np.asarray(run.q_dot[b]) if len(run.q_dot) > b else None
    if q_dot is None or q_dot.shape != q.shape:
        raise InputError(
            f"RunResult.q_dot[{b}]: expected shape {q.shape} (the rates "
            f"of q), got {None if q_dot is None else q_dot.shape}"
        )
    return q, q_dot


def _submit_body_series(pool, out, name, run, b, body, material, q, q_dot, idx):
    """The fields of body b (named ``name`` in the files) at the outputs idx (q, q_dot: its
    rows there, (len(idx), nq)), computed here, and their .vtu files submitted to the thread
    pool, in the run's field precision. Returns (entries: (time [s], file name) per output,
    the pool's futures of the writes)."""
    dtype = field_dtype(run)
    q, q_dot = np.asarray(q, dtype=float), np.asarray(q_dot, dtype=float)
    geometry = body_geometry(body)
    stress = StressOperator(geometry, material)
    # psi q and the stresses of all written outputs at once (one pass over psi, one
    # product per cell for all fields: StressOperator.von_mises_series)
    U, Ud = _elastic_series(body, q), _elastic_series(body, q_dot)
    vm = stress.von_mises_series(U)
    # the points (the undeformed body at output 0) and the cells are the same in
    # every file: encoded once
    series = VtuSeries(
        reference_positions(body, run.frame_r[0, b], run.frame_A[0, b]).astype(dtype),
        [(c.cell_type.value, c.connectivity) for c in body.mesh.cells],
    )
    plastic = (run.plastic or {}).get(body.name)  # integrate.plastic_bodies.PlasticReport
    entries, writes = [], []
    for k, i in enumerate(idx):
        fl = nodal_fields(
            body,
            material,
            run.frame_r[i, b],
            run.frame_A[i, b],
            q[k],
            run.frame_v[i, b],
            q_dot[k],
            run.frame_r[0, b],
            run.frame_A[0, b],
            geometry,
            stress=stress,
            u=U[k],
            u_dot=Ud[k],
            von_mises=vm[k],
        )
        fname = f"{name}_{i:06d}.vtu"
        fields = {
            "displacement": fl.displacement.astype(dtype, copy=False),
            "velocity": fl.velocity.astype(dtype, copy=False),
            "von_mises": fl.von_mises.astype(dtype, copy=False),
        }
        cells = None
        if plastic is not None:  # volume average per cell of its points' alpha
            cells = {"equivalent_plastic_strain": plastic.cell_history[i]}
        writes.append(pool.submit(series.write, out / fname, fields, cells))
        entries.append((float(run.t[i]), fname))
    return entries, writes
