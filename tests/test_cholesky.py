"""fe.solvers.cholesky: the supernodal multifrontal L D L^T against dense Cholesky and SuperLU.

Tolerances: the factor of a matrix of condition ~1e3 (the Hex27 tube's W = M + (theta h)^2 K)
agrees with LAPACK's dense Cholesky of the same ordered matrix to 1e-12 of the largest entry
(~1e4 machine epsilons: two summation orders of the same arithmetic); solves are held to a
backward error of 1e-14, what a stable Cholesky solve gives (~1e-16) with a margin. Structure
(elimination tree, column counts, supernode rows) is compared exactly.
"""

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from test_fe import tube_hex27

from flexmvm.errors import SolverError
from flexmvm.fe import assemble
from flexmvm.fe.solvers import spd
from flexmvm.fe.solvers.cholesky import cholesky_ldl, numeric_factor
from flexmvm.fe.solvers.ldl import SPLIT_MIN_N, SupernodalLDL
from flexmvm.fe.solvers.ordering import mmd_order
from flexmvm.fe.solvers.superlu import SPD_LU
from flexmvm.fe.solvers.symbolic import SymbolicFactor
from flexmvm.materials import ALUMINIUM


@pytest.fixture(scope="module")
def tube_w():
    """W = M + (theta h)^2 K of a free Hex27 tube (4,680 DOFs, SPD: M is)."""
    fe = assemble(tube_hex27(n_theta=12, n_r=2, n_x=6), ALUMINIUM)
    return sp.csc_matrix(fe.M + (0.55 * 2e-6) ** 2 * fe.K)


def _backward(A, x, b) -> float:
    return float(
        np.abs(A @ x - b).max() / (abs(A).sum(axis=1).max() * np.abs(x).max() + np.abs(b).max())
    )


def _unpack(sym, tri, rect, d):
    """Dense unit lower L and d of the packed factor, in the symbolic's order."""
    n = sym.n
    L = np.eye(n)
    for s in range(sym.starts.size - 1):
        c0, c1 = sym.starts[s], sym.starts[s + 1]
        w = c1 - c0
        T = tri[sym.t_off[s] : sym.t_off[s + 1]].reshape(w, w)
        L[c0:c1, c0:c1] += np.tril(T, -1)
        rows = sym.rows[sym.r_off[s] : sym.r_off[s + 1]]
        L[rows, c0:c1] = rect[sym.b_off[s] : sym.b_off[s + 1]].reshape(rows.size, w)
    return L, d


def test_factor_equals_dense_cholesky(tube_w):
    """L D L^T of the ordered matrix equals LAPACK's dense Cholesky L_c = L sqrt(D)."""
    sym = SymbolicFactor(tube_w)
    tri, rect, d = numeric_factor(sym, tube_w)
    L, d = _unpack(sym, tri, rect, d)
    p = sym.order
    Lc = np.linalg.cholesky(tube_w[p][:, p].toarray())
    np.testing.assert_allclose(L * np.sqrt(d), Lc, rtol=0, atol=1e-12 * np.abs(Lc).max())


def test_structure_is_the_exact_symbolic_factor(tube_w):
    """Column counts equal the nonzero counts of the dense Cholesky factor of the ordered
    pattern with random SPD values (no cancellation: every structural entry is nonzero);
    the supernodes hold every entry of L (amalgamation adds zeros, never drops an entry)."""
    rng = np.random.default_rng(0)
    A = tube_w.copy()
    A.data = rng.uniform(-1, 1, A.data.size)
    A = sp.csc_matrix(A + A.T)
    A = A + sp.diags(abs(A).sum(axis=1).A1 + 1.0)  # diagonally dominant: SPD
    sym = SymbolicFactor(A)
    p = sym.order
    Lc = np.linalg.cholesky(A[p][:, p].toarray())
    nz = np.abs(Lc) > 0
    np.testing.assert_array_equal(sym.column_counts, nz.sum(axis=0))
    held = np.zeros_like(nz)
    for s in range(sym.starts.size - 1):
        c0, c1 = sym.starts[s], sym.starts[s + 1]
        held[c0:c1, c0:c1] = np.tril(np.ones((c1 - c0, c1 - c0), bool))
        held[sym.rows[sym.r_off[s] : sym.r_off[s + 1]], c0:c1] = True
    assert not np.any(nz & ~held)
    assert sym.nnz == held.sum() >= nz.sum()
    # the parent of every column is its first below-diagonal row (elimination tree)
    first_below = [np.flatnonzero(nz[j + 1 :, j]) for j in range(sym.n)]
    parent = np.array([j + 1 + f[0] if f.size else -1 for j, f in enumerate(first_below)])
    assert np.all(parent[parent >= 0] > np.flatnonzero(parent >= 0))


