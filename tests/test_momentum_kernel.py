"""bodies.momentum.momentum_terms against the numpy reference (FlexibleBody.inertia_terms,
mass_times, velocity_forces, gravity_forces) on random bodies and states.

Same arithmetic in another order: agreement to 1e-12 of each vector's largest entry (sums of
~9 nq products of O(1) numbers carry ~nq eps of rounding; nq <= 40 here).
"""

import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.momentum import momentum_terms
from flexmvm.bodies.rotation import expm_so3


def _body(nq: int, seed: int) -> FlexibleBody:
    rng = np.random.default_rng(seed)
    n = 30
    X = rng.normal(size=(n, 3))
    B = sp.random(n, n, density=0.2, random_state=seed)
    Ms = sp.csr_matrix(B @ B.T + sp.eye(n))
    psi = rng.normal(size=(3 * n, nq))
    K = rng.normal(size=(nq, nq))
    return FlexibleBody.build("b", X, Ms, psi, K @ K.T + np.eye(nq))


@pytest.mark.parametrize("nq, seed, spin, gravity", [(1, 0, True, False), (12, 1, True, True),
                                                     (40, 2, False, True), (40, 3, True, True)])
def test_equals_numpy_reference(nq, seed, spin, gravity):
    body = _body(nq, seed)
    rng = np.random.default_rng(100 + seed)
    A = expm_so3(rng.normal(size=3))
    q = 1e-2 * rng.normal(size=nq)
    dv = rng.normal(size=6 + nq)
    vm = rng.normal(size=6 + nq)
    if not spin:
        vm[3:6] = 0.0  # the branch without quadratic-velocity terms in the q rows
    g = np.array([0.3, -9.81, 0.1]) if gravity else np.zeros(3)
    Lq, Lqd = body.contractions(q), body.contractions(vm[6:])
    Kq = body.k_hat @ q
    mqq_dv, mqq_vm = body.inv.M_qq @ dv[6:], body.inv.M_qq @ vm[6:]

    terms = body.inertia_terms(q, Lq)
    want_inertia = body.mass_times(A, q, dv, terms, mqq_dv)
    want_force = body.velocity_forces(A, q, vm, terms, Lqd)
    if gravity:
        want_force += body.gravity_forces(A, q, g, terms[0])
    want_force[6:] -= Kq
    want_momentum = body.mass_times(A, q, vm, terms, mqq_vm)

    got = [np.empty(body.nv) for _ in range(3)]
    inv = body.inv
    momentum_terms(A, q, dv, vm, Lq, Lqd, Kq, mqq_dv, mqq_vm, inv.mass, inv.S0, inv.S1, inv.G0,
                   body.G1_array, g, *got)
    for name, x, want in zip(("inertia", "force", "momentum"), got,
                             (want_inertia, want_force, want_momentum)):
        np.testing.assert_allclose(x, want, rtol=0, atol=1e-12 * np.abs(want).max(),
                                   err_msg=name)
