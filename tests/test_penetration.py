"""Penetration measured both ways (issue 11, item 4) and the overlap check at t = 0 (item 7).

Constructed geometry with known answers: a flat slave face (2 x 2 unit quads at z = 0, slave
body below, normal +z) and a master face of 0.5-spaced quads above it (normal -z) whose node
at (0.5, 0.5) dips to z = -d. Every slave node sits on a master facet corner at z = 0: the
slave-into-master direction (the one the constraint pass sees) reads 0, the master node is d
inside the slave face. Depths are compared to 1e-12 m: the facets are flat, the projections
exact up to the Newton tolerance (1e-12 on local coordinates of unit facets).
"""

from __future__ import annotations

import json
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.contact.geometry import MasterSurface
from flexmvm.contact.pairs import PointToSurfaceContact
from flexmvm.contact.penetration import EDGE_TOL
from flexmvm.runs.run import run_scenario
from flexmvm.scenarios import load_scenario

ROOT = Path(__file__).resolve().parents[1]
SHORT = ROOT / "tests" / "data" / "short_flat_impact.toml"
D = 0.01  # depth of the dipping master node [m]


def _grid(n, step, z=0.0):
    g = np.arange(n + 1) * step
    X, Y = np.meshgrid(g, g, indexing="xy")
    nodes = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, z)])
    k = lambda i, j: j * (n + 1) + i
    quads = np.array(
        [[k(i, j), k(i + 1, j), k(i + 1, j + 1), k(i, j + 1)] for j in range(n) for i in range(n)]
    )
    return nodes, quads


def _bodies(extra=None):
    """Master (body 0): 4 x 4 quads of 0.5 over [0, 2]^2, node (0.5, 0.5) at z = -D, quads
    reversed (normal -z); extra (x, z): a strip of quads from x = 2 to x = 2 + (x - 2) along
    the y = 0 edge with its outer nodes at height z. Slave (body 1): 2 x 2 unit quads, +z."""
    Xm, qm = _grid(4, 0.5)
    Xm[6, 2] = -D  # node (i, j) = (1, 1): x = y = 0.5
    qm = qm[:, ::-1]
    if extra is not None:
        x, z = extra
        base = len(Xm)
        Xm = np.vstack([Xm, [[x, 0.0, z], [x, 0.5, z]]])
        qm = np.vstack([qm, [[4, 9, base + 1, base]]])  # (2, 0), (2, 0.5), outer: normal -z
    Xs, qs = _grid(2, 1.0)
    mk = lambda name, X: FlexibleBody(
        name, X, sp.csr_matrix((3 * len(X), 0)), types.SimpleNamespace(nq=0), None
    )
    return (
        [mk("top", Xm), mk("bottom", Xs)],
        MasterSurface(qm, np.zeros((0, 3))),
        MasterSurface(qs, np.zeros((0, 3))),
    )


def _states():
    st = lambda: types.SimpleNamespace(r=np.zeros(3), A=np.eye(3), q=np.zeros(0), v=np.zeros(6))
    return [st(), st()]


def _provider(extra=None, two_way=True):
    bodies, master, slave = _bodies(extra)
    prov = PointToSurfaceContact(
        bodies,
        1,
        slave.nodes(),
        0,
        master,
        search_radius_m=0.05,
        slave_surface=slave if two_way else None,
    )
    return bodies, prov


def test_master_node_inside_the_slave_face_is_seen_only_the_other_way():
    """The dipping master node is D inside the slave face: the reverse direction reads D at
    that node (mesh id 6) on the slave facet under it; the forward direction and the gaps of
    the constraint pass's rows read nothing (>= -1e-12 m)."""
    bodies, prov = _provider()
    states = _states()
    fwd, rev = prov.penetration(bodies, states)
    assert fwd.depth_m == 0.0 and fwd.node == -1
    assert abs(rev.depth_m - D) < 1e-12
    assert (rev.body, rev.node, rev.against, rev.facet) == (0, 6, 1, 0)
    crows = prov.candidate_rows(bodies, states, 1e-6)
    assert crows.gaps.size and crows.gaps.min() >= -1e-12
    # without the slave facets only the forward direction is measured
    bodies, one_way = _provider(two_way=False)
    (only,) = one_way.penetration(bodies, _states())
    assert only.depth_m == 0.0


def test_moving_the_slave_up_gives_the_depth_in_both_directions():
    """Slave lifted by e = 0.004 m: every slave node is e into the master face (forward) and
    the dipping node D + e into the slave face (reverse)."""
    bodies, prov = _provider()
    states = _states()
    e = 0.004
    states[1].r = np.array([0.0, 0.0, e])
    fwd, rev = prov.penetration(bodies, states)
    assert abs(fwd.depth_m - e) < 1e-12 and fwd.against == 0
    assert abs(rev.depth_m - (D + e)) < 1e-12 and rev.node == 6


@pytest.mark.parametrize(("offset", "expected"), [(0.5 * EDGE_TOL, 0.03), (0.5, D)])
def test_nodes_beside_the_surface_do_not_count(offset, expected):
    """Two master nodes 0.03 m below the slave plane, outside the slave face's edge x = 2 by a
    lateral offset: within EDGE_TOL (of the slave facet's circumradius sqrt(0.5) m) they count
    (depth 0.03 m), half a metre beside the face they do not (the extended facet plane alone
    would read 0.03 m): the deepest is then the dipping node, D."""
    R = np.sqrt(0.5)
    bodies, prov = _provider(extra=(2.0 + offset * R, -0.03))
    _, rev = prov.penetration(bodies, _states())
    assert abs(rev.depth_m - expected) < 1e-12


