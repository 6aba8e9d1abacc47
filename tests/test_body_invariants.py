"""The invariant contractions of FlexibleBody against brute-force nodal sums.

Exact identities (kinetic energy, momenta, quadratic-velocity vector of the virtual-work
formulation), so the tolerance is round-off: 1e-10 relative. The invariants themselves are also
checked against their definitions, cut bases and the reduced stiffness.
"""

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.build import reduced_stiffness
from flexmvm.bodies.invariants import inertia_invariants, leading_columns
from flexmvm.bodies.rotation import expm_so3, skew


def _random_body(sparse: bool, seed=0):
    rng = np.random.default_rng(seed)
    n, nq = 7, 5
    X = rng.normal(size=(n, 3))
    B = rng.normal(size=(n, n))
    Ms = sp.csr_matrix(B @ B.T / n + np.eye(n))
    if sparse:
        psi = sp.csr_matrix(np.eye(3 * n)[:, 6 : 6 + nq])
    else:
        psi = rng.normal(size=(3 * n, nq))
    k = np.diag(rng.uniform(1, 2, nq))
    body = FlexibleBody.build("b", X, Ms, psi, k)
    return body, X, Ms, np.asarray(psi.todense()) if sparse else psi, rng


def _nodal(body, X, Ms, psi, r, A, q, v):
    n = len(X)
    s = X + (psi @ q).reshape(n, 3)
    sd = (psi @ v[6:]).reshape(n, 3)
    w = v[3:6]
    xd = v[:3] + (np.cross(w, s) + sd) @ A.T
    M3 = np.kron(Ms.toarray(), np.eye(3))
    T = 0.5 * xd.ravel() @ M3 @ xd.ravel()
    a_quad = (np.cross(w, np.cross(w, s)) + 2 * np.cross(w, sd)) @ A.T  # global
    f = -(M3 @ a_quad.ravel()).reshape(n, 3)
    Q = np.zeros(6 + body.nq)
    Q[:3] = f.sum(axis=0)
    fl = f @ A  # body frame
    Q[3:6] = np.cross(s, fl).sum(axis=0)
    Q[6:] = psi.T @ fl.ravel()
    p = (M3 @ xd.ravel()).reshape(n, 3)
    x = r + s @ A.T
    return T, Q, p.sum(axis=0), np.cross(x, p).sum(axis=0)


@pytest.mark.parametrize("sparse", [False, True])
def test_invariants_match_nodal_sums(sparse):
    body, X, Ms, psi, rng = _random_body(sparse)
    r = rng.normal(size=3)
    A = expm_so3(rng.normal(size=3))
    q = 0.1 * rng.normal(size=body.nq)
    v = rng.normal(size=body.nv)
    T, Q, p, h = _nodal(body, X, Ms, psi, r, A, q, v)
    assert body.kinetic_energy(A, q, v) == pytest.approx(T, rel=1e-10)
    np.testing.assert_allclose(
        body.velocity_forces(A, q, v), Q, rtol=1e-10, atol=1e-10 * abs(Q).max()
    )
    np.testing.assert_allclose(body.linear_momentum(A, q, v), p, rtol=1e-10)
    np.testing.assert_allclose(body.angular_momentum(r, A, q, v), h, rtol=1e-10)


def test_point_jacobian_gives_node_velocity():
    body, X, _, _, rng = _random_body(False, seed=3)
    A = expm_so3(rng.normal(size=3))
    q = 0.1 * rng.normal(size=body.nq)
    v = rng.normal(size=body.nv)
    d = np.array([0.3, -0.2, 0.9])
    for k in range(len(X)):
        fr, qp = body.point_jacobian(k, A, q, d)
        xd = body.node_velocities(np.array([k]), A, q, v)[0]
        assert fr @ v[:6] + qp @ v[6:] == pytest.approx(d @ xd, rel=1e-12)


