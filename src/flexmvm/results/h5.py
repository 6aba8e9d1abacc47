"""The HDF5 archive of a run (results.h5): histories at every output, fields (q, q_dot) at the
field outputs (results.field_rows), chunked by row and compressed; read back by results.read.
Written atomically (results/atomic.py)."""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from typing import Any

import h5py
import numpy as np

from flexmvm.bodies.body import FlexibleBody
from flexmvm.integrate.run_result import RunResult
from flexmvm.results.atomic import atomic_path
from flexmvm.results.field_rows import field_selection
from flexmvm.results.run_checks import (
    bodies_by_name,
    check_every,
    check_run,
    field_dtype,
    safe_name,
)

__all__ = ["H5_FIELD_FILTER", "write_results_h5"]


def _dataset(
    group: h5py.Group,
    name: str,
    data: Any,
    units: str,
    description: str = "",
    compress: bool = False,
) -> None:
    data = np.asarray(data)
    opts = {"compression": "gzip", "compression_opts": 4, "shuffle": True} if compress else {}
    ds = group.create_dataset(name, data=data, **(opts if data.size else {}))
    ds.attrs["units"] = units
    if description:
        ds.attrs["description"] = description


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
            safe_name("drive", name),
            torque,
            "N m",
            "drive torque on body 1 about the axis",
        )
    probes = f.create_group("probes")
    for i, name in enumerate(run.probe_names):
        g = probes.create_group(safe_name("probe", name))
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
    _dataset(mesh, "nodes", body.X, "m", "undeformed nodes, body frame (n, 3)", True)
    if body.mesh is not None:
        for block in body.mesh.cells:
            _dataset(
                mesh,
                f"cells_{block.cell_type.value}",
                block.connectivity,
                "1",
                "node ids, meshio/VTK node order",
                True,
            )


#: HDF5 filter of the field datasets (q, q_dot): byte shuffle + gzip level 1, one chunk per
#: output row (a frame reads alone). Measured on the seed striker's q and q_dot (25,767 DOF,
#: 101 rows, t <= 0.2 ms): float64 41.8 MB raw, gzip 1 37.0 MB (2.0 s), shuffle + gzip 1
#: 36.3 MB (1.7 s), shuffle + gzip 4 36.0 MB (1.8 s), shuffle + lzf 37.9 MB (0.8 s); float32
#: 20.9 / 17.2 / 17.1 (0.6 s) / 16.8 (0.9 s) / 18.1 MB (0.4 s): the digits below round-off
#: do not compress, float32 halves them; gzip 1 is within 2 % of gzip 4 at 3/4 of its time.
H5_FIELD_FILTER = {"compression": "gzip", "compression_opts": 1, "shuffle": True}


def _field_dataset(g: h5py.Group, name: str, data: np.ndarray, units: str, description: str):
    """A field dataset (k, nq), chunked by row and compressed (H5_FIELD_FILTER); its dtype
    kept (float32 fields stay float32)."""
    data = np.asarray(data)
    opts = {}
    if data.size:
        opts = dict(H5_FIELD_FILTER, chunks=(1,) + (min(data.shape[1], 1 << 17),))
    ds = g.create_dataset(name, data=data, **opts)
    ds.attrs["units"] = units
    ds.attrs["description"] = description


def _rows(q, nq: int, n_out: int) -> np.ndarray:
    """A body's kept coordinates as (k, nq); a rigid body (nq = 0) gives (n_out, 0), whose
    rows `pos` select as any other's (reshape(-1, 0) has no row count to infer)."""
    q = np.asarray(q)
    return np.zeros((n_out, 0)) if nq == 0 else q.reshape(-1, nq)


def _write_body(g: h5py.Group, run: RunResult, b: int, body: FlexibleBody, rows, pos) -> None:
    """Body b's fields at the outputs `rows` (rows `pos` of run.q[b]) and its mesh."""
    g.attrs["nq"] = body.nq
    g.attrs["label"] = body.label
    _dataset(g, "time_index", rows, "1", "rows of /time these fields belong to")
    _dataset(g, "r", run.frame_r[rows, b], "m", "frame origin, global (k, 3)")
    _dataset(g, "A", run.frame_A[rows, b], "1", "rotation body -> global (k, 3, 3)")
    _dataset(
        g,
        "frame_velocity",
        run.frame_v[rows, b],
        "m/s, rad/s",
        "[r_dot (global), omega (body frame)] (k, 6)",
    )
    dtype = field_dtype(run)
    q = _rows(run.q[b], body.nq, len(run.t))[pos].astype(dtype)
    _field_dataset(
        g, "q", q, "basis units", "elastic coordinates (k, nq); nodal displacement u = psi q [m]"
    )
    if len(run.q_dot) > b:
        q_dot = _rows(run.q_dot[b], body.nq, len(run.t))[pos].astype(dtype)
        _field_dataset(
            g, "q_dot", q_dot, "basis units / s", "rates of the elastic coordinates (k, nq)"
        )
    _write_mesh(g, body)


