"""Mixed linear complementarity problem of the constraint impulses.

    D_ee l_e + D_eu l_u + c_e = 0                     (bilateral rows, l_e free)
    w = D_ue l_e + D_uu l_u + c_u >= 0, l_u >= 0, w . l_u = 0   (unilateral rows)

D = Phi W^-1 Phi^T is symmetric positive (semi-)definite. The equality rows are eliminated by
a Schur complement; the remaining LCP is the convex QP min 1/2 l^T D' l + c'^T l, l >= 0,
solved exactly (finite active-set termination) as NNLS on the Cholesky factor
(Lawson & Hanson 1974): D' = L L^T, min |L^T l + L^-1 c'|.

Every solve of a time step is checked (:func:`solve_checked`): the natural residual
r_e = w_e (equality rows), r_u = min(d_u l_u, w_u) (unilateral rows; d = diag D turns an
impulse into a velocity so both arguments are in m/s), relative to the problem's velocity
scale max(|c|, |D l|). It is zero exactly at a solution; LCP_RTOL bounds it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from scipy.optimize import nnls

from flexmvm.errors import SolverError

_REG = 1e-12
# The regularisation above perturbs w by ~_REG D l, NNLS stops at its own round-off: both
# ~1e-12 of the velocity scale; measured on the seed case <= ~1e-10 (docs/validation.md).
LCP_RTOL = 1e-8


def regularised_cho(D: np.ndarray, what: str):
    """Cholesky factor of D + _REG mean(diag D) I (scipy cho_factor, lower); SolverError
    naming `what` if it is not positive definite (also used by integrate.coulomb)."""
    m = len(D)
    scale = max(float(np.trace(D)) / m, 1e-300)
    try:
        return sla.cho_factor(D + _REG * scale * np.eye(m), lower=True)
    except np.linalg.LinAlgError:
        raise SolverError(f"{what} constraint matrix is not positive definite (redundant or "
                          "inconsistent constraints)") from None


def solve_mixed_lcp(D: np.ndarray, c: np.ndarray, n_eq: int) -> np.ndarray:
    """Impulses l (m,) for the mixed LCP above; the first n_eq rows are equalities."""
    m = len(c)
    if m == 0:
        return np.zeros(0)
    if not (np.isfinite(D).all() and np.isfinite(c).all()):
        what = "matrix" if not np.isfinite(D).all() else "right-hand side"
        raise SolverError(f"constraint LCP ({m} rows): non-finite number (NaN/inf) in its "
                          f"{what}; the state diverged before this step")
    D = 0.5 * (D + D.T)
    if n_eq == m:
        return _refine(D, c, n_eq, -sla.cho_solve(regularised_cho(D, "joint"), c))
    el = eliminate_equalities(D, c, n_eq)
    lu = _solve_lcp(0.5 * (el.D + el.D.T), el.c)
    return _refine(D, c, n_eq, np.concatenate([el.equalities(lu), lu]))


@dataclass(frozen=True)
class Elimination:
    """The Schur complement of the first n_eq (equality) rows of w = D l + c: the unilateral
    rows' w is D' l_u + c' once the equalities hold, with l_e = equalities(l_u). cho: the
    factor of D_ee (None without equalities)."""

    D: np.ndarray
    c: np.ndarray
    cho: tuple | None
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
    De_inv_Deu = sla.cho_solve(cho_e, D[e, u])
    De_inv_ce = sla.cho_solve(cho_e, c[e])
    return Elimination(D[u, u] - D[u, e] @ De_inv_Deu, c[u] - D[u, e] @ De_inv_ce, cho_e,
                       De_inv_Deu, De_inv_ce)


def _refine(D: np.ndarray, c: np.ndarray, n_eq: int, lam: np.ndarray,
            sweeps: int = 2) -> np.ndarray:
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
        trial[S] -= sla.cho_solve(cho, D[S] @ out + c[S])
        if np.any(trial[n_eq:] < 0.0):
            break
        out = trial
    return out


def _solve_lcp(D: np.ndarray, c: np.ndarray) -> np.ndarray:
    if np.all(c >= 0):
        return np.zeros_like(c)
    L, _ = regularised_cho(D, "contact")
    L = np.tril(L)
    rhs = -sla.solve_triangular(L, c, lower=True)
    lam, _ = nnls(L.T, rhs, maxiter=50 * len(c) + 100)
    return lam


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
        r = max(r, float(np.abs(np.minimum(d * lam[n_eq:], w[n_eq:])).max()),
                float(np.maximum(-lam[n_eq:], 0.0).max() * d.max()))
    return float(r) / scale


def solve_checked(D: np.ndarray, c: np.ndarray, n_eq: int, rtol: float = LCP_RTOL,
                  where: str = "") -> tuple[np.ndarray, float]:
    """solve_mixed_lcp, then its complementarity residual; raises SolverError (naming
    `where`, if given) when the residual exceeds rtol (and, from solve_mixed_lcp, when D or c
    is not finite). The time loop adds the step's time to the message."""
    lam = solve_mixed_lcp(D, c, n_eq)
    res = complementarity_residual(0.5 * (D + D.T), c, n_eq, lam)
    if not res <= rtol:
        raise SolverError(f"constraint impulses{where}: complementarity residual {res:.2e} "
                          f"exceeds {rtol:.0e} ({len(c)} rows, {n_eq} equalities)")
    return lam, res
