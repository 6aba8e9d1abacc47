"""Mixed linear complementarity problem of the constraint impulses.

    D_ee l_e + D_eu l_u + c_e = 0                     (bilateral rows, l_e free)
    w = D_ue l_e + D_uu l_u + c_u >= 0, l_u >= 0, w . l_u = 0   (unilateral rows)

D = Phi W^-1 Phi^T is symmetric positive (semi-)definite. The equality rows are eliminated by
a Schur complement; the remaining LCP is the convex QP min 1/2 l^T D' l + c'^T l, l >= 0,
solved exactly (finite active-set termination) by Lawson and Hanson's (1974) active-set
method: on D' directly in a compiled kernel (`active_set_qp`, a Cholesky solve of the passive
block per pass), and, should that fail (a singular passive block: redundant rows), as NNLS on
the Cholesky factor of the regularised D' (D' = L L^T, min |L^T l + L^-1 c'|, scipy).

Every solve of a time step is checked (:func:`solve_checked`): the natural residual
r_e = w_e (equality rows), r_u = min(d_u l_u, w_u) (unilateral rows; d = diag D turns an
impulse into a velocity so both arguments are in m/s), relative to the problem's velocity
scale max(|c|, |D l|). It is zero exactly at a solution; LCP_RTOL bounds it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
import scipy.linalg as sla

from flexmvm.errors import SolverError
from flexmvm.integrate.moreau_jean.dense_solve import cho_factor, cho_solve

_REG = 1e-12
# The regularisation above perturbs w by ~_REG D l, NNLS stops at its own round-off: both
# ~1e-12 of the velocity scale; measured on the seed case <= ~1e-10 (docs/validation.md).
LCP_RTOL = 1e-8


def regularised_cho(D: np.ndarray, what: str):
    """Cholesky factor of D + _REG mean(diag D) I (scipy cho_factor, lower); SolverError
    naming `what` if it is not positive definite (also used by integrate.moreau_jean.coulomb)."""
    m = len(D)
    scale = max(float(np.trace(D)) / m, 1e-300)
    try:
        return cho_factor(D + _REG * scale * np.eye(m), lower=True)
    except np.linalg.LinAlgError:
        raise SolverError(
            f"{what} constraint matrix is not positive definite (redundant or "
            "inconsistent constraints)"
        ) from None


def solve_mixed_lcp(D: np.ndarray, c: np.ndarray, n_eq: int) -> np.ndarray:
    """Impulses l (m,) for the mixed LCP above; the first n_eq rows are equalities."""
    m = len(c)
    if m == 0:
        return np.zeros(0)
    if not (np.isfinite(D).all() and np.isfinite(c).all()):
        what = "matrix" if not np.isfinite(D).all() else "right-hand side"
        raise SolverError(
            f"constraint LCP ({m} rows): non-finite number (NaN/inf) in its "
            f"{what}; the state diverged before this step"
        )
    D = 0.5 * (D + D.T)
    if n_eq == m:
        return _refine(D, c, n_eq, -cho_solve(regularised_cho(D, "joint"), c))
    if n_eq == 0:
        # an exact active-set solution leaves _refine nothing to remove (it is for the
        # regularised NNLS fallback and the eliminated equalities)
        lam, exact = _solve_lcp(D, c)
        return lam if exact else _refine(D, c, 0, lam)
    el = eliminate_equalities(D, c, n_eq)
    lu, _ = _solve_lcp(0.5 * (el.D + el.D.T), el.c)
    return _refine(D, c, n_eq, np.concatenate([el.equalities(lu), lu]))


@dataclass(frozen=True)
class Elimination:
    """The Schur complement of the first n_eq (equality) rows of w = D l + c: the unilateral
    rows' w is D' l_u + c' once the equalities hold, with l_e = equalities(l_u). cho: the
    factor of D_ee (None without equalities)."""

    D: np.ndarray
    c: np.ndarray
    cho: tuple[np.ndarray, bool] | None
    De_inv_Deu: np.ndarray
    De_inv_ce: np.ndarray

    def equalities(self, lu: np.ndarray) -> np.ndarray:
        if self.cho is None:
            return np.zeros(0)
        return -(self.De_inv_ce + self.De_inv_Deu @ lu)


def eliminate_equalities(D: np.ndarray, c: np.ndarray, n_eq: int) -> Elimination:
    """Elimination of the first n_eq rows of (D, c); n_eq = 0 leaves D and c as they are."""
    e, u = slice(0, n_eq), slice(n_eq, len(c))
    if not n_eq:
        return Elimination(D, c, None, np.zeros((0, len(c))), np.zeros(0))
    cho_e = regularised_cho(D[e, e], "joint")
    De_inv_Deu = cho_solve(cho_e, D[e, u])
    De_inv_ce = cho_solve(cho_e, c[e])
    return Elimination(
        D[u, u] - D[u, e] @ De_inv_Deu, c[u] - D[u, e] @ De_inv_ce, cho_e, De_inv_Deu, De_inv_ce
    )


def _refine(
    D: np.ndarray, c: np.ndarray, n_eq: int, lam: np.ndarray, sweeps: int = 2
) -> np.ndarray:
    """Iterative refinement on the rows that hold as equalities at the solution (the joints
    and the active contacts, l > 0): the regularisation _REG * mean(diag D) shifts l by
    ~_REG cond(D) of itself, which for a joint with a stiff and a soft direction (cond ~1e4
    and more) is far above round-off; two sweeps with the true D remove it. An active
    impulse that a sweep would make negative keeps its unrefined value."""
    S = np.concatenate([np.arange(n_eq), n_eq + np.flatnonzero(lam[n_eq:] > 0.0)])
    if not len(S):
        return lam
    cho = regularised_cho(D[np.ix_(S, S)], "active")
    out = lam.copy()
    for _ in range(sweeps):
        trial = out.copy()
        trial[S] -= cho_solve(cho, D[S] @ out + c[S])
        if np.any(trial[n_eq:] < 0.0):
            break
        out = trial
    return out


@numba.njit(cache=True, nogil=True)
def _passive_solve(D, c, idx, k, A, z):  # pragma: no cover - compiled
    """z[:k] = -D_PP^-1 c_P for P = idx[:k] by Cholesky in A[:k, :k]; False if D_PP is not
    positive definite (a pivot <= 1e-14 of its diagonal entry)."""
    for a in range(k):
        for b in range(a + 1):
            acc = D[idx[a], idx[b]]
            for t in range(b):
                acc -= A[a, t] * A[b, t]
            if a == b:
                if acc <= 1e-14 * D[idx[a], idx[a]]:
                    return False
                A[a, a] = np.sqrt(acc)
            else:
                A[a, b] = acc / A[b, b]
    for a in range(k):
        acc = -c[idx[a]]
        for t in range(a):
            acc -= A[a, t] * z[t]
        z[a] = acc / A[a, a]
    for a in range(k - 1, -1, -1):
        acc = z[a]
        for t in range(a + 1, k):
            acc -= A[t, a] * z[t]
        z[a] = acc / A[a, a]
    return True


@numba.njit(cache=True, nogil=True)
def _gather(passive, idx):  # pragma: no cover - compiled
    """idx[:k] = the passive rows in order; returns k."""
    k = 0
    for i in range(passive.shape[0]):
        if passive[i]:
            idx[k] = i
            k += 1
    return k


@numba.njit(cache=True, nogil=True)
def _velocity(D, c, lam, w):  # pragma: no cover - compiled
    """w = D lam + c."""
    m = c.shape[0]
    for i in range(m):
        acc = c[i]
        for t in range(m):
            acc += D[i, t] * lam[t]
        w[i] = acc


@numba.njit(cache=True, nogil=True)
def _all_positive(z, k):  # pragma: no cover - compiled
    for a in range(k):
        if z[a] <= 0.0:
            return False
    return True


@numba.njit(cache=True, nogil=True)
def _refine_passive(D, c, lam, passive, idx, A, z):  # pragma: no cover - compiled
    """One sweep of iterative refinement of the passive block's solution (D_PP l_P = -c_P with
    the residual in double precision), kept only if l_P stays positive: the round-off of an
    ill-conditioned block (measured up to 6e-9 of the velocity scale at cond 1e8 without it)."""
    k = _gather(passive, idx)
    if k == 0:
        return
    r = np.empty(c.shape[0])
    _velocity(D, c, lam, r)  # only its passive rows are read
    if not _passive_solve(D, r, idx, k, A, z):
        return
    for a in range(k):
        if lam[idx[a]] + z[a] <= 0.0:
            return
    for a in range(k):
        lam[idx[a]] += z[a]


@numba.njit(cache=True, nogil=True)
def active_set_qp(D, c, tol, max_passes):  # pragma: no cover - compiled
    """(l, ok): min 1/2 l^T D l + c^T l subject to l >= 0 for D (m, m) symmetric positive
    definite, by Lawson and Hanson's active-set method (1974, ch. 23, the NNLS algorithm
    written on the normal equations D = L L^T without forming L): a row enters the passive
    set when its w = D l + c is the most negative below -tol, the passive block
    D_PP z = -c_P is solved by Cholesky, and a z with non-positive entries is cut back along
    l -> z to the first one that reaches 0. ok is False when a passive block is not positive
    definite (numerically: pivot <= 1e-14 of its diagonal) or max_passes is exceeded."""
    m = c.shape[0]
    lam = np.zeros(m)
    blocked = np.zeros(m, np.bool_)
    w = c.copy()
    idx = np.empty(m, np.int64)
    A = np.empty((m, m))
    z = np.empty(m)
    # start: the rows with c < 0 all passive, if that block's solution is positive (impacts
    # and persistent contacts: usually the answer, one Cholesky instead of one per row)
    passive = c < 0.0
    k = _gather(passive, idx)
    if k > 0 and _passive_solve(D, c, idx, k, A, z) and _all_positive(z, k):
        for a in range(k):
            lam[idx[a]] = z[a]
        _velocity(D, c, lam, w)
    else:
        passive[:] = False
    for _ in range(max_passes):
        j = -1
        wmin = -tol
        for i in range(m):
            if not passive[i] and not blocked[i] and w[i] < wmin:
                wmin = w[i]
                j = i
        if j < 0:
            _refine_passive(D, c, lam, passive, idx, A, z)
            return lam, True
        passive[j] = True
        first = True
        while True:
            k = _gather(passive, idx)
            if not _passive_solve(D, c, idx, k, A, z):
                return lam, False
            if first:
                first = False
                pos_j = 0
                for a in range(k):
                    if idx[a] == j:
                        pos_j = a
                if z[pos_j] <= 0.0:  # round-off: j cannot enter; try the next row
                    passive[j] = False
                    blocked[j] = True
                    break
            if _all_positive(z, k):
                lam[:] = 0.0
                for a in range(k):
                    lam[idx[a]] = z[a]
                blocked[:] = False
                break
            alpha = 1.0
            for a in range(k):
                if z[a] <= 0.0:
                    li = lam[idx[a]]
                    alpha = min(alpha, li / (li - z[a]))
            for a in range(k):
                i = idx[a]
                lam[i] += alpha * (z[a] - lam[i])
                if lam[i] <= 0.0 or (z[a] <= 0.0 and lam[i] <= 1e-15 * abs(z[a])):
                    lam[i] = 0.0
                    passive[i] = False
        _velocity(D, c, lam, w)
    return lam, False


def _active_set(D: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, bool]:
    m = len(c)
    return active_set_qp(
        np.ascontiguousarray(D, dtype=float),
        np.array(c, dtype=float),
        1e-13 * float(np.abs(c).max()),
        3 * m + 30,
    )


def _nnls(D: np.ndarray, c: np.ndarray) -> np.ndarray:
    """NNLS on the Cholesky factor of the regularised D (the fallback of active_set_qp)."""
    from scipy.optimize import nnls  # here: the fallback is rare, scipy.optimize slow to import

    L, _ = regularised_cho(D, "contact")
    L = np.tril(L)
    rhs = -sla.solve_triangular(L, c, lower=True)
    lam, _ = nnls(L.T, rhs, maxiter=50 * len(c) + 100)
    return lam


def _solve_lcp(D: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, bool]:
    """(l, exact) of the LCP for D symmetric positive (semi-)definite: the compiled
    active-set method, exact on the unregularised active block (or l = 0 when c >= 0), or,
    where it fails, NNLS on the regularised Cholesky factor (exact False: _refine it)."""
    if np.all(c >= 0):
        return np.zeros_like(c), True
    lam, ok = _active_set(D, c)
    return (lam, True) if ok else (_nnls(D, c), False)


def complementarity_residual(D: np.ndarray, c: np.ndarray, n_eq: int, lam: np.ndarray) -> float:
    """Natural residual of l for the mixed LCP (D, c, n_eq), relative to the velocity scale
    max(|c|, |D l|) (module docstring): 0 at a solution, ~1 for a wrong one."""
    m = len(c)
    if m == 0:
        return 0.0
    w = D @ lam + c
    scale = max(float(np.abs(c).max()), float(np.abs(w - c).max()), 1e-300)
    r = np.abs(w[:n_eq]).max() if n_eq else 0.0
    if n_eq < m:
        d = np.maximum(np.diag(D)[n_eq:], 0.0)
        r = max(
            r,
            float(np.abs(np.minimum(d * lam[n_eq:], w[n_eq:])).max()),
            float(np.maximum(-lam[n_eq:], 0.0).max() * d.max()),
        )
    return float(r) / scale


def solve_checked(
    D: np.ndarray, c: np.ndarray, n_eq: int, rtol: float = LCP_RTOL, where: str = ""
) -> tuple[np.ndarray, float]:
    """solve_mixed_lcp, then its complementarity residual; raises SolverError (naming
    `where`, if given) when the residual exceeds rtol (and, from solve_mixed_lcp, when D or c
    is not finite). The time loop adds the step's time to the message."""
    lam = solve_mixed_lcp(D, c, n_eq)
    res = complementarity_residual(0.5 * (D + D.T), c, n_eq, lam)
    if not res <= rtol:
        raise SolverError(
            f"constraint impulses{where}: complementarity residual {res:.2e} "
            f"exceeds {rtol:.0e} ({len(c)} rows, {n_eq} equalities)"
        )
    return lam, res
