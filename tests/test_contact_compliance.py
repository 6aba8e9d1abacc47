"""integrate.moreau_jean.compliance: the contact compliance D = Phi W^-1 Phi^T and the velocity
correction W^-1 Phi^T lambda from the cached nodal columns equal the explicit dense formulas (W^-1
by a dense solve) to 1e-10 relative, for the 6 x 6 frame Schur complement (Newton step) and the
3 x 3 translational one (non-rotating step); also after the cache grew, and after
refresh_coupling replaced M_w (the cached M_w c_j and psi_j Z_w must follow). A selector
given as a NodalSelector (CSR arrays, read by a compiled kernel) gives bit for bit what its
scipy matrix gives."""

import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.constraints.rows import NodalSelector, Rows, stack
from flexmvm.integrate.moreau_jean.body_solver import BodySolver

H_STEP = 1e-3
TOL = 1e-10


def _body(kind: str, n: int = 30, seed: int = 3) -> FlexibleBody:
    """A small random body: psi a selection of free DOFs ("select", as a full FE model),
    a general sparse psi ("sparse") or a dense one ("dense")."""
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, 3))
    B = sp.random(n, n, density=0.1, random_state=seed)
    Ms = sp.csr_matrix(B @ B.T + sp.eye(n))
    if kind == "select":
        psi = sp.csr_matrix(sp.eye(3 * n).tocsc()[:, 6:])
    elif kind == "sparse":
        psi = sp.random(3 * n, 40, density=0.08, random_state=seed) + sp.eye(3 * n, 40)
        psi = sp.csr_matrix(psi)
    else:
        psi = rng.normal(size=(3 * n, 25))
    nq = psi.shape[1]
    Kd = sp.random(nq, nq, density=0.05, random_state=seed + 1)
    K = Kd @ Kd.T + sp.eye(nq)
    K = sp.csr_matrix(K) if sp.issparse(psi) else K.toarray()
    return FlexibleBody.build("b", X, Ms, psi, K)


def _dense(a) -> np.ndarray:
    return a.toarray() if sp.issparse(a) else np.asarray(a)


def _selector(rng, m: int, n_nodes: int, nodes: np.ndarray) -> sp.csr_matrix:
    """m rows, each a random direction on 1 to 4 random nodes among `nodes`."""
    rows, cols, vals = [], [], []
    for i in range(m):
        d = rng.normal(size=3)
        for k in rng.choice(nodes, size=rng.integers(1, 5), replace=False):
            rows += [i] * 3
            cols += [3 * k, 3 * k + 1, 3 * k + 2]
            vals += list(rng.uniform() * d)
    return sp.csr_matrix((vals, (rows, cols)), shape=(m, 3 * n_nodes))


def _wqq(body: FlexibleBody, theta: float) -> np.ndarray:
    return _dense(body.inv.M_qq) + (theta * H_STEP) ** 2 * _dense(body.k_hat)


def _setup(kind: str, theta: float = 0.55):
    body = _body(kind)
    rng = np.random.default_rng(7)
    A = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    return body, BodySolver(body, theta), rng, A, _wqq(body, theta)


def _prepare_full(solver, body, rng, A, Wqq, Mw) -> np.ndarray:
    """Refresh M_w, prepare the 6 x 6 form with an SPD W; returns the dense W."""
    solver.refresh_coupling(H_STEP, Mw, 0.0)
    B = np.vstack([A @ body.inv.S1, Mw])
    R = rng.normal(size=(6, 6))
    Mff = B @ np.linalg.solve(Wqq, B.T) + R @ R.T + 0.1 * np.eye(6)
    solver.prepare(H_STEP, A, Mff)
    return np.block([[Mff, B], [B.T, Wqq]])


def _check(comp, Phi, W, lam) -> None:
    Y = np.linalg.solve(W, Phi.T)
    D = Phi @ Y
    assert np.abs(comp.D - D).max() <= TOL * np.abs(D).max()
    v = Y @ lam
    assert np.abs(comp.velocity(lam) - v).max() <= TOL * np.abs(v).max()


