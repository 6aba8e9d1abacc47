"""Mixed linear complementarity problem of the constraint impulses.

    D_ee l_e + D_eu l_u + c_e = 0                     (bilateral rows, l_e free)
    w = D_ue l_e + D_uu l_u + c_u >= 0, l_u >= 0, w . l_u = 0   (unilateral rows)

D = Phi W^-1 Phi^T is symmetric positive (semi-)definite. The equality rows are eliminated by
a Schur complement; the remaining LCP is the convex QP min 1/2 l^T D' l + c'^T l, l >= 0,
solved exactly (finite active-set termination) as NNLS on the Cholesky factor
(Lawson & Hanson 1974): D' = L L^T, min |L^T l + L^-1 c'|.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
from scipy.optimize import nnls

from flexmvm.errors import SolverError

_REG = 1e-12


def _regularised_cho(D: np.ndarray, what: str):
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
        return -sla.cho_solve(_regularised_cho(D, "joint"), c)
    e, u = slice(0, n_eq), slice(n_eq, m)
    if n_eq:
        cho_e = _regularised_cho(D[e, e], "joint")
        De_inv_Deu = sla.cho_solve(cho_e, D[e, u])
        De_inv_ce = sla.cho_solve(cho_e, c[e])
        Dp = D[u, u] - D[u, e] @ De_inv_Deu
        cp = c[u] - D[u, e] @ De_inv_ce
    else:
        Dp, cp = D, c
    lu = _solve_lcp(0.5 * (Dp + Dp.T), cp)
    out = np.zeros(m)
    out[u] = lu
    if n_eq:
        out[e] = -(De_inv_ce + De_inv_Deu @ lu)
    return out


def _solve_lcp(D: np.ndarray, c: np.ndarray) -> np.ndarray:
    if np.all(c >= 0):
        return np.zeros_like(c)
    L, _ = _regularised_cho(D, "contact")
    L = np.tril(L)
    rhs = -sla.solve_triangular(L, c, lower=True)
    lam, _ = nnls(L.T, rhs, maxiter=50 * len(c) + 100)
    return lam
