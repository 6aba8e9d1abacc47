"""Result writers (CSV, JSON, HDF5, ParaView), nodal fields and the run figure.

The run is built by hand from two real rod bodies (dense and csr psi) moving with a known
motion: r(t) = r0 + v t, A(t) = rotation about z by w t (omega = (0, 0, w) in the body frame),
q(t) = q0 + qd t + qa t^2. The RunResult carries the exact q_dot, which the writers use as
it is, so the written nodal velocities must equal FlexibleBody.node_velocities with the exact
q_dot (to round-off).
"""

from __future__ import annotations

import csv
import dataclasses
import json
import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.errors import InputError
from flexmvm.integrate.energy_ledger import EnergyLedgerHistory
from flexmvm.integrate.run_result import RunResult
from flexmvm.materials import ALUMINIUM, BRASS
from flexmvm.mesh.mesh import CellBlock, CellType, Mesh
from flexmvm.mesh.quality import HEX27_IJK
from flexmvm.mesh.rod import RodSpec, rod_mesh
from flexmvm.plots.figures import curves_from_run, plot_force_comparison, plot_run
from flexmvm.results import fields as fields_module
from flexmvm.results.fields import (
    StressOperator,
    displacement,
    nodal_stress,
    node_positions,
    node_velocities,
    von_mises,
)
from flexmvm.results.vtu import VtuSeries
from flexmvm.results.writers import (
    default_every,
    write_history_csv,
    write_paraview_series,
    write_results_h5,
    write_summary_json,
)

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
SPEC = RodSpec(
    length_m=0.05,
    radius_m=0.01,
    core_elements=1,
    core_half_width_m=0.003,
    n_rings=1,
    first_element_m=0.01,
    growth=1.0,
    max_element_m=0.01,
)
NQ = 4
W = 3.0  # frame spin about z [rad/s]


def _rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@pytest.fixture(scope="module")
def rod():
    return rod_mesh(SPEC)


@pytest.fixture(scope="module")
def bodies(rod):
    mesh = rod.mesh
    n = mesh.n_nodes
    rng = np.random.default_rng(7)
    psi = 1e-4 * rng.standard_normal((3 * n, NQ))
    b1 = FlexibleBody.build(
        "b1", mesh.nodes, sp.identity(n, format="csr"), psi, np.eye(NQ), mesh=mesh
    )
    b2 = FlexibleBody.build(
        "b2",
        mesh.nodes,
        sp.identity(n, format="csr"),
        sp.csr_matrix(psi[:, ::-1]),
        np.eye(NQ),
        mesh=mesh,
    )
    return [b1, b2]


@pytest.fixture(scope="module")
def motion():
    """Per body: r0, v, q0, qd, qa; plus the output times (non-uniform)."""
    t = np.array([0.0, 1e-4, 2e-4, 3.5e-4, 5e-4])
    return t, [
        (
            np.array([-0.05, 0.0, 0.0]),
            np.array([0.21, 0.0, 0.0]),
            np.zeros(NQ),
            np.zeros(NQ),
            np.zeros(NQ),
        ),
        (
            np.array([0.0, 0.01, 0.0]),
            np.array([0.0, 0.0, 0.05]),
            np.array([1.0, -2.0, 0.5, 0.0]),
            np.array([30.0, 10.0, -20.0, 5.0]),
            np.array([1e5, -4e4, 0.0, 2e5]),
        ),
    ]


def _state(t, r0, v, q0, qd, qa):
    """(r, A, q, [r_dot, omega], true q_dot) at time t."""
    return (
        r0 + v * t,
        _rot_z(W * t),
        q0 + qd * t + qa * t**2,
        np.concatenate([v, [0.0, 0.0, W]]),
        qd + 2.0 * qa * t,
    )


