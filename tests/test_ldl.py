"""fe.solvers.ldl: the supernodal L D L^T solve (of fe.solvers.cholesky's factor) equals SuperLU's solve.

Both solve the same matrix with the same ordering, so they agree to round-off: the
tolerance 1e-12 relative is ~1e3 machine epsilons, the growth of rounding through a
triangular solve of a well-conditioned matrix. A residual check (|A x - b| / |b| < 1e-10 for
a matrix of condition ~1e3) guards against an agreement of two wrong answers.
"""

import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
import scipy.sparse as sp
from test_fe import tube_hex27

from flexmvm.errors import SolverError
from flexmvm.fe import assemble
from flexmvm.fe.solvers.cholesky import cholesky_ldl, ldl_factor
from flexmvm.fe.solvers.ldl import BACKWARD_RTOL, SPLIT_MIN_N
from flexmvm.fe.solvers.superlu import superlu_spd
from flexmvm.fe.solvers.symbolic import SymbolicFactor
from flexmvm.materials import ALUMINIUM


@pytest.fixture(scope="module")
def iteration_matrix():
    """W = M + (theta h)^2 K of a free Hex27 tube (SPD: M is), as the integrator makes it."""
    fe = assemble(tube_hex27(n_theta=12, n_r=2, n_x=6), ALUMINIUM)
    th_h = 0.55 * 2e-6
    return sp.csc_matrix(fe.M + th_h**2 * fe.K)


def test_supernodes_found(iteration_matrix):
    ldl = cholesky_ldl(iteration_matrix)
    assert 1 <= ldl.n_supernodes < ldl.n  # Hex27 nodes couple 3 DOFs: runs of >= 3 columns


@pytest.mark.parametrize("k", [0, 1, 3, 8, 40])
def test_equals_superlu_solve(iteration_matrix, k):
    """From BLAS_MIN_COLUMNS right-hand sides the blocks go through BLAS (8, 40 here): the
    same answer to round-off."""
    A = iteration_matrix
    lu = superlu_spd(A)
    solve = cholesky_ldl(A).solve
    rng = np.random.default_rng(k)
    b = rng.standard_normal(A.shape[0]) if k == 0 else rng.standard_normal((A.shape[0], k))
    x = solve(b)
    assert x.shape == b.shape
    want = lu.solve(b)
    np.testing.assert_allclose(x, want, rtol=0, atol=1e-12 * np.abs(want).max())
    res = np.abs(A @ x - b).max() / np.abs(b).max()
    assert res < 1e-10


def test_threads_give_the_serial_answer(iteration_matrix):
    """The kernel releases the GIL; two threads solving at once get the serial results."""
    solve = ldl_factor(iteration_matrix)
    rng = np.random.default_rng(5)
    bs = [rng.standard_normal(iteration_matrix.shape[0]) for _ in range(4)]
    serial = [solve(b) for b in bs]
    got = [None] * 4

    def work(i):
        got[i] = solve(bs[i])

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for a, b in zip(got, serial):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("k", [0, 3])
def test_two_halves_on_two_threads(iteration_matrix, k):
    """A solve split into its two etree halves (a pool given) equals the solve without the
    pool bit for bit (same arithmetic, other threads) and SuperLU's to round-off; the split
    really happens on this tube (4,680 DOFs: above SPLIT_MIN_N, halves of ~equal work)."""
    A = iteration_matrix
    lu = superlu_spd(A)
    serial = cholesky_ldl(A)
    assert serial.split
    first, second, top = serial._halves[:3]
    assert len(first) and len(second)
    assert not set(first) & set(second) and not (set(first) | set(second)) & set(top)
    rng = np.random.default_rng(11 + k)
    b = rng.standard_normal(A.shape[0]) if k == 0 else rng.standard_normal((A.shape[0], k))
    want = lu.solve(b)
    with ThreadPoolExecutor(2) as pool:
        threaded = cholesky_ldl(A, pool)
        got = [threaded.solve(b) for _ in range(3)]
    x = serial.solve(b)
    np.testing.assert_allclose(x, want, rtol=0, atol=1e-12 * np.abs(want).max())
    for g in got:
        np.testing.assert_array_equal(g, x)


