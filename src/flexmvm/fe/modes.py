"""Undamped eigenmodes K phi = omega^2 M phi by sparse shift-invert Lanczos (ARPACK eigsh).

Nothing full-size is ever densified: the shifted matrix K - sigma M is factored sparsely
(fe.solvers.spd_solver: the supernodal L D L^T of fe.solvers.cholesky, solved by
fe.solvers.ldl, when it is positive definite)
and handed to eigsh as ``OPinv``: the Lanczos iteration is mostly those solves, and
fe.solvers.ldl's (on two threads) take a fraction of the time of SuperLU's
(docs/notes/2026-11-27-comment-measurements.md).
Modes are M-normalised (phi^T M phi = 1).
Eigenvalues are checked, never abs()-ed: a negative omega^2 with
|omega^2| <= NEG_RTOL * scale (scale = max(|sigma|, largest computed omega^2)) is round-off of
a zero-energy mode and clipped to 0; anything more negative raises SolverError.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from flexmvm.errors import InputError, SolverError
from flexmvm.fe.assembly import FEModel

# The sparse solvers live in fe.solvers; their names stay importable from here for the
# modules that took them from fe.modes before (reduction, scenarios, cli).
from flexmvm.fe.solvers.spd import CHOLESKY_MIN_N, solver_pool, spd_solver
from flexmvm.fe.solvers.superlu import SPD_LU, Solve, factor, superlu_spd

#: Relative size of a negative omega^2 accepted as round-off of a zero eigenvalue.
NEG_RTOL = 1e-6

#: Default free-free shift, relative to the mean of diag(K) / diag(M) (a bound on the
#: highest squared mesh frequency): small enough that the lowest elastic modes are near it.
FREE_SHIFT_REL = 1e-9

#: Seed of the Lanczos start vector: ARPACK's own start is random, so two builds of one basis
#: differed (signs, vectors within a degenerate pair); a fixed random start makes them
#: repeatable (and a cached basis equal to a fresh one). Random, not ones: a symmetric start
#: is orthogonal to the antisymmetric (bending) modes of a symmetric mesh.
V0_SEED = 20140101


#: Every mode of a problem (n_modes = its DOFs) comes from a dense solve up to this size
#: (memory 2 m^2 doubles: 400 MB at 5,000).
DENSE_MAX_DOF = 5000


def shift_invert_modes(
    M: sp.spmatrix,
    K: sp.spmatrix,
    n_modes: int,
    sigma: float,
    solve: Solve | None = None,
    tol: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Lowest ``n_modes`` eigenpairs of K phi = lambda M phi nearest ``sigma`` (shift-invert).

    M, K: (m, m) sparse symmetric, M positive definite, K positive semi-definite.
    solve: x = (K - sigma M)^{-1} b if already factored (e.g. CB reuses its K_ii factor).
    The Lanczos start vector is fixed (V0_SEED): the same input gives the same modes.
    Returns (lam (n_modes,) ascending [rad^2/s^2], phi (m, n_modes) M-normalised).
    n_modes = m (every mode: Lanczos cannot) takes LAPACK's dense generalized eigensolver,
    for m up to DENSE_MAX_DOF.
    Raises InputError if n_modes is not in 1..m (or m is too large for all of them),
    SolverError if ARPACK fails or an eigenvalue is negative beyond round-off.
    """
    m = M.shape[0]
    if not 1 <= n_modes <= m:
        raise InputError(f"number of modes must be in 1..{m} for {m} free DOFs, got {n_modes}")
    if n_modes == m:
        if m > DENSE_MAX_DOF:
            raise InputError(
                f"all {m} modes need a dense eigensolve, limited to "
                f"{DENSE_MAX_DOF} DOFs; ask for at most {m - 1} modes"
            )
        lam, phi = sla.eigh(
            sp.csr_matrix(K).toarray(), sp.csr_matrix(M).toarray()
        )  # phi^T M phi = I
        return _check_eigenvalues(lam, sigma), phi
    if solve is not None:
        return _arpack(M, K, n_modes, sigma, solve, tol)
    if sigma > 0.0:  # K - sigma M indefinite: SuperLU with pivoting
        return _arpack(M, K, n_modes, sigma, factor(sp.csc_matrix(K - sigma * M), spd=False), tol)
    with solver_pool() as pool:
        return _arpack(M, K, n_modes, sigma, spd_solver(sp.csc_matrix(K - sigma * M), pool), tol)


