"""integrate.moreau_jean.compliance's sparse-row kernels: K = N_d P N_d^T and N_d X read from
the row entries of N_d (a contact row touches a slave node and a master facet's nodes, 3 to 15
of the n_d DOFs) equal the dense products they replaced. Tolerance 1e-13 of the largest entry:
the two differ only in the order of the same sums (the dense product adds exact zeros too),
a few ulps over ~15 terms; K exactly symmetric (computed once per pair, mirrored), which the
dense product was not."""

import numpy as np

from flexmvm.integrate.moreau_jean.compliance import row_entries, rows_times, sandwich


def _case(seed: int = 0, m: int = 40, n_d: int = 120, cap: int = 150):
    rng = np.random.default_rng(seed)
    Nd = np.zeros((m, n_d))
    for a in range(m):
        Nd[a, rng.choice(n_d, size=rng.integers(3, 16), replace=False)] = rng.normal(size=1)
    Nd[5] = 0.0  # a row with no entry (a pair whose weights are all zero)
    B = rng.normal(size=(cap, cap))
    P = B @ B.T
    slots = rng.permutation(cap)[:n_d]
    return Nd, P, slots


def test_sandwich_equals_the_dense_product_and_is_symmetric():
    Nd, P, slots = _case()
    counts, cols, vals = row_entries(Nd)
    assert counts[5] == 0 and counts.max() <= 15
    K = sandwich(counts, cols, vals, slots, P)
    want = Nd @ (P[np.ix_(slots, slots)] @ Nd.T)
    np.testing.assert_allclose(K, want, rtol=0, atol=1e-13 * np.abs(want).max())
    assert np.array_equal(K, K.T)


def test_rows_times_equals_the_dense_product():
    Nd = _case(seed=1)[0]
    X = np.random.default_rng(2).normal(size=(Nd.shape[1], 12))
    got = rows_times(*row_entries(Nd), X)
    want = Nd @ X
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-13 * np.abs(want).max())


def test_no_rows():
    counts, cols, vals = row_entries(np.zeros((0, 7)))
    assert sandwich(counts, cols, vals, np.arange(7), np.eye(7)).shape == (0, 0)
    assert rows_times(counts, cols, vals, np.ones((7, 3))).shape == (0, 3)