@pytest.mark.parametrize("kind", ["tube", "tridiagonal", "dense"])
def test_halves_are_whole_subtrees(iteration_matrix, kind):
    """What makes the halves independent: every row a supernode of one half updates (its
    rectangle's rows) is a column of the same half or of the top, never of the other half.
    A dense matrix (one supernode) has nothing to split."""
    from flexmvm.fe.solvers.ldl import etree_halves

    n = 60
    A = {
        "tube": iteration_matrix,
        "tridiagonal": sp.diags([-np.ones(n - 1), 2.5 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1]),
        "dense": np.ones((n, n)) + n * np.eye(n),
    }[kind]
    sym = SymbolicFactor(sp.csc_matrix(A))
    starts, r_off, rows = sym.starts, sym.r_off, sym.rows
    halves = etree_halves(starts, r_off, rows, 1.0)
    if kind == "dense":
        assert halves is None
        return
    label = np.full(sym.n, -1)
    for h, part in enumerate(halves):
        for s in part:
            label[starts[s] : starts[s + 1]] = h
    assert np.all(label >= 0) and len(halves[0]) and len(halves[1])
    for h in (0, 1):
        for s in halves[h]:
            assert set(label[rows[r_off[s] : r_off[s + 1]]]) <= {h, 2}


def test_zero_pivot_is_a_solver_error():
    """Without pivoting (the symmetric ordering) a zero diagonal pivot cannot be factored:
    a clear SolverError, not a division by zero inside the kernel."""
    A = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0]]))
    with pytest.raises(SolverError):
        ldl_factor(A)


@pytest.mark.parametrize("kind", ["diagonal", "dense", "tridiagonal"])
def test_edge_structures(kind):
    """Supernodes of width 1 with nothing below (diagonal), one supernode holding everything
    (dense), and chains (tridiagonal): solves equal SuperLU's to round-off."""
    n = 40
    rng = np.random.default_rng(3)
    if kind == "diagonal":
        A = sp.diags(rng.uniform(1, 2, n))
    elif kind == "dense":
        B = rng.standard_normal((n, n))
        A = sp.csc_matrix(B @ B.T + n * np.eye(n))
    else:
        A = sp.diags([-np.ones(n - 1), 2.5 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1])
    A = sp.csc_matrix(A)
    lu = superlu_spd(A)
    b = rng.standard_normal((n, 2))
    np.testing.assert_allclose(
        cholesky_ldl(A).solve(b), lu.solve(b), rtol=0, atol=1e-12 * np.abs(lu.solve(b)).max()
    )


@pytest.mark.parametrize("kind", ["diagonal", "two_chains"])
def test_forest_split_with_empty_top(kind):
    """An elimination tree that is a forest (a diagonal matrix; two uncoupled tridiagonal
    chains, e.g. two bodies in one matrix) splits into halves with nothing above them: the
    split is taken with an empty top (it raised ValueError from np.concatenate before) and
    the solve equals SuperLU's to round-off, with and without the pool."""
    n = SPLIT_MIN_N + 2
    rng = np.random.default_rng(5)
    if kind == "diagonal":
        A = sp.diags(rng.uniform(1, 2, n))
    else:
        chain = sp.diags(
            [-np.ones(n // 2 - 1), 2.5 * np.ones(n // 2), -np.ones(n // 2 - 1)], [-1, 0, 1]
        )
        A = sp.block_diag([chain, chain])
    A = sp.csc_matrix(A)
    lu = superlu_spd(A)
    with ThreadPoolExecutor(1) as pool:
        for p in (None, pool):
            ldl = cholesky_ldl(A, p)
            assert ldl.split
            for k in (3, 20):  # loops; blocks through BLAS
                b = rng.standard_normal((A.shape[0], k))
                np.testing.assert_allclose(
                    ldl.solve(b), lu.solve(b), rtol=0, atol=1e-12 * np.abs(lu.solve(b)).max()
                )


def test_backward_error_check_takes_ill_conditioned_spd_and_refuses_unsymmetric():
    """Given A, the factor is checked by the backward error of one solve, which does not grow
    with the conditioning: an SPD matrix of condition ~1e13 (a free beam's K - sigma M with
    sigma 1e-12 of its stiffness scale: LU and LDL^T solves then differ by 3e-6, both
    correct) is accepted; an unsymmetric one, whose lower triangle alone was factored, is
    refused."""
    fe = assemble(tube_hex27(n_x=3), ALUMINIUM)
    sigma = -1e-12 * float(fe.K.diagonal().mean() / fe.M.diagonal().mean())
    A = sp.csc_matrix(fe.K - sigma * fe.M)
    ldl = cholesky_ldl(A)
    b = np.random.default_rng(7).standard_normal(A.shape[0])
    x = ldl.solve(b)
    assert np.abs(A @ x - b).max() <= BACKWARD_RTOL * (abs(A).sum(axis=1).max() * np.abs(x).max())
    B = sp.csc_matrix(np.array([[4.0, 1.0, 0.0], [3.0, 5.0, 1.0], [0.0, 2.0, 6.0]]))
    with pytest.raises(SolverError, match="backward error"):
        cholesky_ldl(B)