def _arpack(
    M, K, n_modes: int, sigma: float, solve: Solve, tol: float
) -> tuple[np.ndarray, np.ndarray]:
    """shift_invert_modes by ARPACK's implicitly restarted Lanczos (eigsh) with OPinv = solve."""
    m = M.shape[0]
    op_inv = spla.LinearOperator((m, m), matvec=solve, dtype=np.float64)
    v0 = np.random.default_rng(V0_SEED).standard_normal(m)
    try:
        lam, phi = spla.eigsh(
            sp.csr_matrix(K),
            k=n_modes,
            M=sp.csr_matrix(M),
            sigma=sigma,
            which="LM",
            OPinv=op_inv,
            tol=tol,
            v0=v0,
        )
    except (spla.ArpackNoConvergence, spla.ArpackError) as exc:
        raise SolverError(
            f"eigsh did not converge for {n_modes} modes (sigma={sigma:g}): {exc}"
        ) from None
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    lam = _check_eigenvalues(lam, sigma)
    norms = np.sqrt(np.einsum("ij,ij->j", phi, M @ phi))
    return lam, phi / norms


def _check_eigenvalues(lam: np.ndarray, sigma: float) -> np.ndarray:
    """Clip round-off negatives (|lam| <= NEG_RTOL * scale) to 0, else SolverError."""
    if not np.all(np.isfinite(lam)):
        raise SolverError("eigsh returned non-finite eigenvalues")
    scale = max(abs(sigma), float(np.max(np.abs(lam))))
    if lam.min() < -NEG_RTOL * scale:
        raise SolverError(
            f"negative eigenvalue omega^2 = {lam.min():.3e} (scale {scale:.3e}): stiffness not "
            "positive semi-definite or mass not positive definite"
        )
    return np.where(lam < 0.0, 0.0, lam)


def to_hz(lam: np.ndarray) -> np.ndarray:
    """Frequencies f = sqrt(lambda) / (2 pi) [Hz] of checked, non-negative eigenvalues."""
    return np.sqrt(lam) / (2.0 * np.pi)


def free_modes(
    fe: FEModel, n_modes: int, sigma: float | None = None, tol: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """First ``n_modes`` free-free modes of ``fe`` (the six rigid-body modes first).

    sigma: shift [rad^2/s^2], negative so K - sigma M is positive definite; default
    -FREE_SHIFT_REL * mean(diag K) / mean(diag M).
    Returns (freqs_hz (n_modes,), modes (3n, n_modes) M-normalised).
    Raises InputError for sigma >= 0 or a bad n_modes, SolverError on failure.
    """
    if sigma is None:
        sigma = -FREE_SHIFT_REL * float(fe.K.diagonal().mean() / fe.M.diagonal().mean())
    if not sigma < 0:
        raise InputError(f"free-free shift sigma must be < 0 (K is singular), got {sigma!r}")
    lam, phi = shift_invert_modes(fe.M, fe.K, n_modes, sigma, tol=tol)
    return to_hz(lam), phi


def constrained_modes(
    M: sp.spmatrix, K: sp.spmatrix, fixed_dofs: np.ndarray, n_modes: int, tol: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """First ``n_modes`` modes with ``fixed_dofs`` clamped (shift-invert about sigma = 0).

    M, K: (N, N) sparse; fixed_dofs: int DOF ids (must remove all rigid-body motion).
    Returns (freqs_hz (n_modes,), modes (N, n_modes), zero rows at fixed_dofs, M-normalised).
    Raises InputError for DOF ids outside 0..N-1, SolverError if K_ff is singular.
    """
    n = M.shape[0]
    fixed = np.unique(np.asarray(fixed_dofs, dtype=np.int64))
    if fixed.size and (fixed[0] < 0 or fixed[-1] >= n):
        raise InputError(f"fixed DOF ids must be in 0..{n - 1}, got {fixed.min()}..{fixed.max()}")
    free = np.setdiff1d(np.arange(n), fixed)
    m_ff = sp.csr_matrix(M)[free][:, free]
    k_ff = sp.csr_matrix(K)[free][:, free]
    lam, phi_f = shift_invert_modes(m_ff, k_ff, n_modes, 0.0, tol=tol)
    phi = np.zeros((n, n_modes))
    phi[free] = phi_f
    return to_hz(lam), phi


__all__ = [
    "CHOLESKY_MIN_N",
    "DENSE_MAX_DOF",
    "NEG_RTOL",
    "SPD_LU",
    "V0_SEED",
    "Solve",
    "constrained_modes",
    "factor",
    "free_modes",
    "shift_invert_modes",
    "solver_pool",
    "spd_solver",
    "superlu_spd",
    "to_hz",
]
