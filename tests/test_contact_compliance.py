"""integrate.compliance: the contact compliance D = Phi W^-1 Phi^T and the velocity correction
W^-1 Phi^T lambda from the cached nodal columns equal the explicit dense formulas (W^-1 by a
dense solve) to 1e-10 relative, for the 6 x 6 frame Schur complement (Newton step) and the
3 x 3 translational one (non-rotating step); also after the cache grew, and after
refresh_coupling replaced M_w (the cached M_w c_j and psi_j Z_w must follow)."""

import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.integrate.body_solver import BodySolver

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