@pytest.fixture(scope="module")
def run(rod, bodies, motion):
    t, per_body = motion
    probes = [
        (1, int(rod.mesh.node_set("end_a_centre")[0])),
        (1, int(rod.mesh.node_set("end_b_centre")[0])),
    ]
    n_out, nb = len(t), len(bodies)
    r, A, fv = np.zeros((n_out, nb, 3)), np.zeros((n_out, nb, 3, 3)), np.zeros((n_out, nb, 6))
    qs = [np.zeros((n_out, NQ)) for _ in bodies]
    qds = [np.zeros((n_out, NQ)) for _ in bodies]
    px, pv = np.zeros((n_out, 2, 3)), np.zeros((n_out, 2, 3))
    for i, ti in enumerate(t):
        for b, body in enumerate(bodies):
            r[i, b], A[i, b], qs[b][i], fv[i, b], qds[b][i] = _state(ti, *per_body[b])
        for p, (b, node) in enumerate(probes):
            rb, Ab, qb, fvb, qd = _state(ti, *per_body[b])
            vb = np.concatenate([fvb, qd])
            px[i, p] = bodies[b].node_positions(np.array([node]), rb, Ab, qb)[0]
            pv[i, p] = bodies[b].node_velocities(np.array([node]), Ab, qb, vb)[0]
    force = np.array([0.0, 12.5, 1e3 / 3.0, 7.25, 0.0])
    return RunResult(
        t=t,
        body_names=["b1", "b2"],
        frame_r=r,
        frame_v=fv,
        probe_names=["b2_impact_end", "b2_free_end"],
        probe_x=px,
        probe_v=pv,
        contact_force=force,
        joint_force=np.zeros((n_out, 0)),
        kinetic=np.linspace(1.0, 2.0, n_out),
        strain=np.linspace(0.0, 0.1, n_out),
        potential=np.zeros(n_out),
        momentum=np.ones((n_out, 3)),
        angular_momentum=np.full((n_out, 3), 2.0),
        q=qs,
        q_dot=qds,
        frame_A=A,
        contact_intervals=[(1e-4, 3.5e-4)],
        n_steps=40,
        n_factorizations=2,
        wall_time_s=0.5,
    )


# -- CSV / JSON -----------------------------------------------------------------------------


def test_history_csv_header_and_exact_round_trip(tmp_path, run):
    path = tmp_path / "history.csv"
    write_history_csv(path, run)
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["t_s", "contact_force_N", "b2_impact_end_vx_mps", "b2_free_end_vx_mps"]
    data = np.array(rows[1:], dtype=float)
    assert data.shape == (len(run.t), 4)
    np.testing.assert_array_equal(data[:, 0], run.t)
    np.testing.assert_array_equal(data[:, 1], run.contact_force)
    np.testing.assert_array_equal(data[:, 2:], run.probe_v[:, :, 0])
    assert [p.name for p in tmp_path.iterdir()] == ["history.csv"]


def test_history_csv_other_axis_and_bad_axis(tmp_path, run):
    path = tmp_path / "h.csv"
    write_history_csv(path, run, probe_axis=1)
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    assert path.read_text().splitlines()[0].endswith("b2_free_end_vy_mps")
    np.testing.assert_array_equal(data[:, 2:], run.probe_v[:, :, 1])
    with pytest.raises(InputError, match="probe_axis"):
        write_history_csv(path, run, probe_axis=3)


def test_summary_json(tmp_path):
    path = tmp_path / "summary.json"
    write_summary_json(path, {"ncc": np.float64(0.995), "peak_N": 1234.5, "ok": True})
    assert json.loads(path.read_text()) == {"ncc": 0.995, "ok": True, "peak_N": 1234.5}
    with pytest.raises(InputError, match="non-finite"):
        write_summary_json(path, {"ncc": float("nan")})
    assert json.loads(path.read_text())["ncc"] == 0.995


# -- HDF5 ---------------------------------------------------------------------------------------


def test_results_h5_keeps_the_energy_ledger(tmp_path, run, bodies):
    """/energy/ledger holds the ledger's histories as given, in J, with the loads' and joints'
    names (json) as attributes."""
    n = len(run.t)
    ramp = np.linspace(0.0, 1.0, n)
    led = EnergyLedgerHistory(
        ["push"],
        [],
        ramp[:, None],
        0 * ramp[:, None],
        0 * ramp[:, None],
        np.zeros((n, 0)),
        -ramp,
        0 * ramp,
        0.5 * ramp,
    )
    path = tmp_path / "ledger.h5"
    write_results_h5(path, dataclasses.replace(run, energy_ledger=led), bodies)
    with h5py.File(path, "r") as f:
        g = f["energy/ledger"]
        assert json.loads(g.attrs["load_names"]) == ["push"]
        np.testing.assert_array_equal(g["loads"][()], led.loads)
        np.testing.assert_array_equal(g["contact"][()], -ramp)
        assert g["joints"].shape == (n, 0) and g["numerical"].attrs["units"] == "J"


