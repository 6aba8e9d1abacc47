"""Mixed LCP of constraint impulses: complementarity on random SPD problems.

Tolerance: 1e-9 relative to |D| |l| + |c|; the solver adds a 1e-12 relative regularisation.
"""

import numpy as np

from flexmvm.integrate.moreau_jean.lcp import solve_mixed_lcp


def test_random_mixed_lcps_satisfy_complementarity():
    rng = np.random.default_rng(1)
    for _ in range(300):
        m = int(rng.integers(1, 12))
        ne = int(rng.integers(0, m + 1))
        B = rng.normal(size=(m, m))
        D = B @ B.T + 0.1 * np.eye(m)
        c = rng.normal(size=m)
        lam = solve_mixed_lcp(D, c, ne)
        w = D @ lam + c
        tol = 1e-9 * (np.abs(D).max() * np.abs(lam).max() + np.abs(c).max())
        assert np.all(np.abs(w[:ne]) < tol)
        assert np.all(lam[ne:] >= -tol) and np.all(w[ne:] >= -tol)
        assert abs(lam[ne:] @ w[ne:]) < tol * (1 + np.abs(lam).max())


def test_separating_rows_get_no_impulse():
    D = np.array([[2.0, 0.5], [0.5, 1.0]])
    assert np.all(solve_mixed_lcp(D, np.array([1.0, 2.0]), 0) == 0.0)


# -- positive semidefinite Delassus matrices, as contact produces them ----------------------
from scipy.optimize import minimize

from flexmvm.integrate.moreau_jean.lcp import LCP_RTOL, complementarity_residual, solve_checked


def _two_reduced_bodies_delassus(rng, m: int, n1: int, n2: int):
    """D = G1 W1^-1 G1^T + G2 W2^-1 G2^T for two bodies with n1, n2 coordinates (random SPD
    iteration matrices, spread over 4 decades as M + h^2/4 K is) and m contact rows acting on
    both with opposite signs: rank <= n1 + n2 < m gives redundant rows (many contact nodes on
    a patch carried by few coordinates)."""

    def spd(n):
        Q, _ = np.linalg.qr(rng.normal(size=(n, n)))
        return Q @ np.diag(10.0 ** rng.uniform(-2, 2, n)) @ Q.T

    G1, G2 = rng.normal(size=(m, n1)), -rng.normal(size=(m, n2))
    D = G1 @ np.linalg.solve(spd(n1), G1.T) + G2 @ np.linalg.solve(spd(n2), G2.T)
    # free relative velocities c = G v of some velocity v of the bodies: the LCP is then
    # feasible (v+ = 0 satisfies every row), as it is for contact rows of a time step
    c = np.hstack([G1, G2]) @ rng.normal(size=n1 + n2)
    return D, c


def _qp_value(lam, D, c):
    return 0.5 * lam @ D @ lam + c @ lam


def test_semidefinite_delassus_with_redundant_rows():
    """m = 24 contact rows on two reduced bodies of 6 + 4 coordinates each (rank 20 < 24): the
    LCP is the convex QP min 1/2 l^T D l + c^T l, l >= 0, whose w = D l + c is unique even
    though l is not. Checked: the natural residual <= LCP_RTOL (1e-8 of the velocity scale; a
    wrong active set gives ~1), and the QP value no worse than an independent bound-constrained
    quasi-Newton solve (L-BFGS-B, started from 0) by more than 1e-9 of the value scale."""
    rng = np.random.default_rng(7)
    for trial in range(40):
        m = 24
        D, c = _two_reduced_bodies_delassus(rng, m, 10, 10)
        assert np.linalg.matrix_rank(D, tol=1e-9 * np.abs(D).max()) <= 20
        lam, res = solve_checked(D, c, 0)
        assert res <= LCP_RTOL
        assert np.all(lam >= 0.0)
        ref = minimize(
            _qp_value,
            np.zeros(m),
            args=(D, c),
            jac=lambda x, D=D, c=c: D @ x + c,
            bounds=[(0.0, None)] * m,
            method="L-BFGS-B",
            options={"ftol": 1e-15, "gtol": 1e-12, "maxiter": 20000},
        )
        scale = max(abs(ref.fun), np.abs(c).max() ** 2 / np.abs(np.diag(D)).max())
        assert _qp_value(lam, D, c) <= ref.fun + 1e-9 * scale, trial


def test_semidefinite_delassus_with_joint_rows():
    """Two joint (equality) rows on top of 14 redundant contact rows of two reduced bodies."""
    rng = np.random.default_rng(11)
    for _ in range(40):
        D, c = _two_reduced_bodies_delassus(rng, 16, 6, 6)
        lam, res = solve_checked(D, c, 2)
        assert res <= LCP_RTOL
        w = D @ lam + c
        assert np.abs(w[:2]).max() <= 1e-8 * np.abs(c).max()