@pytest.mark.parametrize("kind", ["select", "sparse", "dense"])
def test_full_form_equals_dense_formula(kind):
    """6 x 6 Schur form: overlapping selectors (cache reuse and growth), then a changed M_w."""
    body, solver, rng, A, Wqq = _setup(kind)
    n = len(body.X)
    Mw0 = body.inertia_terms(np.zeros(body.nq))[2]
    selections = (np.arange(0, 8), np.arange(4, 20), np.arange(0, n), np.arange(10, 25))
    for i, nodes in enumerate(selections):
        Mw = Mw0 * (1.0 + 0.1 * i) + 0.01 * rng.normal(size=Mw0.shape)
        W = _prepare_full(solver, body, rng, A, Wqq, Mw)
        m = 9
        N, bf = _selector(rng, m, n, nodes), rng.normal(size=(m, 6))
        Phi = np.hstack([bf, _dense(N @ body.psi)])
        _check(solver.contact_compliance(H_STEP, bf, N), Phi, W, rng.normal(size=m))


@pytest.mark.parametrize("kind", ["select", "sparse", "dense"])
def test_translational_form_equals_dense_formula(kind):
    """3 x 3 Schur form (non-rotating step): W_t = [[m I, A S1], [S1^T A^T, W_qq]]."""
    body, solver, rng, A, Wqq = _setup(kind)
    n = len(body.X)
    B = A @ body.inv.S1
    W = np.block([[body.inv.mass * np.eye(3), B], [B.T, Wqq]])
    solver.prepare_translation(H_STEP, A)
    for nodes in (np.arange(0, 8), np.arange(4, 20), np.arange(0, n)):
        m = 11
        N, bf = _selector(rng, m, n, nodes), rng.normal(size=(m, 6))
        Phi = np.hstack([bf[:, :3], _dense(N @ body.psi)])
        _check(solver.translation_compliance(H_STEP, bf, N), Phi, W, rng.normal(size=m))


def test_velocity_reads_only_rows_with_impulse():
    """Rows with zero impulse do not contribute (the kernel skips their columns) and the
    result is still exact: one active row among many."""
    body, solver, rng, A, Wqq = _setup("select")
    Mw = body.inertia_terms(np.zeros(body.nq))[2]
    W = _prepare_full(solver, body, rng, A, Wqq, Mw)
    m = 6
    N, bf = _selector(rng, m, len(body.X), np.arange(len(body.X))), rng.normal(size=(m, 6))
    Phi = np.hstack([bf, _dense(N @ body.psi)])
    lam = np.zeros(m)
    lam[2] = 1.5
    _check(solver.contact_compliance(H_STEP, bf, N), Phi, W, lam)


def _raw_selector(rng, m: int, n_nodes: int, nodes: np.ndarray, sort: bool = True):
    """CSR arrays of m rows as contact rows make them (ContactNodes.rows: 3 DOFs per node,
    columns ascending within a row), with what the scipy path must agree on too: a node
    repeated in a row (its columns add), explicit zeros and -0.0 (a direction with a zero
    component). sort=False leaves the columns of each row in node order."""
    data, idx, ptr = [], [], [0]
    for i in range(m):
        d = rng.normal(size=3)
        d[rng.integers(0, 3)] = rng.choice([0.0, -0.0])
        row = list(rng.choice(nodes, size=rng.integers(1, 5), replace=False))
        if i % 3 == 0:
            row.append(row[0])
        entries = [(3 * k + j, rng.uniform() * d[j]) for k in row for j in range(3)]
        if sort:
            entries.sort(key=lambda e: e[0])  # stable, as pair_rows._sort_row
        idx += [c for c, _ in entries]
        data += [v for _, v in entries]
        ptr.append(len(idx))
    return (
        np.array(data),
        np.array(idx, dtype=np.int64),
        np.array(ptr, dtype=np.int64),
        (m, 3 * n_nodes),
    )