def test_results_h5_layout_values_and_units(tmp_path, run, bodies, rod):
    path = tmp_path / "run.h5"
    write_results_h5(path, run, bodies, fields_every=2)
    n = len(run.t)
    with h5py.File(path, "r") as f:
        np.testing.assert_array_equal(f["time"][()], run.t)
        assert f["time"].attrs["units"] == "s"
        assert f["contact_force"].attrs["units"] == "N"
        np.testing.assert_array_equal(f["contact_force"][()], run.contact_force)
        for i, name in enumerate(run.probe_names):
            np.testing.assert_array_equal(f[f"probes/{name}/position"][()], run.probe_x[:, i])
            np.testing.assert_array_equal(f[f"probes/{name}/velocity"][()], run.probe_v[:, i])
            assert f[f"probes/{name}/velocity"].attrs["units"] == "m/s"
        for key in ("kinetic", "strain", "potential"):
            assert f[f"energy/{key}"].shape == (n,)
            assert f[f"energy/{key}"].attrs["units"] == "J"
        np.testing.assert_array_equal(f["momentum/linear"][()], run.momentum)
        np.testing.assert_array_equal(f["momentum/angular"][()], run.angular_momentum)
        np.testing.assert_array_equal(f["contact_intervals"][()], [[1e-4, 3.5e-4]])
        assert f.attrs["n_steps"] == 40
        rows = np.arange(0, n, 2)
        for b, body in enumerate(bodies):
            g = f[f"bodies/{body.name}"]
            np.testing.assert_array_equal(g["time_index"][()], rows)
            np.testing.assert_array_equal(g["r"][()], run.frame_r[rows, b])
            np.testing.assert_array_equal(g["A"][()], run.frame_A[rows, b])
            np.testing.assert_array_equal(g["frame_velocity"][()], run.frame_v[rows, b])
            np.testing.assert_array_equal(g["q"][()], run.q[b][rows])
            assert g["q"].shape == (3, NQ)
            np.testing.assert_array_equal(g["mesh/nodes"][()], rod.mesh.nodes)
            assert g["mesh/cells_hexahedron27"].shape == (rod.mesh.n_cells, 27)
    assert [p.name for p in tmp_path.iterdir()] == ["run.h5"]


def test_results_h5_refuses_bodies_out_of_order(tmp_path, run, bodies):
    with pytest.raises(InputError, match="in order"):
        write_results_h5(tmp_path / "x.h5", run, bodies[::-1])
    assert not list(tmp_path.iterdir())


# -- ParaView -------------------------------------------------------------------------------


def test_paraview_series_files_and_point_data(tmp_path, run, bodies, motion):
    t, per_body = motion
    out = write_paraview_series(tmp_path / "pv", run, bodies, [BRASS, ALUMINIUM], every=2)
    written = [0, 2, 4]
    for b, (body, material) in enumerate(zip(bodies, [BRASS, ALUMINIUM])):
        root = ET.parse(out / f"{body.name}.pvd").getroot()
        sets = root.findall("./Collection/DataSet")
        assert [ds.get("file") for ds in sets] == [f"{body.name}_{i:06d}.vtu" for i in written]
        np.testing.assert_array_equal([float(ds.get("timestep")) for ds in sets], t[written])
        r0, A0 = per_body[b][0], np.eye(3)
        for ds, i in zip(sets, written):
            m = meshio.read(out / ds.get("file"))
            np.testing.assert_allclose(m.points, r0 + body.X @ A0.T, rtol=0, atol=1e-15)
            assert m.cells[0].type == "hexahedron27"
            np.testing.assert_array_equal(m.cells[0].data, body.mesh.cells[0].connectivity)
            r, A, q, fv, qd = _state(t[i], *per_body[b])
            x = body.node_positions(np.arange(len(body.X)), r, A, q)
            np.testing.assert_allclose(m.point_data["displacement"], x - m.points, atol=1e-15)
            v_exact = body.node_velocities(np.arange(len(body.X)), A, q, np.concatenate([fv, qd]))
            np.testing.assert_allclose(m.point_data["velocity"], v_exact, rtol=0, atol=1e-9)
            u = np.asarray(body.psi @ q).reshape(-1, 3)
            vm = m.point_data["von_mises"]
            assert vm.shape == (len(body.X),)
            np.testing.assert_allclose(vm, von_mises(body.mesh, material, u), rtol=1e-12)
            assert (vm.max() > 0) == bool(np.any(q))
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [f"{b}_{i:06d}.vtu" for b in ("b1", "b2") for i in written] + ["b1.pvd", "b2.pvd"]
    )