def test_residual_detects_a_wrong_solution():
    """The residual is ~1 for an impulse that violates complementarity (it can fail)."""
    D = np.array([[2.0, 0.5], [0.5, 1.0]])
    c = np.array([-1.0, 1.0])
    good, _ = solve_checked(D, c, 0)
    assert complementarity_residual(D, c, 0, good) <= 1e-14
    assert complementarity_residual(D, c, 0, np.zeros(2)) > 0.1  # penetrating row
    assert complementarity_residual(D, c, 0, good + [0.0, 0.3]) > 0.1  # impulse on a gap


def test_contact_runs_check_every_lcp(monkeypatch):
    """Every LCP of a real contact run is solved to LCP_RTOL and the run's summary carries the
    largest residual. The case makes the Delassus matrices singular as reduced contact does:
    the flat-on-flat short rods (tests/data/short_flat_impact.toml, 25 contact rows) with both
    bodies modal with 4 modes, so 25 rows act on 2 x 10 coordinates (rank <= 20)."""
    from pathlib import Path

    from flexmvm.integrate.moreau_jean import coulomb
    from flexmvm.runs.run import run_scenario
    from flexmvm.scenarios import ModelConfig, load_scenario

    seen = []

    def spy(D, c, n_eq, rtol=LCP_RTOL, where=""):
        out = solve_checked(D, c, n_eq, rtol, where)
        seen.append((D.copy(), out[1]))
        return out

    # both steps (general and non-rotating) solve through coulomb.solve_contact_impulses
    monkeypatch.setattr(coulomb, "solve_checked", spy)
    sc = load_scenario(Path(__file__).parent / "data" / "short_flat_impact.toml")
    modal = ModelConfig(kind="modal", modes=4)
    run = run_scenario(sc.with_overrides(body_models={"b1": modal, "b2": modal}))
    assert seen and run.summary["lcp_residual_max"] == max(r for _, r in seen)
    assert run.summary["lcp_residual_max"] <= LCP_RTOL
    singular = [np.linalg.matrix_rank(D, tol=1e-10 * np.abs(D).max()) < len(D) for D, _ in seen]
    assert sum(singular) >= len(seen) // 2
    assert run.summary["max_contact_force_interval_mean_N"] > 0.0


def test_active_set_kernel_agrees_with_nnls():
    """The compiled active-set method (lcp.active_set_qp, the contact-only path) and NNLS on
    the regularised Cholesky factor (scipy, the fallback; refined) solve the same LCPs: on 300
    random SPD problems of 1..60 rows with condition numbers below 1e4 (the seed case's
    Delassus matrices: below 6) the impulses agree to 1e-10 of their largest and both
    complementarity residuals are round-off (<= 1e-12)."""
    from flexmvm.integrate.moreau_jean.lcp import _nnls, _refine, active_set_qp

    rng = np.random.default_rng(7)
    n_active = 0
    for _ in range(300):
        m = int(rng.integers(1, 61))
        B = rng.standard_normal((m, m + 3))
        D = B @ B.T + 0.1 * m * np.eye(m)
        c = rng.standard_normal(m) * 10.0 ** rng.uniform(-3, 3)
        lam, ok = active_set_qp(D, c.copy(), 1e-13 * np.abs(c).max(), 3 * m + 30)
        ref = _refine(D, c, 0, _nnls(D, c)) if np.any(c < 0) else np.zeros(m)
        assert ok
        assert np.abs(lam - ref).max() <= 1e-10 * max(np.abs(ref).max(), 1e-300)
        assert complementarity_residual(D, c, 0, lam) <= 1e-12
        assert np.all(lam >= 0.0)
        n_active += int((lam > 0).sum())
    assert n_active > 1000  # the problems are not trivial: many rows carry impulses


def test_redundant_rows_and_the_nnls_fallback(monkeypatch):
    """Two identical contact rows (a redundant pair) are solved by the kernel (it adds rows
    one at a time and never needs the singular block); with the kernel made to fail (as it
    does on a singular passive block), solve_mixed_lcp falls back to NNLS on the regularised
    factor and still solves the LCP."""
    from flexmvm.integrate.moreau_jean import lcp

    D = np.array([[1.0, 1.0, 0.2], [1.0, 1.0, 0.2], [0.2, 0.2, 2.0]])
    c = np.array([-1.0, -1.0, -0.5])
    lam = solve_mixed_lcp(D, c, 0)
    assert complementarity_residual(D, c, 0, lam) <= 1e-12
    monkeypatch.setattr(lcp, "_active_set", lambda D, c: (np.zeros(len(c)), False))
    lam = solve_mixed_lcp(D, c, 0)
    assert complementarity_residual(D, c, 0, lam) <= LCP_RTOL