def test_gravity_matches_nodal_loads():
    body, X, Ms, psi, rng = _random_body(False, seed=5)
    A = expm_so3(rng.normal(size=3))
    q = 0.1 * rng.normal(size=body.nq)
    g = np.array([0.0, 0.0, -9.81])
    n = len(X)
    msum = np.asarray(Ms.sum(axis=1)).ravel()
    f = msum[:, None] * g
    s = X + (psi @ q).reshape(n, 3)
    fl = f @ A
    Q = np.concatenate([f.sum(0), np.cross(s, fl).sum(0), psi.T @ fl.ravel()])
    np.testing.assert_allclose(body.gravity_forces(A, q, g), Q, rtol=1e-10, atol=1e-12)
    assert skew(np.ones(3)).trace() == 0.0


def _definition(X, Ms, psi):
    """The invariants straight from the module docstring's definitions (dense arrays)."""
    M = Ms.toarray()
    P = [np.asarray(psi[a::3, :].todense() if sp.issparse(psi) else psi[a::3, :]) for a in range(3)]
    one = np.ones(len(X))
    return {
        "mass": one @ M @ one,
        "S0": one @ M @ X,
        "G0": X.T @ M @ X,
        "S1": np.array([one @ M @ P[a] for a in range(3)]),
        "G1": [[X[:, a] @ M @ P[b] for b in range(3)] for a in range(3)],
        "G2": [[P[a].T @ M @ P[b] for b in range(3)] for a in range(3)],
    }


def _dense(a):
    return a.toarray() if sp.issparse(a) else np.asarray(a)