def test_paraview_default_every_caps_steps(tmp_path, run, bodies):
    assert default_every(100) == 1 and default_every(101) == 2 and default_every(250) == 3
    out = write_paraview_series(tmp_path, run, bodies, [BRASS, ALUMINIUM])
    assert len(ET.parse(out / "b2.pvd").getroot().findall("./Collection/DataSet")) == len(run.t)
    with pytest.raises(InputError, match="materials"):
        write_paraview_series(tmp_path, run, bodies, [BRASS])


# -- nodal fields -------------------------------------------------------------------------------


def test_fields_match_body_kinematics(bodies, motion):
    t, per_body = motion
    body = bodies[1]
    r, A, q, fv, qd = _state(t[3], *per_body[1])
    nodes = np.arange(len(body.X))
    np.testing.assert_allclose(
        node_positions(body, r, A, q), body.node_positions(nodes, r, A, q), atol=1e-15
    )
    np.testing.assert_allclose(
        node_velocities(body, A, q, fv, qd),
        body.node_velocities(nodes, A, q, np.concatenate([fv, qd])),
        atol=1e-14,
    )
    u = displacement(body, r, A, q, per_body[1][0], np.eye(3))
    np.testing.assert_allclose(
        u, node_positions(body, r, A, q) - (per_body[1][0] + body.X), atol=1e-15
    )


def _uniaxial(nodes: np.ndarray, sigma: float, material) -> np.ndarray:
    e, nu = material.E, material.nu
    x, y, z = nodes.T
    return np.column_stack([sigma / e * x, -nu * sigma / e * y, -nu * sigma / e * z])


def test_von_mises_uniaxial_on_curved_hex27_rod(rod):
    """u = (s/E x, -nu s/E y, -nu s/E z) is uniaxial stress s along x: von Mises = |s|."""
    s = -3.0e7
    vm = von_mises(rod.mesh, ALUMINIUM, _uniaxial(rod.mesh.nodes, s, ALUMINIUM))
    np.testing.assert_allclose(vm, abs(s), rtol=1e-10, atol=0)
    sig = nodal_stress(rod.mesh, ALUMINIUM, _uniaxial(rod.mesh.nodes, s, ALUMINIUM).ravel())
    np.testing.assert_allclose(sig[:, 0, 0], s, rtol=1e-10)
    np.testing.assert_allclose(sig[:, 1:, 1:], 0.0, atol=1e-10 * abs(s))


_B = np.array([[1.0, 0.3, 0.1], [-0.2, 0.9, 0.25], [0.15, -0.1, 1.1]]) * 0.02  # det > 0
_C = np.array([0.1, -0.05, 0.02])


def _single_cell(cell_type: CellType, distort: float) -> Mesh:
    """One cell: reference nodes mapped by x = B xi + c, corners perturbed by `distort` [m]."""
    tet = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    edges = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]])
    wedge = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1]], float)
    ref = {
        CellType.HEX8: HEX27_IJK[:8] / 2.0,
        CellType.HEX27: HEX27_IJK / 2.0,
        CellType.TET4: tet,
        CellType.TET10: np.vstack([tet, tet[edges].mean(axis=1)]),
        CellType.WEDGE6: wedge,
    }[cell_type]
    x = ref @ _B.T + _C
    x += distort * np.random.default_rng(3).uniform(-1, 1, x.shape)
    return Mesh(x, (CellBlock(cell_type, np.arange(len(x))[None, :]),))


@pytest.mark.parametrize("cell_type", list(CellType))
def test_von_mises_uniaxial_every_cell_type(cell_type):
    mesh = _single_cell(cell_type, distort=1e-3)
    vm = von_mises(mesh, BRASS, _uniaxial(mesh.nodes, 5.0e6, BRASS))
    np.testing.assert_allclose(vm, 5.0e6, rtol=1e-10, atol=0)