def test_floor_skips_only_what_cannot_be_deeper():
    """floors: depths at or below the floor read 0, deeper ones exactly."""
    bodies, prov = _provider()
    _, rev = prov.penetration(bodies, _states(), floors=[0.0, 0.5 * D])
    assert abs(rev.depth_m - D) < 1e-12
    _, rev = prov.penetration(bodies, _states(), floors=[0.0, 2 * D])
    assert rev.depth_m == 0.0 and rev.node == -1


def _flexmvm(*args):
    return subprocess.run(
        [sys.executable, "-m", "flexmvm.cli.main", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )


def test_overlap_at_start_is_one_line_error(tmp_path):
    """b2 moved 1 mm into b1 (flat faces): exit status 2, one line naming both bodies and the
    depth, no traceback, nothing written."""
    text = SHORT.read_text()
    old = '[bodies.model]\nkind = "full"\n\n[[contacts]]'
    assert old in text
    path = tmp_path / "overlap.toml"
    path.write_text(
        text.replace(
            old,
            '[bodies.model]\nkind = "full"\n[bodies.placement]\n'
            "position_m = [-0.001, 0.0, 0.0]\n\n[[contacts]]",
        )
    )
    out = tmp_path / "out"
    p = _flexmvm(
        "run",
        path,
        "--out",
        out,
        "--model",
        "rigid",
        "--t-end",
        "1e-6",
        "--no-fields",
        "--no-progress",
    )
    assert p.returncode == 2, p.stderr
    err = p.stderr.strip()
    assert "Traceback" not in p.stderr and len(err.splitlines()) == 1, err
    assert err.startswith("flexmvm: error:")
    assert "'b1'" in err and "'b2'" in err and "overlap" in err and "0.001 m" in err, err
    assert not out.exists() or not any(out.iterdir())


def test_summary_reports_where_and_when():
    """The short flat impact (full FE both): max_penetration_m with its time, body, node and
    the body it is in; equal to the deepest of the two directions; touching at t = 0 is not
    an overlap."""
    sc = load_scenario(SHORT).with_overrides(t_end_s=10e-6)
    s = run_scenario(sc).summary
    at = s["max_penetration_at"]
    by = s["max_penetration_by_direction_m"]
    assert set(by) == {"b2 nodes into b1", "b1 nodes into b2"}
    assert s["max_penetration_m"] == max(by.values()) > 0.0
    assert {at["body"], at["against"]} == {"b1", "b2"} and at["node"] >= 0
    assert 0.0 < at["t_s"] <= 10e-6 + 1e-15
    json.dumps(s)


def test_simulate_refuses_an_overlap_unless_continuing():
    """In process: the same 1 mm overlap (rigid rods) is an InputError from simulate; with
    check_overlap=False (a continuation) the run goes on and reports the depth at t = 0."""
    from flexmvm.assembly.build import build_scenario
    from flexmvm.errors import InputError
    from flexmvm.integrate.driver import simulate

    sc = load_scenario(SHORT).with_overrides(model="rigid", t_end_s=1e-6)
    built = build_scenario(sc)
    states = [s.copy() for s in built.states]
    states[1].r = states[1].r + np.array([-0.001, 0.0, 0.0])
    with pytest.raises(InputError, match=r"'b\d' and 'b\d' overlap at t = 0 s by 0\.001 m"):
        simulate(built.system, states, built.grid)
    res = simulate(built.system, states, built.grid, check_overlap=False)
    assert abs(res.max_penetration_m - 0.001) < 1e-9
    assert res.max_penetration_at["t_s"] == 0.0


@pytest.mark.parametrize("recovery", [None, 0.0])
def test_overlap_at_rest_is_held_without_energy_gain(recovery):
    """Two rigid rods moving together at 0.1 m/s, overlapping by 10 um (a continuation). The
    velocity law's penetration recovery (default beta = 0.2) is capped by the pair's closing
    speed, here 0: the overlap is held, not pushed out (uncapped, it pushed them apart at
    beta * 10 um / h = 8 m/s, h = 0.25 us, a rise of the kinetic energy by a factor of
    hundreds that nothing in the system supplies); with penetration_recovery = 0 likewise. No
    gain, no warning; energy_gain_warning still names a gain above its threshold."""
    from flexmvm.assembly.build import build_scenario
    from flexmvm.integrate.driver import simulate
    from flexmvm.runs.guard import ENERGY_GAIN_WARN, energy_gain_warning
    from flexmvm.runs.run import summarize

    data = load_scenario(SHORT).with_overrides(model="rigid", t_end_s=5e-6).model_dump(mode="json")
    for b in data["bodies"]:
        b["placement"]["velocity_mps"] = [0.1, 0.0, 0.0]
    if recovery is not None:
        data["contacts"][0]["penetration_recovery"] = recovery
    from flexmvm.scenarios import scenario_from_dict

    built = build_scenario(scenario_from_dict(data))
    states = [s.copy() for s in built.states]
    states[1].r = states[1].r + np.array([-1e-5, 0.0, 0.0])
    s = summarize(simulate(built.system, states, built.grid, check_overlap=False), built)
    assert 0.0 <= s["energy_gain_rel_max"] <= 1e-9
    assert energy_gain_warning(s) is None
    assert "energy rose" in energy_gain_warning({"energy_gain_rel_max": 2 * ENERGY_GAIN_WARN})
    assert energy_gain_warning({"energy_gain_rel_max": ENERGY_GAIN_WARN}) is None
    assert energy_gain_warning({"energy_gain_rel_max": None}) is None