@pytest.mark.parametrize("sparse", [False, True])
def test_invariants_match_their_definitions(sparse):
    body, X, Ms, psi, _ = _random_body(sparse, seed=7)
    ref, inv = _definition(X, Ms, psi), body.inv
    assert inv.mass == pytest.approx(ref["mass"], rel=1e-13)
    for name in ("S0", "G0", "S1"):
        np.testing.assert_allclose(getattr(inv, name), ref[name], rtol=1e-12, atol=1e-12)
    for a in range(3):
        for b in range(3):
            np.testing.assert_allclose(inv.G1[a][b], ref["G1"][a][b], rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(_dense(inv.G2[a][b]), ref["G2"][a][b], atol=1e-12)
            assert sp.issparse(inv.G2[a][b]) == sparse
    M_qq = sum(ref["G2"][a][a] for a in range(3))
    np.testing.assert_allclose(_dense(inv.M_qq), M_qq, atol=1e-12)
    assert (inv.Ms is not None) == sparse and (inv.PT is not None) == sparse


def test_rigid_invariants():
    body, X, Ms, _, _ = _random_body(False, seed=2)
    inv = inertia_invariants(X, Ms, np.zeros((3 * len(X), 0)))
    assert inv.nq == 0 and inv.M_qq.shape == (0, 0) and inv.G2[1][2].shape == (0, 0)
    assert inv.mass == pytest.approx(body.inv.mass, rel=1e-14)
    np.testing.assert_array_equal(inv.G0, body.inv.G0)


def test_leading_columns_equal_the_cut_basis():
    body, X, Ms, psi, _ = _random_body(False, seed=4)
    cut, fresh = leading_columns(body.inv, 3), inertia_invariants(X, Ms, psi[:, :3])
    for name in ("S0", "S1", "G0", "M_qq"):
        np.testing.assert_allclose(getattr(cut, name), getattr(fresh, name), rtol=1e-13)
    for a in range(3):
        for b in range(3):
            np.testing.assert_allclose(cut.G1[a][b], fresh.G1[a][b], rtol=1e-13)
            np.testing.assert_allclose(cut.G2[a][b], fresh.G2[a][b], rtol=1e-13, atol=1e-14)
    with pytest.raises(ValueError):
        leading_columns(body.inv, body.nq + 1)
    sparse_body = _random_body(True)[0]
    with pytest.raises(ValueError):
        leading_columns(sparse_body.inv, 1)


@pytest.mark.parametrize("selection", [True, False])
def test_reduced_stiffness_sparse(selection):
    rng = np.random.default_rng(9)
    B = sp.random(12, 12, density=0.4, random_state=1)
    K = sp.csr_matrix(B @ B.T + sp.eye(12))
    cols = np.eye(12)[:, [0, 2, 3, 7, 11]]
    if not selection:
        cols = cols * rng.uniform(0.5, 2.0, size=5)
    psi = sp.csr_matrix(cols)
    k_hat = reduced_stiffness(K, psi)
    assert sp.isspmatrix_csr(k_hat)
    np.testing.assert_allclose(k_hat.toarray(), cols.T @ K.toarray() @ cols, rtol=1e-14)
    dense = reduced_stiffness(K, cols)
    np.testing.assert_allclose(dense, cols.T @ K.toarray() @ cols, rtol=1e-14)


@pytest.mark.parametrize("nq", [1, 5, 37])
def test_packed_g2_contraction_equals_the_nine_products(nq):
    """bodies.contraction reads the six distinct G2 blocks once (four rows at a time, the
    rest one by one: nq = 1, 5, 37 cover both); it must give G2[b][a] x for all nine (a, b)
    to round-off (1e-13 relative: sums of nq products in another order)."""
    from flexmvm.bodies.contraction import G2Contraction

    rng = np.random.default_rng(nq)
    G2 = [[None] * 3 for _ in range(3)]
    for a in range(3):
        g = rng.standard_normal((nq, nq))
        G2[a][a] = g + g.T
        for b in range(a + 1, 3):
            G2[a][b] = rng.standard_normal((nq, nq))
            G2[b][a] = G2[a][b].T.copy()
    x = rng.standard_normal(nq)
    packed = G2Contraction(G2)
    got = packed(x)
    for a in range(3):
        for b in range(3):
            want = G2[b][a] @ x
            np.testing.assert_allclose(
                got[a, b], want, rtol=0, atol=1e-13 * max(np.abs(want).max(), 1.0)
            )
    # in two parts on two threads: the same arithmetic, bit for bit
    with ThreadPoolExecutor(1) as pool:
        np.testing.assert_array_equal(packed(x, pool), got)


@pytest.mark.parametrize("sparse", [False, True])
def test_mass_times_is_the_trace_of_the_contraction(sparse):
    """M_qq = sum_a G2[a][a], so M_qq x is the trace L(x)[0, 0] + L(x)[1, 1] + L(x)[2, 2]
    of the contraction (the integrator takes M_qq dq_dot from it instead of a product with
    M_qq): equal to round-off (1e-13 relative) for dense and sparse bases, and for a dense
    basis wide enough for the packed contraction."""
    body = _random_body(sparse)[0]
    bodies = [body]
    if not sparse:
        rng = np.random.default_rng(4)
        n = 120
        X = rng.normal(size=(n, 3))
        B = sp.random(n, n, density=0.05, random_state=4)
        Ms = sp.csr_matrix(B @ B.T + sp.eye(n))
        bodies.append(FlexibleBody.build("wide", X, Ms, rng.normal(size=(3 * n, 320)), np.eye(320)))
    for b in bodies:
        x = np.random.default_rng(b.nq).standard_normal(b.nq)
        L = b.contractions(x)
        want = b.inv.M_qq @ x
        np.testing.assert_allclose(
            L[0, 0] + L[1, 1] + L[2, 2], want, rtol=0, atol=1e-13 * np.abs(want).max()
        )


def test_expm_so3_against_the_matrix_exponential():
    """Rodrigues' formula written out on scalars against scipy's expm of the skew matrix, from
    1e-12 rad (the series branch below 1e-8) to 3 rad: agreement to 1e-13 (expm's own
    accuracy at 3 rad is ~1e-14 per entry, and the formula's cancellation in 1 - cos adds a
    few ulps), orthogonal to 1e-14, determinant 1."""
    from scipy.linalg import expm

    rng = np.random.default_rng(5)
    for scale in (1e-12, 1e-9, 1e-7, 1e-3, 0.5, 3.0):
        for _ in range(50):
            t = rng.normal(size=3) * scale
            R = expm_so3(t)
            assert np.abs(R - expm(skew(t))).max() < 1e-13
            assert np.abs(R.T @ R - np.eye(3)).max() < 1e-14
            assert abs(np.linalg.det(R) - 1.0) < 1e-14
    assert np.array_equal(expm_so3(np.zeros(3)), np.eye(3))