@pytest.mark.parametrize("cell_type", [CellType.HEX27, CellType.TET10])
def test_von_mises_quadratic_field_at_nodes(cell_type):
    """u = (a x^2, 0, 0) on an affine quadratic cell is interpolated exactly; at each node
    eps_xx = 2 a x, the rest 0, so s_xx - s_yy = 2 mu eps_xx, s_yy = s_zz, von Mises =
    2 mu |2 a x|. Checks that stresses are evaluated at the right nodes."""
    mesh = _single_cell(cell_type, distort=0.0)
    a = 1e-2
    x = mesh.nodes[:, 0]
    u = np.column_stack([a * x**2, np.zeros_like(x), np.zeros_like(x)])
    _, mu = ALUMINIUM.lame
    vm = von_mises(mesh, ALUMINIUM, u)
    np.testing.assert_allclose(vm, 2 * mu * np.abs(2 * a * x), rtol=1e-9)


def test_von_mises_rejects_bad_shape(rod):
    with pytest.raises(InputError, match="u_local"):
        von_mises(rod.mesh, ALUMINIUM, np.zeros((5, 3)))


@pytest.mark.parametrize("gradient_bytes", [None, 1])
def test_von_mises_series_is_von_mises_of_each_field(rod, monkeypatch, gradient_bytes):
    """The batched path (one product per cell for many fields, a compiled average) gives
    what one field at a time gives, to round-off (1e-12 of the largest stress: the sums run
    in another order); gradient_bytes = 1 takes one field at a time through it (the chunk
    boundaries). The uniaxial field is checked against its closed form, |s|."""
    if gradient_bytes is not None:
        monkeypatch.setattr(fields_module, "SERIES_GRADIENT_BYTES", gradient_bytes)
    op = StressOperator(rod.mesh, ALUMINIUM)
    rng = np.random.default_rng(7)
    U = np.stack(
        [_uniaxial(rod.mesh.nodes, -3.0e7, ALUMINIUM), np.zeros_like(rod.mesh.nodes)]
        + [1e-5 * rng.standard_normal(rod.mesh.nodes.shape) for _ in range(3)]
    )
    vm = op.von_mises_series(U)
    assert vm.shape == (5, rod.mesh.n_nodes)
    np.testing.assert_allclose(vm[0], 3.0e7, rtol=1e-10, atol=0)
    assert not vm[1].any()
    for k in range(2, 5):
        one = op.von_mises(U[k])
        np.testing.assert_allclose(vm[k], one, rtol=0, atol=1e-12 * one.max())
    with pytest.raises(InputError, match="expected shape"):
        op.von_mises_series(U[0])


@pytest.mark.parametrize("cell_type", list(CellType))
def test_von_mises_series_every_cell_type(cell_type):
    mesh = _single_cell(cell_type, distort=1e-3)
    op = StressOperator(mesh, BRASS)
    U = np.stack(
        [
            _uniaxial(mesh.nodes, 5.0e6, BRASS),
            1e-4 * np.random.default_rng(1).standard_normal(mesh.nodes.shape),
        ]
    )
    vm = op.von_mises_series(U)
    np.testing.assert_allclose(vm[0], 5.0e6, rtol=1e-10, atol=0)
    np.testing.assert_allclose(vm[1], op.von_mises(U[1]), rtol=1e-12)


# -- VTU files --------------------------------------------------------------------------------


def _mixed_mesh():
    """Every cell type flexmvm has, in separate blocks of one grid (offsets across blocks)."""
    blocks, points = [], []
    for k, cell_type in enumerate(CellType):
        m = _single_cell(cell_type, distort=1e-3)
        base = sum(len(p) for p in points)
        points.append(m.nodes + [0.1 * k, 0.0, 0.0])
        conn = m.cells[0].connectivity + base
        blocks.append((cell_type.value, np.vstack([conn, conn[:, ::-1]])))
    return np.vstack(points), blocks