@pytest.mark.parametrize("kind", ["select", "dense"])
@pytest.mark.parametrize("sort", [True, False])
def test_nodal_selector_equals_its_csr_bit_for_bit(kind, sort):
    """The same rows as a NodalSelector and as the scipy matrix of its arrays: the same
    slots and N_d, D and velocity bit for bit (both caches growing alike), also for rows
    with a repeated node, explicit zeros, -0.0, and (sort=False) unsorted columns, which
    the kernel hands back to the scipy path. N @ x and stack read it as that matrix."""
    body, solver_a, rng, A, Wqq = _setup(kind)
    solver_b = BodySolver(body, 0.55)
    n = len(body.X)
    Mw = body.inertia_terms(np.zeros(body.nq))[2]
    for s in (solver_a, solver_b):
        _prepare_full(s, body, np.random.default_rng(1), A, Wqq, Mw)
    for nodes in (np.arange(0, 8), np.arange(4, 20), np.arange(0, n)):
        m = 10
        data, idx, ptr, shape = _raw_selector(rng, m, n, nodes, sort)
        sel = NodalSelector(data, idx, ptr, shape)
        csr = sp.csr_matrix((data.copy(), idx.copy(), ptr.copy()), shape=shape)
        bf, lam = rng.normal(size=(m, 6)), rng.normal(size=m)
        got = solver_a.contact_compliance(H_STEP, bf, sel)
        want = solver_b.contact_compliance(H_STEP, bf, csr)
        np.testing.assert_array_equal(got.D, want.D)
        np.testing.assert_array_equal(got.velocity(lam), want.velocity(lam))
        ca, cb = solver_a._f.nodal, solver_b._f.nodal
        for (sa, Na), (sb, Nb) in zip([ca.touch(sel, None)], [cb.touch(csr, None)]):
            np.testing.assert_array_equal(sa, sb)
            np.testing.assert_array_equal(Na, Nb)
            assert np.array_equal(np.signbit(Na), np.signbit(Nb))
        x = rng.normal(size=shape[1])
        np.testing.assert_array_equal(sel @ x, csr @ x)
        rows = Rows(m, {0: (bf, np.zeros((m, body.nq)))}, {0: sel})
        stacked = stack([rows, rows]).nodal_selector(0)
        assert (stacked != sp.vstack([csr, csr])).nnz == 0


@pytest.mark.parametrize("sort", [True, False])
def test_transpose_times_through_the_selector(sort):
    """Phi^T lambda of a full-FE body's rows (row_products.body_impulse: N^T lambda summed
    entry by entry and gathered at each coordinate's DOF, no transposed matrices) equals the
    dense block's bq^T lambda, bit for bit against the scipy transpose product it replaced,
    for a NodalSelector (repeated nodes, explicit zeros, -0.0, unsorted columns) and its csr."""
    from flexmvm.integrate.row_products import body_impulse

    body = _body("select", n=30, seed=9)
    assert body.nodal is not None
    rng = np.random.default_rng(10)
    m = 9
    data, idx, ptr, shape = _raw_selector(rng, m, len(body.X), np.arange(len(body.X)), sort)
    csr = sp.csr_matrix((data.copy(), idx.copy(), ptr.copy()), shape=shape)
    bf, lam = rng.normal(size=(m, 6)), rng.normal(size=m)
    bq = _dense(csr @ body.psi)
    want = np.concatenate([bf.T @ lam, bq.T @ lam])
    old = np.asarray(body.psi.T @ (csr.T @ lam)).ravel()
    for sel in (NodalSelector(data, idx, ptr, shape), csr):
        got = body_impulse(Rows(m, {0: (bf, bq)}, {0: sel}), 0, body, lam)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-14 * np.abs(want).max())
        np.testing.assert_array_equal(got[6:], old)
