"""The slave window (contact/slave_window.py): a contact moves only the slave nodes that can
reach the master, and the run is the same, bit for bit, as when it moves them all.

A small clamped plate (kind mvm-sparse) struck by a rigid ball, as tests/test_big_part.py's,
over 20 steps: its 137 top-face slave nodes against the ball, the window forced on (the
shipped threshold leaves a face this small whole) with a margin small enough that the drift
bound refreshes it several times.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gmsh")

import flexmvm as fm
from flexmvm.assembly.build import build_scenario
from flexmvm.contact import pairs
from flexmvm.integrate.driver import simulate

ROOT = Path(__file__).resolve().parents[1]

SCENARIO = """name = "small_plate_window"
gravity_mps2 = [0.0, 0.0, 0.0]
[time]
t_end_s = 10.0e-6
dt_s = 0.5e-6
dt_max_s = 0.5e-6
output_dt_s = 0.5e-6
[[bodies]]
name = "ball"
material = { name = "steel", E_pa = 210.0e9, nu = 0.3, rho_kg_m3 = 7850.0 }
mesh_file = "sphere_r5.msh"
[bodies.model]
kind = "rigid"
[bodies.placement]
position_m = [0.0, 0.0, 0.005]
velocity_mps = [0.0, 0.0, -1.0]
[[bodies]]
name = "plate"
material = "aluminium"
mesh_file = "plate.msh"
[bodies.model]
kind = "mvm-sparse"
region = { ball = { centre_m = [0.0, 0.0, 0.0], radius_m = 1.0e-3 } }
modes = 8
[[supports]]
type = "clamp"
body = "plate"
node_set = "side"
[[contacts]]
slave = "plate.top"
master = "ball.front"
law = "position"
"""

HISTORIES = ("t", "contact_force", "q", "q_dot", "frame_r", "frame_v", "kinetic", "strain")


@pytest.fixture(scope="module")
def scenario(tmp_path_factory):
    from flexmvm.mesh.gmsh_session import Refinement
    from flexmvm.mesh.parts import block

    d = tmp_path_factory.mktemp("plate_window")
    refine = Refinement((0.0, 0.0, 0.0), 0.5e-3, 1.0e-3, 3.0e-3)
    block(d / "plate.msh", 0.020, 0.020, 0.002, 2.5e-3, order=1, refine=refine)
    shutil.copy(ROOT / "scenarios" / "meshes" / "sphere_r5.msh", d / "sphere_r5.msh")
    (d / "plate.toml").write_text(SCENARIO)
    return fm.load_scenario(d / "plate.toml")


def _run(scenario, monkeypatch, window: bool):
    monkeypatch.setattr(pairs, "WINDOW_MIN_NODES", 0 if window else 10**9)
    # a margin of 1/100 of the search radius (10 um): the drift bound refreshes it often
    monkeypatch.setattr(pairs, "MARGIN_PER_SEARCH_RADIUS", 0.01)
    built = build_scenario(scenario)
    res = simulate(built.system, built.states, built.grid, built.probes)
    return res, built.system.contacts[0]


def test_window_moves_fewer_nodes_and_changes_nothing(scenario, monkeypatch):
    """With the window: fewer slave nodes moved per step than the face has, refreshed more
    than once (the bound is exercised), and every history equal bit for bit to the run that
    moves every node (tolerance 0: the same kernels on the same numbers, and no node outside
    the window can pass the scans' box test)."""
    whole, c_whole = _run(scenario, monkeypatch, window=False)
    assert c_whole._window is None
    windowed, c = _run(scenario, monkeypatch, window=True)
    n_slave = len(c.slave_nodes)
    assert c._s.window_rows is not None
    assert 0 < len(c._s.window_rows) < 0.7 * n_slave  # 77 of 137 when written
    assert c._window.refreshes >= 3  # 11 when written
    assert np.max(whole.contact_force) > 100.0  # the ball is in contact: ~170 N at the end
    for name in HISTORIES:
        a, b = getattr(whole, name), getattr(windowed, name)
        if isinstance(a, list):
            assert all(np.array_equal(np.asarray(x), np.asarray(y)) for x, y in zip(a, b)), name
        else:
            assert np.array_equal(np.asarray(a), np.asarray(b)), name


def test_window_moves_its_rows_as_the_whole_update_does():
    """ContactNodes with a window moves only its rows, bit for bit as the whole update does,
    leaves the others as they were, and returns the largest velocity component and
    displacement over the window (those of the nodes that can reach the master); the column
    bounds of the drift bound are the largest |psi_i[:, k]| over the rows, dense or CSR.
    Tolerance 0: the same arithmetic."""
    from types import SimpleNamespace

    import scipy.sparse as sp

    from flexmvm.contact.nodes import ContactNodes
    from flexmvm.contact.slave_window import column_bounds

    rng = np.random.default_rng(7)
    n, nq = 60, 5
    A = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    st = SimpleNamespace(
        q=1e-4 * rng.normal(size=nq), v=rng.normal(size=6 + nq), r=rng.normal(size=3), A=A
    )
    rows = np.arange(10, 25)
    for sparse in (False, True):
        psi = rng.normal(size=(3 * n, nq)) * (rng.random((3 * n, nq)) < (0.1 if sparse else 1))
        body = SimpleNamespace(
            X=rng.normal(size=(n, 3)), psi=sp.csr_matrix(psi) if sparse else psi, nq=nq
        )
        whole, win = ContactNodes(body, np.arange(n)), ContactNodes(body, np.arange(n))
        assert win.dense is not sparse
        whole.update(st)
        win.x[:] = -7.0
        win.set_rows(rows, invalidate=True)
        vmax, umax = win.update(st)
        assert vmax == np.abs(whole.xd[rows]).max()
        assert umax == np.linalg.norm(whole.u[rows], axis=1).max()
        for name in ("u", "ud", "s", "x", "xd"):
            np.testing.assert_array_equal(getattr(win, name)[rows], getattr(whole, name)[rows])
        assert (np.delete(win.x, rows, axis=0) == -7.0).all()
        want = np.linalg.norm(psi.reshape(n, 3, nq)[rows], axis=1).max(axis=0)
        np.testing.assert_allclose(column_bounds(win, rows), want, rtol=1e-14)