def test_mmd_order_is_superlus():
    """mmd_order reads SuperLU's minimum-degree ordering without a factorization: the same
    permutation as splu's with fe.solvers.superlu.SPD_LU."""
    fe = assemble(tube_hex27(n_theta=8, n_r=1, n_x=4), ALUMINIUM)
    A = sp.csc_matrix(fe.M + 1e-12 * fe.K)
    perm_c = np.asarray(spla.splu(A, **SPD_LU).perm_c)
    want = np.empty_like(perm_c)
    want[perm_c] = np.arange(perm_c.size)
    np.testing.assert_array_equal(mmd_order(A), want)


@pytest.mark.parametrize("kind", ["tube", "diagonal", "dense", "two_chains", "one", "csr"])
def test_solves_to_round_off(tube_w, kind):
    """Backward error of block and single solves on structures at the edges: width-one
    supernodes with nothing below (diagonal), one supernode (dense), a forest (two uncoupled
    chains), a 1x1 matrix, and a CSR input (factored through its transpose)."""
    rng = np.random.default_rng(2)
    n = 50
    if kind in ("tube", "csr"):
        A = tube_w if kind == "tube" else sp.csr_matrix(tube_w)
    elif kind == "diagonal":
        A = sp.diags(rng.uniform(1, 2, n))
    elif kind == "dense":
        B = rng.standard_normal((n, n))
        A = sp.csc_matrix(B @ B.T + n * np.eye(n))
    elif kind == "two_chains":
        chain = sp.diags([-np.ones(n - 1), 2.5 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1])
        A = sp.block_diag([chain, chain])
    else:
        A = sp.csc_matrix(np.array([[3.0]]))
    solve = cholesky_ldl(A).solve
    for b in (rng.standard_normal(A.shape[0]), rng.standard_normal((A.shape[0], 3))):
        x = solve(b)
        assert x.shape == b.shape
        assert _backward(A, x, b) < 1e-14


def test_two_threads_give_the_serial_factor_bit_for_bit():
    """With a pool the two etree halves are factored on two threads: the same arithmetic,
    so the same packed factor to the last bit (a matrix large enough to split)."""
    fe = assemble(tube_hex27(n_theta=12, n_r=2, n_x=26), ALUMINIUM)
    A = sp.csc_matrix(fe.M + (0.55 * 2e-6) ** 2 * fe.K)
    assert A.shape[0] >= SPLIT_MIN_N
    sym = SymbolicFactor(A)
    assert sym.halves is not None
    serial = numeric_factor(sym, A)
    with ThreadPoolExecutor(1) as pool:
        threaded = numeric_factor(sym, A, pool)
        x = cholesky_ldl(A, pool).solve(np.ones(A.shape[0]))
    for one, two in zip(serial, threaded, strict=True):
        np.testing.assert_array_equal(one, two)
    assert _backward(A, x, np.ones(A.shape[0])) < 1e-14


def test_symbolic_reused_for_new_values(tube_w):
    """One analysis serves every matrix of its pattern (the integrator's W for each step
    size); a matrix of another pattern is refused by numeric_factor, and cholesky_ldl makes
    its analysis anew with the same order."""
    sym = SymbolicFactor(tube_w)
    B = tube_w * 3.0 + sp.diags(np.ones(tube_w.shape[0]))  # same pattern (diagonal stored)
    b = np.ones(tube_w.shape[0])
    assert _backward(B, cholesky_ldl(B, symbolic=sym).solve(b), b) < 1e-14
    n = tube_w.shape[0]
    eps = 1e-3 * tube_w.diagonal().min()  # a new coupling, small enough to stay SPD
    C = sp.csc_matrix(tube_w + eps * (sp.eye(n, k=n - 1) + sp.eye(n, k=1 - n)))
    with pytest.raises(SolverError, match="another sparsity pattern"):
        numeric_factor(sym, C)
    assert _backward(C, cholesky_ldl(C, symbolic=sym).solve(b), b) < 1e-14