def test_vtu_series_reads_back_as_meshio_writes_it(tmp_path):
    """A file of VtuSeries reads back (meshio's reader: the VTK XML format, zlib blocks)
    as the same grid and data a file of meshio's own writer does: every cell type, the
    linear wedge's node order (VTK's differs from meshio's), scalars and vectors."""
    points, cells = _mixed_mesh()
    rng = np.random.default_rng(5)
    data = {"displacement": rng.standard_normal(points.shape), "von_mises": rng.random(len(points))}
    series = VtuSeries(points, cells)
    for k in range(2):  # the encoded grid is reused by every file
        data = {name: v * (k + 1) for name, v in data.items()}
        series.write(tmp_path / f"ours_{k}.vtu", data)
        meshio.write(tmp_path / f"theirs_{k}.vtu", meshio.Mesh(points, cells, point_data=data))
        ours, theirs = (
            meshio.read(tmp_path / f"ours_{k}.vtu"),
            meshio.read(tmp_path / f"theirs_{k}.vtu"),
        )
        np.testing.assert_array_equal(ours.points, points)
        assert (
            [c.type for c in ours.cells] == [c.type for c in theirs.cells] == [c for c, _ in cells]
        )
        for ours_block, theirs_block, (_, conn) in zip(ours.cells, theirs.cells, cells):
            np.testing.assert_array_equal(ours_block.data, conn)
            np.testing.assert_array_equal(theirs_block.data, conn)
        for name, v in data.items():
            np.testing.assert_array_equal(ours.point_data[name], v)
            np.testing.assert_array_equal(theirs.point_data[name], v)
    # the data raw in <AppendedData> (as VTK's own writers): XML up to there
    head = (tmp_path / "ours_0.vtu").read_bytes().split(b"<AppendedData")[0]
    root = ET.fromstring(head + b"</VTKFile>")
    assert (
        root.get("type") == "UnstructuredGrid" and root.get("compressor") == "vtkZLibDataCompressor"
    )
    assert not list(tmp_path.glob(".*.tmp"))  # written atomically, nothing left behind


def test_vtu_series_refuses_bad_input(tmp_path):
    points, cells = _mixed_mesh()
    with pytest.raises(InputError, match="unsupported cell type 'pyramid'"):
        VtuSeries(points, [("pyramid", np.zeros((1, 5), int))])
    with pytest.raises(InputError, match="node index outside"):
        VtuSeries(points, [("tetra", np.array([[0, 1, 2, len(points)]]))])
    with pytest.raises(InputError, match="expected shape"):
        VtuSeries(points[:, :2], cells)
    series = VtuSeries(points, cells)
    with pytest.raises(InputError, match="rows"):
        series.write(tmp_path / "a.vtu", {"v": np.zeros(len(points) - 1)})
    assert not list(tmp_path.iterdir())


# -- figures ----------------------------------------------------------------------------------


def test_plot_run_writes_png(tmp_path, run):
    t, f, v = curves_from_run(run)
    theory = (t, 0.9 * f, {"b2_impact_end": v["b2_impact_end"]})
    path = tmp_path / "fig5.png"
    plot_run(path, {"FE": (t, f, v), "MVM": (t, 1.01 * f, v)}, theory=theory, title="test")
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC and len(data) > 5000
    assert [p.name for p in tmp_path.iterdir()] == ["fig5.png"]
    with pytest.raises(InputError, match="MVM"):
        plot_run(path, {"MVM": (t, f[:-1], v)})


def test_plot_force_comparison(tmp_path, run):
    t = np.linspace(0, 1e-4, 41)
    f = np.sin(np.pi * t / 1e-4) * 1e3
    path = tmp_path / "force.png"
    res = plot_force_comparison(path, (t, f), {"MVM": (t, 1.1 * f)})
    assert path.read_bytes()[:8] == PNG_MAGIC
    assert res["MVM"].ncc == pytest.approx(1.0, abs=1e-12)
    assert res["MVM"].peak_err == pytest.approx(0.1, rel=1e-9)


def test_atomic_files_get_the_mode_open_would_give(tmp_path):
    """mkstemp creates 0o600; a result file must be readable as a plain open() would make it
    (0o666 minus the umask), e.g. by a colleague or a web server."""
    import os

    from flexmvm.results.atomic import write_text_atomic

    umask = os.umask(0)
    os.umask(umask)
    path = tmp_path / "x.json"
    write_text_atomic(path, "{}")
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask
