"""BodySolver.nodal_inverse: W_qq^-1 psi^T N^T from cached nodal columns equals the direct
back-substitution (an identity of linear algebra: tolerance round-off, 1e-10 relative)."""

import dataclasses

import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.integrate.moreau_jean.body_solver import BodySolver


def _body(sparse: bool, n=40, seed=1):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, 3))
    B = sp.random(n, n, density=0.1, random_state=seed)
    Ms = sp.csr_matrix(B @ B.T + sp.eye(n))
    nq = 3 * n - 6
    psi = sp.csr_matrix(sp.eye(3 * n).tocsc()[:, 6:]) if sparse else rng.normal(size=(3 * n, 20))
    nq = psi.shape[1]
    Kd = sp.random(nq, nq, density=0.05, random_state=seed + 1)
    K = Kd @ Kd.T + sp.eye(nq)
    K = sp.csr_matrix(K) if sparse else K.toarray()
    return FlexibleBody.build("b", X, Ms, psi, K), rng


def _selector(rng, m, n, nodes):
    rows, cols, vals = [], [], []
    for i in range(m):
        picked = rng.choice(nodes, size=4, replace=False)
        d = rng.normal(size=3)
        for k in picked:
            for c in range(3):
                rows.append(i)
                cols.append(3 * k + c)
                vals.append(rng.uniform() * d[c])
    return sp.csr_matrix((vals, (rows, cols)), shape=(m, 3 * n))


@pytest.mark.parametrize("sparse", [True, False])
def test_nodal_inverse_equals_direct_solve(sparse):
    body, rng = _body(sparse)
    solver = BodySolver(body, theta=0.55)
    h = 1e-3
    n = len(body.X)
    for nodes in (np.arange(0, 12), np.arange(6, 30), np.arange(0, n)):  # overlap: cache reuse
        N = _selector(rng, 7, n, nodes)
        got = solver.nodal_inverse(h, N)
        rhs = N @ body.psi
        rhs = rhs.toarray() if sp.issparse(rhs) else np.asarray(rhs)
        want = np.asarray(solver._factor(h).solve(np.ascontiguousarray(rhs.T)))
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-10 * np.abs(want).max())


@pytest.mark.parametrize("sparse", [True, False])
def test_solve_nodal_equals_bordered_solve(sparse):
    """W^-1 Phi^T for rows Phi = [frame part, N psi] through the cached nodal columns equals
    the back-substitution of the explicit rows (joint rows of large bodies take this path):
    linear algebra, so round-off (1e-10 relative; the frame Schur complement is well
    conditioned for this random body)."""
    body, rng = _body(sparse)
    solver = BodySolver(body, theta=0.55)
    h = 1e-3
    solver.prepare(
        h,
        np.eye(3),
        body.frame_mass(
            np.eye(3),
            body.first_moment(np.zeros(body.nq)),
            body.frame_inertia_first_order(np.zeros(body.nq)),
        ),
    )
    n = len(body.X)
    N = _selector(rng, 5, n, np.arange(n))
    bf = rng.normal(size=(5, 6))
    bq = N @ body.psi
    bq = bq.toarray() if sp.issparse(bq) else np.asarray(bq)
    got = solver.solve_nodal(h, bf, N)
    want = solver.solve(np.hstack([bf, bq]).T)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-10 * np.abs(want).max())


@pytest.mark.parametrize("sparse", [True, False])
def test_solve_frame_equals_bordered_solve_of_frame_rows(sparse):
    """W^-1 [bf; 0] from the frame Schur complement and the cached Z columns alone (the later
    Newton iterates whose residual sits in the frame rows) equals the full bordered solve of
    the same right-hand side: linear algebra, round-off (1e-10 relative)."""
    body, rng = _body(sparse)
    solver = BodySolver(body, theta=0.55)
    h = 1e-3
    A = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    q = 1e-3 * rng.normal(size=body.nq)
    solver.prepare(
        h, A, body.frame_mass(A, body.first_moment(q), body.frame_inertia_first_order(q))
    )
    bf = rng.normal(size=6)
    got = solver.solve_frame(bf)
    want = solver.solve(np.concatenate([bf, np.zeros(body.nq)]))
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-10 * np.abs(want).max())


@pytest.mark.parametrize("sparse", [True, False])
def test_schur_complement_follows_a_kept_coupling_to_first_order(sparse):
    """When refresh_coupling keeps the M_wq of W (drift below its tolerance), prepare() still
    makes the frame Schur complement of the current M_wq to first order in the drift: its
    error is second order (here relative drift 1e-5: the error must fall by more than 1e3
    against the stale complement; measured 1.9e4 and 5.0e4 on these bodies)."""
    from flexmvm.integrate.moreau_jean.dense_solve import lu_solve

    body, rng = _body(sparse)
    h = 1e-3
    A = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    q = 1e-3 * rng.normal(size=body.nq)
    Mff = body.frame_mass(A, body.first_moment(q), body.frame_inertia_first_order(q))
    Mw0 = body.rotational_coupling(np.zeros(body.nq))
    Mw = Mw0 + 1e-5 * np.linalg.norm(Mw0) * rng.normal(size=Mw0.shape) / np.sqrt(Mw0.size)
    Wqq = body.inv.M_qq + (0.55 * h) ** 2 * body.k_hat
    Wqq = Wqq.toarray() if sp.issparse(Wqq) else np.asarray(Wqq)
    B = np.vstack([A @ np.asarray(body.inv.S1), Mw])
    S_exact = Mff - B @ np.linalg.solve(Wqq, B.T)

    def schur_error(solver):
        S_inv = lu_solve(solver._schur, np.eye(6))
        return np.abs(S_inv @ S_exact - np.eye(6)).max()

    kept = BodySolver(body, theta=0.55)
    kept.refresh_coupling(h, Mw, tol=1e-3)  # kept: drift 1e-5 < 1e-3
    assert kept.n_coupling_updates == 0
    kept.prepare(h, A, Mff)
    stale = BodySolver(body, theta=0.55)  # the complement with M_wq(0), uncorrected
    stale.prepare(h, A, Mff)
    assert schur_error(kept) < 1e-3 * schur_error(stale)


