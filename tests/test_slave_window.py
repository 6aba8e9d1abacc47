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
from flexmvm.contact import pairs
from flexmvm.integrate.driver import simulate
from flexmvm.scenarios.build import build_scenario

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


def test_window_maxima_are_exact_whether_or_not_the_bound_holds():
    """ContactNodes with a window moves only its rows, bit for bit as the whole update does,
    and returns the largest velocity component and displacement over every node: from the
    window when the bound over the outside nodes allows it, else by moving those too (the
    largest psi row put outside the window). Tolerance 0: the same arithmetic."""
    from types import SimpleNamespace

    from flexmvm.contact.nodes import ContactNodes
    from flexmvm.contact.slave_window import column_bounds, outside_bounds

    rng = np.random.default_rng(7)
    n, nq = 60, 5
    A = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    v = rng.normal(size=6 + nq)
    v[:6] *= 1e-3  # a slow frame: the elastic velocities decide the largest component
    st = SimpleNamespace(q=1e-4 * rng.normal(size=nq), v=v, r=rng.normal(size=3), A=A)
    for big_outside in (False, True):
        psi = 1e-3 * rng.normal(size=(3 * n, nq))
        psi[:30] *= 100.0  # the first 10 nodes (the window) move the most
        if big_outside:
            psi[3 * 50 : 3 * 51] *= 1e6  # node 50, outside, moves the most
        body = SimpleNamespace(X=rng.normal(size=(n, 3)), psi=psi, nq=nq)
        whole, win = ContactNodes(body, np.arange(n)), ContactNodes(body, np.arange(n))
        want = whole.update(st)
        rows, out = np.arange(10), np.arange(10, n)
        c_out = column_bounds(win, out)
        x_out = float(np.linalg.norm(body.X[out], axis=1).max())
        win.set_rows(rows, (out, c_out, x_out), invalidate=True)
        bound_v, _ = outside_bounds(c_out, x_out, st.q, st.v)
        assert (bound_v > abs(whole.xd[:10]).max()) == big_outside
        assert win.update(st) == want
        for name in ("u", "ud", "s", "x", "xd"):
            np.testing.assert_array_equal(getattr(win, name)[rows], getattr(whole, name)[rows])
