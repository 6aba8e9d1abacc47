"""bodies.momentum.momentum_terms against the numpy reference (FlexibleBody.inertia_terms,
mass_times, velocity_forces, gravity_forces) on random bodies and states.

Same arithmetic in another order: agreement to 1e-12 of each vector's largest entry (sums of
~9 nq products of O(1) numbers carry ~nq eps of rounding; nq <= 40 here).
"""

import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.momentum import momentum_terms, momentum_terms_nodal
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


@pytest.mark.parametrize(
    "nq, seed, spin, gravity",
    [(1, 0, True, False), (12, 1, True, True), (40, 2, False, True), (40, 3, True, True)],
)
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
    momentum_terms(
        A,
        q,
        dv,
        vm,
        Lq,
        Lqd,
        Kq,
        mqq_dv,
        mqq_vm,
        inv.mass,
        inv.S0,
        inv.S1,
        inv.G0,
        body.G1_array,
        g,
        *got,
    )
    for name, x, want in zip(
        ("inertia", "force", "momentum"), got, (want_inertia, want_force, want_momentum)
    ):
        np.testing.assert_allclose(x, want, rtol=0, atol=1e-12 * np.abs(want).max(), err_msg=name)


def _nodal_body(seed: int, drop: int) -> FlexibleBody:
    """A body whose basis selects nodal DOFs (as a full-FE body's does), `drop` DOFs left out
    (a reference condition) and the columns shuffled, so nothing relies on k = 3 n + c."""
    rng = np.random.default_rng(seed)
    n = 30
    X = rng.normal(size=(n, 3))
    B = sp.random(n, n, density=0.2, random_state=seed)
    Ms = sp.csr_matrix(B @ B.T + sp.eye(n))
    dofs = rng.permutation(3 * n)[: 3 * n - drop]
    psi = sp.csr_matrix(
        (np.ones(dofs.size), (dofs, np.arange(dofs.size))), shape=(3 * n, dofs.size)
    )
    K = sp.random(dofs.size, dofs.size, density=0.1, random_state=seed)
    return FlexibleBody.build("b", X, Ms, psi, sp.csr_matrix(K @ K.T + sp.eye(dofs.size)))


@pytest.mark.parametrize(
    "seed, drop, spin, gravity", [(0, 0, True, False), (1, 6, True, True), (2, 5, False, True)]
)
def test_nodal_kernel_equals_the_general_one(seed, drop, spin, gravity):
    """momentum_terms_nodal on the compact contractions Y(q), Y(q_dot) against momentum_terms
    on the full L(q), L(q_dot) of the same body (bodies.nodal_contraction): the same sums in
    another order, to 1e-12 of each vector's largest entry (as above); the inertia terms, frame
    coupling and first-order frame inertia from the compact form to 1e-13. The compact form itself:
    expand(Y(x)) equals contractions(x) and trace(Y(x)) equals M_qq x to 1e-13 (one M_s
    product against three)."""
    body = _nodal_body(seed, drop)
    nodal = body.nodal
    assert nodal is not None
    rng = np.random.default_rng(200 + seed)
    A = expm_so3(rng.normal(size=3))
    q = 1e-2 * rng.normal(size=body.nq)
    dv = rng.normal(size=body.nv)
    vm = rng.normal(size=body.nv)
    if not spin:
        vm[3:6] = 0.0
    g = np.array([0.3, -9.81, 0.1]) if gravity else np.zeros(3)
    Lq, Lqd = body.contractions(q), body.contractions(vm[6:])
    Yq, Yqd = body.carried_contractions(q), body.carried_contractions(vm[6:])
    for L, Y, x in ((Lq, Yq, q), (Lqd, Yqd, vm[6:])):
        np.testing.assert_allclose(nodal.expand(Y), L, rtol=0, atol=1e-13 * np.abs(L).max())
        mx = body.inv.M_qq @ x
        np.testing.assert_allclose(
            body.contraction_trace(Y), mx, rtol=0, atol=1e-13 * np.abs(mx).max()
        )
    Kq = body.k_hat @ q
    mqq_dv, mqq_vm = body.inv.M_qq @ dv[6:], body.inv.M_qq @ vm[6:]
    inv = body.inv
    want = [np.empty(body.nv) for _ in range(3)]
    momentum_terms(
        A,
        q,
        dv,
        vm,
        Lq,
        Lqd,
        Kq,
        mqq_dv,
        mqq_vm,
        inv.mass,
        inv.S0,
        inv.S1,
        inv.G0,
        body.G1_array,
        g,
        *want,
    )
    got = [np.empty(body.nv) for _ in range(3)]
    momentum_terms_nodal(
        A,
        q,
        dv,
        vm,
        Yq,
        Yqd,
        Kq,
        mqq_dv,
        mqq_vm,
        inv.mass,
        inv.S0,
        inv.S1,
        inv.G0,
        nodal.MsX,
        nodal.node,
        nodal.comp,
        g,
        *got,
    )
    for name, x, w in zip(("inertia", "force", "momentum"), got, want):
        np.testing.assert_allclose(x, w, rtol=0, atol=1e-12 * np.abs(w).max(), err_msg=name)
    # the inertia terms and the frame coupling from the compact form (the recorder's and the
    # iteration matrix's): S, J, M_wq as from L
    S, J, Mwq, _ = body.inertia_terms(q, Lq)
    S2, J2, Mwq2, C2 = body.inertia_terms(q, Yq)
    assert C2 is None
    np.testing.assert_allclose(S2, S, rtol=0, atol=1e-13 * np.abs(S).max())
    np.testing.assert_allclose(J2, J, rtol=0, atol=1e-13 * np.abs(J).max())
    np.testing.assert_allclose(Mwq2, Mwq, rtol=0, atol=1e-13 * np.abs(Mwq).max())
    np.testing.assert_allclose(
        body.rotational_coupling(q, Yq),
        body.rotational_coupling(q, Lq),
        rtol=0,
        atol=1e-13 * np.abs(Mwq).max(),
    )
    Gq = body.G1_array @ q
    G = body.inv.G0 + Gq + Gq.T
    J1 = np.trace(G) * np.eye(3) - G
    np.testing.assert_allclose(
        body.frame_inertia_first_order(q), J1, rtol=0, atol=1e-13 * np.abs(J1).max()
    )


def test_nodal_contraction_only_for_selecting_bases():
    """A dense basis, or a sparse one with a column that is not a unit DOF, has no compact
    form."""
    assert _body(12, 1).nodal is None
    body = _nodal_body(3, 2)
    psi = body.psi.tolil()
    psi[0, 0] = 0.5 if psi[0, 0] == 0 else 2.0
    other = FlexibleBody.build("c", body.X, body.inv.Ms, psi.tocsr(), body.k_hat)
    assert other.nodal is None
