"""Writers of a RunResult: history CSV, summary JSON, HDF5 archive, ParaView series.

Every file is written atomically (results/atomic.py): a reader sees the previous file or the
complete new one. Units are SI and named in CSV headers and HDF5 ``units`` attributes.
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import h5py
import numpy as np

from flexmvm.bodies.body import FlexibleBody
from flexmvm.errors import InputError
from flexmvm.integrate.run_result import RunResult
from flexmvm.materials import Material
from flexmvm.results.atomic import atomic_path, write_json_atomic, write_text_atomic
from flexmvm.results.fields import (
    StressOperator,
    body_geometry,
    nodal_fields,
    reference_positions,
)
from flexmvm.results.history import write_history
from flexmvm.results.vtu import VtuSeries

__all__ = [
    "MAX_PARAVIEW_STEPS",
    "default_every",
    "write_history_csv",
    "write_paraview_series",
    "write_results_h5",
    "write_summary_json",
]

#: Default cap on the number of time steps of a ParaView series.
MAX_PARAVIEW_STEPS = 100

_AXES = "xyz"
_SAFE_NAME = re.compile(r"^[A-Za-z0-9_.\-]+$")


def _safe_name(kind: str, name: str) -> str:
    if not _SAFE_NAME.match(name):
        raise InputError(
            f"{kind} name {name!r} cannot be used in a file name or column header; "
            "expected letters, digits, '_', '.', '-'"
        )
    return name


def _check_run(run: RunResult) -> int:
    """Number of outputs; InputError unless run's arrays agree with its time axis."""
    n = len(run.t)
    checks = {
        "contact_force": (run.contact_force, (n,)),
        "probe_v": (run.probe_v, (n, len(run.probe_names), 3)),
        "probe_x": (run.probe_x, (n, len(run.probe_names), 3)),
        "frame_r": (run.frame_r, (n, len(run.body_names), 3)),
        "frame_v": (run.frame_v, (n, len(run.body_names), 6)),
        "frame_A": (run.frame_A, (n, len(run.body_names), 3, 3)),
    }
    for key, (arr, shape) in checks.items():
        if np.shape(arr) != shape:
            raise InputError(f"RunResult.{key}: expected shape {shape}, got {np.shape(arr)}")
    if len(run.q) != len(run.body_names) or any(len(q) != n for q in run.q):
        raise InputError(f"RunResult.q: expected one (n_out={n}, nq) array per body")
    return n


def write_history_csv(path: str | os.PathLike[str], run: RunResult, probe_axis: int = 0) -> None:
    """CSV of the histories: ``t_s,contact_force_N,<probe>_v<axis>_mps,...``, one row per output.

    Column <probe>_v<axis>_mps is component `probe_axis` (0 = x, the rods' axial direction) of
    the probe's global velocity [m/s]. Floats are written with repr (they read back bit for
    bit). Raises InputError for a probe_axis outside 0..2, a probe name unusable as a header or
    RunResult arrays of inconsistent shapes.
    """
    if isinstance(probe_axis, bool) or probe_axis not in (0, 1, 2):
        raise InputError(f"probe_axis: expected 0, 1 or 2 (x, y, z), got {probe_axis!r}")
    _check_run(run)
    t, force, curves = run.curves(probe_axis)
    probes = {_safe_name("probe", p): np.asarray(v, dtype=float) for p, v in curves.items()}
    write_history(path, t, force, probes, axis=_AXES[probe_axis])


def write_summary_json(path: str | os.PathLike[str], summary: Mapping[str, Any]) -> None:
    """The caller's summary as JSON (sorted keys), atomically; InputError on NaN/inf or values
    JSON cannot hold (see results.atomic.canonical_json)."""
    if not isinstance(summary, Mapping):
        raise InputError(f"summary: expected a mapping, got {type(summary).__name__}")
    write_json_atomic(path, dict(summary))


def _dataset(group: h5py.Group, name: str, data: Any, units: str, description: str = "") -> None:
    ds = group.create_dataset(name, data=np.asarray(data))
    ds.attrs["units"] = units
    if description:
        ds.attrs["description"] = description


def _bodies_by_name(run: RunResult, bodies: Sequence[FlexibleBody]) -> list[FlexibleBody]:
    names = [b.name for b in bodies]
    if names != list(run.body_names):
        raise InputError(
            f"bodies: expected the run's bodies {list(run.body_names)} in order, got {names}"
        )
    return list(bodies)


def _check_every(name: str, every: int) -> int:
    if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 1:
        raise InputError(f"{name}: expected an integer >= 1, got {every!r}")
    return int(every)


def _write_histories(f: h5py.File, run: RunResult) -> None:
    _dataset(f, "time", run.t, "s", "output times")
    _dataset(
        f,
        "contact_force",
        run.contact_force,
        "N",
        "normal contact force, impulse-averaged over the interval ending at each time",
    )
    _dataset(f, "joint_force", run.joint_force, "N", "averaged joint constraint forces")
    drives = f.create_group("drive_torque")
    for name, torque in run.drive_torque.items():
        _dataset(
            drives,
            _safe_name("drive", name),
            torque,
            "N m",
            "drive torque on body 1 about the axis",
        )
    probes = f.create_group("probes")
    for i, name in enumerate(run.probe_names):
        g = probes.create_group(_safe_name("probe", name))
        _dataset(g, "position", run.probe_x[:, i], "m", "global position (n_out, 3)")
        _dataset(g, "velocity", run.probe_v[:, i], "m/s", "global velocity (n_out, 3)")
    energy = f.create_group("energy")
    _dataset(energy, "kinetic", run.kinetic, "J")
    _dataset(energy, "strain", run.strain, "J")
    _dataset(energy, "potential", run.potential, "J", "gravity potential")
    if run.energy_ledger is not None:
        _write_ledger(energy.create_group("ledger"), run.energy_ledger)
    momentum = f.create_group("momentum")
    _dataset(momentum, "linear", run.momentum, "kg m/s", "total, global (n_out, 3)")
    _dataset(momentum, "angular", run.angular_momentum, "kg m^2/s", "about the origin (n_out, 3)")
    iv = np.asarray(run.contact_intervals, dtype=float).reshape(-1, 2)
    _dataset(f, "contact_intervals", iv, "s", "(start, end) of each contact interval")


def _write_ledger(g: h5py.Group, led) -> None:
    """The energy ledger's cumulative works and dissipations (integrate.energy_ledger)."""
    g.attrs["load_names"] = json.dumps(led.load_names)
    g.attrs["joint_names"] = json.dumps(led.joint_names)
    _dataset(g, "loads", led.loads, "J", "work of each load (n_out, n_loads), load_names")
    _dataset(g, "load_damping", led.load_damping, "J", "dissipated by each load's damper")
    _dataset(g, "load_energy", led.load_energy, "J", "energy stored in each spring")
    _dataset(g, "joints", led.joints, "J", "work of each joint's impulses, joint_names")
    _dataset(g, "contact", led.contact, "J", "work of the contact impulses")
    _dataset(g, "damping", led.damping, "J", "dissipated by the bodies' damping")
    _dataset(g, "numerical", led.numerical, "J", "the scheme's numerical dissipation")
    if led.stiffening is not None:
        _dataset(g, "stiffening", led.stiffening, "J", "work of the geometric stiffening force")
    if led.plastic is not None:
        _dataset(g, "plastic", led.plastic, "J", "plastic work of the plastic bodies")


def _write_mesh(g: h5py.Group, body: FlexibleBody) -> None:
    mesh = g.create_group("mesh")
    _dataset(mesh, "nodes", body.X, "m", "undeformed nodes, body frame (n, 3)")
    if body.mesh is not None:
        for block in body.mesh.cells:
            _dataset(
                mesh,
                f"cells_{block.cell_type.value}",
                block.connectivity,
                "1",
                "node ids, meshio/VTK node order",
            )


def _write_body(g: h5py.Group, run: RunResult, b: int, body: FlexibleBody, idx: np.ndarray) -> None:
    g.attrs["nq"] = body.nq
    g.attrs["label"] = body.label
    _dataset(g, "time_index", idx, "1", "rows of /time these fields belong to")
    _dataset(g, "r", run.frame_r[idx, b], "m", "frame origin, global (k, 3)")
    _dataset(g, "A", run.frame_A[idx, b], "1", "rotation body -> global (k, 3, 3)")
    _dataset(
        g,
        "frame_velocity",
        run.frame_v[idx, b],
        "m/s, rad/s",
        "[r_dot (global), omega (body frame)] (k, 6)",
    )
    _dataset(
        g,
        "q",
        np.asarray(run.q[b])[idx],
        "basis units",
        "elastic coordinates (k, nq); nodal displacement u = psi q [m]",
    )
    if len(run.q_dot) > b:
        _dataset(
            g,
            "q_dot",
            np.asarray(run.q_dot[b])[idx],
            "basis units / s",
            "rates of the elastic coordinates (k, nq)",
        )
    _write_mesh(g, body)


