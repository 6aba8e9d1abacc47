"""Mixed LCP of constraint impulses: complementarity on random SPD problems.

Tolerance: 1e-9 relative to |D| |l| + |c|; the solver adds a 1e-12 relative regularisation.
"""

import numpy as np

from flexmvm.integrate.lcp import solve_mixed_lcp


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