@pytest.mark.parametrize("sparse", [True, False])
def test_elastic_rows_of_a_solve_are_known(sparse):
    """For x = W^-1 b: W_qq x_q = b_q - B^T x_f with B^T x_f = coupling_transpose(x_f), for
    a full solve, a frame-only solve and a solve through the nodal columns, also with a
    refreshed and with a kept (drifted) coupling: what the integrator takes k_hat dq_dot from
    (moreau_jean._WImages). Round-off of the solve (1e-10 of the largest term)."""
    body, rng = _body(sparse)
    solver = BodySolver(body, theta=0.55)
    h = 1e-3
    A = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    n = len(body.X)
    Wqq = body.inv.M_qq + (0.55 * h) ** 2 * body.k_hat
    for drift in (0.0, 1e-5, 1e-2):
        q = drift * rng.normal(size=body.nq)
        solver.refresh_coupling(h, body.rotational_coupling(q), 1e-4)
        solver.prepare(
            h, A, body.frame_mass(A, body.first_moment(q), body.frame_inertia_first_order(q))
        )
        b = rng.normal(size=body.nv)
        N = _selector(rng, 4, n, np.arange(n))
        bf = rng.normal(size=(4, 6))
        lam = rng.normal(size=4)
        cases = [
            (b, solver.solve(b)),
            (np.concatenate([b[:6], np.zeros(body.nq)]), solver.solve_frame(b[:6])),
        ]
        rows_q = np.asarray(N @ body.psi.toarray() if sparse else N @ body.psi)
        cases.append(
            (np.concatenate([bf.T @ lam, rows_q.T @ lam]), solver.solve_nodal(h, bf, N) @ lam)
        )
        for rhs, x in cases:
            got = Wqq @ x[6:]
            want = rhs[6:] - solver.coupling_transpose(x[:6])
            size = max(np.abs(rhs[6:]).max(), np.abs(solver.coupling_transpose(x[:6])).max())
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-10 * size)


@pytest.mark.parametrize("sparse", [True, False])
def test_a_deferred_refresh_solves_as_an_immediate_one(sparse):
    """refresh_coupling(defer=True) solves the 3 columns W_qq^-1 M_wq^T with the next solve's
    right-hand side (one multi-column back-substitution): that solve, and every later use of
    W (solve, solve_frame, contact columns, coupling_transpose), equals the solver refreshed
    at once; a first use other than solve() solves the columns on their own. Linear algebra:
    round-off (1e-10 of the largest entry)."""
    body, rng = _body(sparse)
    h = 1e-3
    A = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    q = 1e-2 * rng.normal(size=body.nq)
    Mw = body.rotational_coupling(q)
    Mff = body.frame_mass(A, body.first_moment(q), body.frame_inertia_first_order(q))
    n = len(body.X)
    N = _selector(rng, 4, n, np.arange(n))
    bf = rng.normal(size=(4, 6))
    b, b2, xf = (rng.normal(size=body.nv), rng.normal(size=body.nv), rng.normal(size=6))

    def uses(solver, first):
        out = [
            first(solver),
            solver.solve(b2),
            solver.solve_frame(b2[:6]),
            solver.solve_nodal(h, bf, N),
            solver.coupling_transpose(xf),
        ]
        assert solver.n_coupling_updates == 1 and solver._pending is None
        return out

    def made(defer):
        solver = BodySolver(body, theta=0.5)
        solver.refresh_coupling(h, Mw, tol=1e-6, defer=defer)
        solver.prepare(h, A, Mff)
        assert solver.n_coupling_updates == (0 if defer else 1)
        return solver

    want = uses(made(False), lambda s: s.solve(b))
    for first in (
        lambda s: s.solve(b),
        lambda s: s.solve(np.column_stack([b, b2]))[:, 0],
        lambda s: (s.solve_frame(b[:6]), s.solve(b))[1],
        lambda s: (s.coupling_transpose(xf), s.solve(b))[1],
    ):
        for got, w in zip(uses(made(True), first), want):
            np.testing.assert_allclose(got, w, rtol=0, atol=1e-10 * np.abs(w).max())


def test_an_order_found_absent_is_not_sought_again(monkeypatch):
    """A body whose elimination order was looked for and none exists (assembly.solver_choice stores
    an empty order) is factored in SuperLU's minimum degree without a second search; a body
    with no order at all (None, built through the API) gets one searched by the solver."""
    import flexmvm.integrate.moreau_jean.body_solver as bs

    calls = []

    def counting(W):
        calls.append(W.shape[0])

    monkeypatch.setattr(bs, "elimination_order", counting)
    body = _body(True)[0]
    x = np.random.default_rng(3).normal(size=body.nv)
    A = np.eye(3)
    Mff = body.frame_mass(
        A, body.first_moment(np.zeros(body.nq)), body.frame_inertia_first_order(np.zeros(body.nq))
    )
    results = []
    for b in (body, dataclasses.replace(body, elimination_order=np.zeros(0, np.int64))):
        solver = BodySolver(b, 0.55)
        solver.prepare(1e-6, A, Mff)
        results.append(solver.solve(x))
    assert calls == [body.nq]
    np.testing.assert_array_equal(results[0], results[1])