def write_results_h5(
    path: str | os.PathLike[str],
    run: RunResult,
    bodies: Sequence[FlexibleBody],
    fields_every: int | None = None,
) -> None:
    """HDF5 archive of a run, written atomically (temporary file, then rename).

    Layout (every dataset carries a ``units`` attribute): /time (n_out,) [s], /contact_force
    (n_out,) [N], /joint_force (n_out, n_rows) [N], /drive_torque/<joint name> (n_out,) [N m]
    (driven joints: constraints.drives), /contact_intervals (k, 2) [s],
    /probes/<name>/{position [m], velocity [m/s]} (n_out, 3), /energy/{kinetic, strain,
    potential} [J] and /energy/ledger/{loads, load_damping, load_energy, joints, contact,
    damping, numerical} [J] (integrate.energy_ledger), /momentum/{linear [kg m/s], angular
    [kg m^2/s]} (n_out, 3): the histories, at every output. Per body, the fields
    /bodies/<name>/{time_index, r (k, 3), A (k, 3, 3), frame_velocity (k, 6), q (k, nq),
    q_dot (k, nq)} at the field outputs (rows time_index of /time; results.field_rows:
    fields_every=None: the run's field rows, or about DEFAULT_FIELD_FRAMES (32) of a run that
    kept every output; an integer: every fields_every-th field row), q and q_dot chunked by
    row and compressed (H5_FIELD_FILTER) in the run's field precision
    (RunResult.field_precision); /bodies/<name>/mesh/{nodes (n, 3), cells_<meshio type>
    (n_cells, npc)}; /bodies/<name>/frame/{r, A, velocity} the frame at every output. Root
    attributes: run counters, body_names and probe_names (JSON, in the run's order),
    field_precision; /scenario the resolved scenario's JSON (when known). `bodies` must be the
    run's bodies in order. Raises InputError on inconsistent inputs.
    """
    if fields_every is not None:
        fields_every = check_every("fields_every", fields_every)
    check_run(run)
    bodies = bodies_by_name(run, bodies)
    rows, pos = field_selection(run, fields_every)
    with atomic_path(path) as tmp, h5py.File(tmp, "w") as f:
        f.attrs["format"] = "flexmvm-run"
        f.attrs["n_steps"] = run.n_steps
        f.attrs["n_factorizations"] = run.n_factorizations
        f.attrs["wall_time_s"] = run.wall_time_s
        f.attrs["max_penetration_m"] = run.max_penetration_m
        f.attrs["body_names"] = json.dumps(list(run.body_names))
        f.attrs["probe_names"] = json.dumps(list(run.probe_names))
        f.attrs["probe_axes"] = json.dumps(list(run.probe_axes))
        f.attrs["field_precision"] = run.field_precision.value
        if run.scenario is not None:  # a dataset: an attribute holds at most 64 kB
            f.create_dataset("scenario", data=json.dumps(run.scenario))
        _write_histories(f, run)
        group = f.create_group("bodies")
        for b, body in enumerate(bodies):
            g = group.create_group(safe_name("body", body.name))
            _write_frame_history(g.create_group("frame"), run, b)
            _write_body(g, run, b, body, rows, pos)


def _write_frame_history(g: h5py.Group, run: RunResult, b: int) -> None:
    """Body b's floating frame at every output (a history, beside its fields' rows)."""
    _dataset(g, "r", run.frame_r[:, b], "m", "frame origin, global (n_out, 3)")
    _dataset(g, "A", run.frame_A[:, b], "1", "rotation body -> global (n_out, 3, 3)")
    _dataset(
        g,
        "velocity",
        run.frame_v[:, b],
        "m/s, rad/s",
        "[r_dot (global), omega (body frame)] (n_out, 6)",
    )
