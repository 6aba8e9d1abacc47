"""Joint rows carry their nodal selector N (elastic part = N psi), so the integrator can apply
W^-1 through cached nodal columns (integrate.moreau_jean.body_solver.BodySolver.solve_nodal). N psi
must be the elastic part exactly (same products: 1e-14 relative); a row with an elastic part given
without N leaves the body without a selector (it then takes the back-substitution)."""

import numpy as np
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.rotation import expm_so3
from flexmvm.constraints.joints import (
    BodyPoint,
    DistanceJoint,
    SphericalJoint,
    fixed_joint,
    revolute_joint,
)
from flexmvm.constraints.rows import Rows, stack
from flexmvm.integrate.state import BodyState


def _bodies_states(seed=0):
    rng = np.random.default_rng(seed)
    bodies, states = [], []
    for k, nq in enumerate((9, 14)):
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


def test_selector_times_psi_is_the_elastic_part():
    bodies, states = _bodies_states()
    joints = [
        DistanceJoint(BodyPoint(0, node=3, offset_m=(0.0, 0.01, 0.0)), BodyPoint(1, node=7), 0.5),
        SphericalJoint(BodyPoint(0, node=5), np.array([0.1, 0.2, 0.3])),
        *revolute_joint(
            BodyPoint(1, node=2), BodyPoint(0, local=(0.0, 0.0, 0.1)), (0.0, 0.0, 1.0), states
        ),
        *fixed_joint(BodyPoint(0, node=1), np.zeros(3), states),
    ]
    rows = stack([j.evaluate(bodies, states, 0.0)[1] for j in joints])
    for b, body in enumerate(bodies):
        N = rows.nodal_selector(b)
        assert N is not None and N.shape == (rows.m, body.psi.shape[0])
        elastic = rows.blocks[b][1]
        np.testing.assert_allclose(
            N @ body.psi, elastic, rtol=0, atol=1e-14 * max(np.abs(elastic).max(), 1.0)
        )


def test_elastic_part_without_selector_has_none():
    bodies, states = _bodies_states(1)
    rows = DistanceJoint(BodyPoint(0, node=3), np.zeros(3), 1.0).evaluate(bodies, states, 0.0)[1]
    other = Rows(1)
    other.add(0, 0, np.ones(6), np.ones(bodies[0].nq), bodies[0].nq)
    assert rows.nodal_selector(0) is not None
    assert stack([rows, other]).nodal_selector(0) is None