def write_results_h5(
    path: str | os.PathLike[str],
    run: RunResult,
    bodies: Sequence[FlexibleBody],
    fields_every: int = 1,
) -> None:
    """HDF5 archive of a run, written atomically (temporary file, then rename).

    Layout (every dataset carries a ``units`` attribute): /time (n_out,) [s], /contact_force
    (n_out,) [N], /joint_force (n_out, n_rows) [N], /drive_torque/<joint name> (n_out,) [N m]
    (driven joints: constraints.drives), /contact_intervals (k, 2) [s],
    /probes/<name>/{position [m], velocity [m/s]} (n_out, 3), /energy/{kinetic, strain,
    potential} [J] and /energy/ledger/{loads, load_damping, load_energy, joints, contact,
    damping, numerical} [J] (integrate.energy_ledger), /momentum/{linear [kg m/s], angular [kg m^2/s]} (n_out, 3), and per body
    /bodies/<name>/{time_index, r (k, 3), A (k, 3, 3), frame_velocity (k, 6), q (k, nq),
    q_dot (k, nq)} at every `fields_every`-th output (rows time_index of /time), /bodies/<name>/mesh/{nodes (n, 3),
    cells_<meshio type> (n_cells, npc)}. Root attributes: run counters. `bodies` must be the
    run's bodies in order. Raises InputError on inconsistent inputs.
    """
    fields_every = _check_every("fields_every", fields_every)
    n = _check_run(run)
    bodies = _bodies_by_name(run, bodies)
    idx = np.arange(0, n, fields_every)
    with atomic_path(path) as tmp, h5py.File(tmp, "w") as f:
        f.attrs["format"] = "flexmvm-run"
        f.attrs["n_steps"] = run.n_steps
        f.attrs["n_factorizations"] = run.n_factorizations
        f.attrs["wall_time_s"] = run.wall_time_s
        f.attrs["max_penetration_m"] = run.max_penetration_m
        _write_histories(f, run)
        group = f.create_group("bodies")
        for b, body in enumerate(bodies):
            _write_body(group.create_group(_safe_name("body", body.name)), run, b, body, idx)


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
    """ParaView time series: ``<out_dir>/<body>_<i:06d>.vtu`` at every `every`-th output i and
    one collection ``<out_dir>/<body>.pvd`` per body listing them with their times [s].

    Points are the undeformed body at the initial frame, r0 + A0 X (output 0); point data:
    ``displacement`` (n, 3) global [m] (Warp By Vector gives the deformed body),
    ``velocity`` (n, 3) global [m/s] and ``von_mises`` (n,) [Pa] (results/fields.py: the
    elastic stress of the displacement, plastic strain not subtracted); cell data of a plastic
    body: ``equivalent_plastic_strain`` (n_cells,) [-] (integrate.plastic_bodies). The
    elastic part of the velocity uses the run's q_dot. every=None writes at most
    MAX_PARAVIEW_STEPS steps. `bodies` and `materials` follow run.body_names. Each file is
    written atomically, the .pvd last. Returns out_dir (created if missing). Raises
    InputError on inconsistent inputs or a body without a mesh.
    """
    n = _check_run(run)
    bodies = _bodies_by_name(run, bodies)
    if len(materials) != len(bodies):
        raise InputError(f"materials: expected {len(bodies)} (one per body), got {len(materials)}")
    every = default_every(n) if every is None else _check_every("every", every)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    pending = None
    with ThreadPoolExecutor(max_workers=2) as pool:  # zlib releases the GIL
        for b, (body, material) in enumerate(zip(bodies, materials)):
            name = _safe_name("body", body.name)
            q, q_dot = _body_rates(run, b, body, n)
            entries, writes = _submit_body_series(
                pool, out, name, run, b, body, material, q, q_dot, np.arange(0, n, every)
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
    q = np.asarray(run.q[b], dtype=float)
    if q.shape != (n, body.nq):
        raise InputError(f"RunResult.q[{b}]: expected shape {(n, body.nq)}, got {q.shape}")
    q_dot = np.asarray(run.q_dot[b], dtype=float) if len(run.q_dot) > b else None
    if q_dot is None or q_dot.shape != q.shape:
        raise InputError(
            f"RunResult.q_dot[{b}]: expected shape {q.shape} (the rates "
            f"of q), got {None if q_dot is None else q_dot.shape}"
        )
    return q, q_dot


def _submit_body_series(pool, out, name, run, b, body, material, q, q_dot, idx):
    """The fields of body b (named ``name`` in the files) at the outputs idx, computed here, and
    their .vtu files submitted to the thread pool. Returns (entries: (time [s], file name)
    per output, the pool's futures of the writes)."""
    geometry = body_geometry(body)
    stress = StressOperator(geometry, material)
    # psi q and the stresses of all written outputs at once (one pass over psi, one
    # product per cell for all fields: StressOperator.von_mises_series)
    U, Ud = _elastic_series(body, q[idx]), _elastic_series(body, q_dot[idx])
    vm = stress.von_mises_series(U)
    # the points (the undeformed body at output 0) and the cells are the same in
    # every file: encoded once
    series = VtuSeries(
        reference_positions(body, run.frame_r[0, b], run.frame_A[0, b]),
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
            q[i],
            run.frame_v[i, b],
            q_dot[i],
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
            "displacement": fl.displacement,
            "velocity": fl.velocity,
            "von_mises": fl.von_mises,
        }
        cells = None
        if plastic is not None:  # volume average per cell of its points' alpha
            cells = {"equivalent_plastic_strain": plastic.cell_history[i]}
        writes.append(pool.submit(series.write, out / fname, fields, cells))
        entries.append((float(run.t[i]), fname))
    return entries, writes
