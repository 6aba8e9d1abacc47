"""The step's cost cuts of issue 49 (docs/notes/2026-11-29-step-cost-cuts.md) give the results
of the code they replace.

- Joints: phi alone (Joint.value, what the Newton iteration needs at the step's end) equals
  evaluate's phi, and a point's rows added as one block (add_rows, Rows.add_block) equal the
  rows added one at a time (add_row): exactly (the same products and sums; tolerance 0).
- stack builds no nodal selector of a part when another part touching the same body has none
  (the result has none either way).
- The contact scans' per-node helpers are inlined (contact.search's module doc).
"""

import numpy as np
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.rotation import expm_so3
from flexmvm.constraints.drives import driven_revolute_joint
from flexmvm.constraints.joints import (
    BodyPoint,
    DistanceJoint,
    NodeSetPoint,
    PrescribedMotion,
    SphericalJoint,
    revolute_joint,
)
from flexmvm.constraints.prescribed import PrescribedPath
from flexmvm.constraints.prismatic import prismatic_joint
from flexmvm.constraints.rows import Rows, stack
from flexmvm.contact import search
from flexmvm.integrate.state import BodyState
from flexmvm.time_functions import Constant, Integral, Table


def _bodies_states(seed=0):
    """Two flexible bodies (nq 9, 14) and a rigid one, at random poses."""
    rng = np.random.default_rng(seed)
    bodies, states = [], []
    for k, nq in enumerate((9, 14, 0)):
        n = 12
        X = rng.normal(size=(n, 3))
        B = sp.random(n, n, density=0.3, random_state=seed + k)
        Ms = sp.csr_matrix(B @ B.T + sp.eye(n))
        psi = rng.normal(size=(3 * n, nq))
        K = rng.normal(size=(nq, nq))
        bodies.append(FlexibleBody.build(f"b{k}", X, Ms, psi, K @ K.T + np.eye(nq)))
        states.append(
            BodyState(
                rng.normal(size=3),
                expm_so3(rng.normal(size=3)),
                1e-2 * rng.normal(size=nq),
                rng.normal(size=6 + nq),
            )
        )
    return bodies, states


def _points(bodies):
    return [
        BodyPoint(0, local=(0.1, -0.2, 0.05)),
        BodyPoint(2, local=(0.0, 0.3, 0.0)),
        BodyPoint(1, node=4),
        BodyPoint(0, node=2, offset_m=(0.0, 0.01, 0.0)),
        NodeSetPoint.of(1, bodies[1], [1, 5, 7]),
        NodeSetPoint.of(2, bodies[2], [0, 3]),
    ]


def _assert_same_rows(a: Rows, b: Rows) -> None:
    assert a.m == b.m and a.blocks.keys() == b.blocks.keys()
    for k, (f, q) in a.blocks.items():
        assert np.array_equal(f, b.blocks[k][0]) and np.array_equal(q, b.blocks[k][1])
        na, nb = a.nodal_selector(k), b.nodal_selector(k)
        assert (na is None) == (nb is None)
        if na is not None:
            assert np.array_equal(na.toarray(), nb.toarray())


def test_add_rows_equals_add_row_per_direction():
    bodies, states = _bodies_states()
    dirs = np.vstack([np.eye(3), np.random.default_rng(3).normal(size=(2, 3))])
    for p in _points(bodies):
        for sign in (1.0, -1.0):
            one, block = Rows(len(dirs)), Rows(len(dirs))
            for i, d in enumerate(dirs):
                p.add_row(one, i, d, sign, bodies, states)
            p.add_rows(block, 0, dirs, sign, bodies, states)
            _assert_same_rows(block, one)


def test_joint_value_is_evaluates_phi():
    bodies, states = _bodies_states(1)
    pts = _points(bodies)
    path = Integral(Table.of_rows([[0.0, 0.0, 1.0, 0.0], [1.0, 2.0, 0.0, -1.0]], width=3))
    joints = [
        SphericalJoint(pts[0], pts[4]),
        SphericalJoint(pts[4], np.array([0.1, 0.2, 0.3])),
        DistanceJoint(pts[3], pts[1], 0.5),
        PrescribedMotion(pts[2], (0.0, 0.1, 0.0), (1.0, 0.0, -2.0)),
        *revolute_joint(pts[5], pts[0], (0.0, 0.0, 1.0), states),
        *prismatic_joint(pts[1], None, (1.0, 0.0, 0.0), bodies, states),
        PrescribedPath(pts[0], np.zeros(3), path),
    ]
    angle = Integral(Constant(150.0))  # a drive at 150 rad/s from its placement
    joints += driven_revolute_joint(pts[4], pts[1], (0.0, 1.0, 0.0), states, angle, "drive")
    moved = [
        BodyState(st.r + 0.01, st.A @ expm_so3(np.array([0.02, -0.01, 0.03])), st.q * 1.1, st.v)
        for st in states
    ]
    for joint in joints:
        for t in (0.0, 1e-3):
            phi, _ = joint.evaluate(bodies, moved, t)
            assert np.array_equal(joint.value(bodies, moved, t), phi), type(joint).__name__


def test_stack_builds_no_selector_it_drops():
    bodies, states = _bodies_states(2)
    with_sel = DistanceJoint(BodyPoint(0, node=3), np.zeros(3), 1.0).evaluate(bodies, states, 0.0)
    rows = with_sel[1]
    other = Rows(1)
    other.add(0, 0, np.ones(6), np.ones(bodies[0].nq), bodies[0].nq)
    out = stack([rows, other])
    assert out.nodal_selector(0) is None
    assert rows.nodal == {}  # not built: the other part has none
    both = stack([rows, rows])
    assert both.nodal_selector(0) is not None


def test_scan_helpers_are_inlined():
    """The per-node helpers of the contact scans are compiled into them (contact.search's
    module doc: a call of one cost ~0.4 us in reference counts, a third of the sphere_block
    scan); their results are the same bit for bit (tests/test_contact_broad_phase.py and the
    stored step histories check the scans)."""
    for helper in (search._search_node, search._closest, search._try):
        assert helper.targetoptions.get("inline") == "always", helper.py_func.__name__