@pytest.mark.parametrize("bad", ["indefinite", "singular", "nan"])
def test_not_positive_definite_is_a_solver_error(tube_w, bad):
    """A pivot that is not positive (indefinite or singular matrix) or a NaN entry stops the
    factor with a clear SolverError naming the cause."""
    n = tube_w.shape[0]
    if bad == "indefinite":
        A = sp.csc_matrix(tube_w - 2.0 * tube_w.diagonal().max() * sp.eye(n))
        match = "not positive"
    elif bad == "singular":
        A = sp.csc_matrix(np.array([[1.0, 1.0], [1.0, 1.0]]))
        match = "not positive"
    else:
        A = tube_w.copy()
        A.data[7] = np.nan
        match = "non-finite"
    with pytest.raises(SolverError, match=match):
        cholesky_ldl(A)


def test_cholesky_backend_setting(monkeypatch):
    """FLEXMVM_CHOLESKY picks spd_solver's Cholesky: unset is the supernodal default, an unknown
    value is a one-line SolverError naming the choices, and "cholmod" without its package is a
    SolverError naming the extra to install (no silent fallback to another factorization)."""
    monkeypatch.delenv(spd.ENV_CHOLESKY, raising=False)
    assert spd.cholesky_backend() is spd.CholeskyBackend.SUPERNODAL
    monkeypatch.setenv(spd.ENV_CHOLESKY, "pardiso")
    with pytest.raises(
        SolverError,
        match=r"FLEXMVM_CHOLESKY must be one of supernodal, "
        r"cholmod, got 'pardiso'",
    ):
        spd.spd_solver(sp.identity(3, format="csc"))
    from flexmvm.fe.solvers import cholmod

    monkeypatch.setattr(cholmod, "available", lambda: False)
    monkeypatch.setenv(spd.ENV_CHOLESKY, "cholmod")
    with pytest.raises(
        SolverError,
        match=r"needs the cholespy package \(pip install "
        r"flexmvm\[cholmod\]\)",
    ):
        spd.spd_solver(sp.identity(3, format="csc"))


def test_cholmod_backend_against_the_default(tube_w, monkeypatch):
    """CHOLMOD behind the same seam (spd_solver, FLEXMVM_CHOLESKY=cholmod), where cholespy is
    installed: on the tube's W (4,680 DOFs, above CHOLESKY_MIN_N) both backends solve one and
    eight right-hand sides to a backward error of 1e-14, and agree with each other to 1e-11 of
    the solution's size (two orderings, two rounding paths: their difference is bounded by
    cond(W) ~1e3 times their backward errors ~1e-16, so ~1e-13 is expected; 1e-11 leaves
    room without letting a wrong factor pass). An unsymmetric matrix, of which CHOLMOD reads
    one triangle, fails its backward-error check and goes to SuperLU's LU, as the default's
    does. Runtime ~1 s."""
    from flexmvm.fe.solvers import cholmod

    if not cholmod.available():
        pytest.skip("cholespy (the CHOLMOD backend, flexmvm[cholmod]) is not installed")
    b = np.random.default_rng(5).standard_normal((tube_w.shape[0], 8))
    monkeypatch.setenv(spd.ENV_CHOLESKY, "cholmod")
    chol = spd.spd_solver(tube_w)
    assert isinstance(chol.__self__, cholmod.CholmodFactor)
    default = spd.spd_solver(tube_w, backend=spd.CholeskyBackend.SUPERNODAL)
    assert isinstance(default.__self__, SupernodalLDL)
    for rhs in (b[:, 0], b):
        x_chol, x_default = chol(rhs), default(rhs)
        assert x_chol.shape == rhs.shape
        assert _backward(tube_w, x_chol, rhs) < 1e-14
        assert _backward(tube_w, x_default, rhs) < 1e-14
        assert np.abs(x_chol - x_default).max() <= 1e-11 * np.abs(x_default).max()
    U = sp.csc_matrix(tube_w + 1e-3 * sp.triu(tube_w, 1))
    refused = spd.spd_solver(U)
    assert not isinstance(refused.__self__, cholmod.CholmodFactor)
    assert _backward(U, refused(b[:, 0]), b[:, 0]) < 1e-14
