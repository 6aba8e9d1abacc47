"""Coulomb friction at impulse level: the contact problem of one Moreau-Jean iteration with
exact (circular) friction cones, solved on the Delassus matrix D = Phi W^-1 Phi^T.

Rows of the problem, w = D l + c (c: the free velocities minus the lower bounds):

    equalities (joints, bonds; the first n_eq rows):   w_e = 0, l_e free
    a normal row N without friction:                    0 <= w_N  _|_  l_N >= 0
    a contact with friction mu (rows N, T = (T1, T2)):  0 <= w_N  _|_  l_N >= 0,
        |l_T| <= mu l_N;  w_T = 0 if |l_T| < mu l_N (stick), else w_T = -a l_T, a >= 0 (slip:
        the impulse opposes the sliding velocity of the contact point at the end of the step)

The tangent rows of a contact act on the same nodal Jacobian as its normal row (two
orthonormal tangents of the master facet normal), so w_T is the tangential relative velocity
u_T(v+) of the slave node against its master point.

Solver: the equalities are eliminated by the Schur complement of lcp.py; on the remaining
D' the contacts are swept by projected block Gauss-Seidel (Jean & Moreau 1992, Jourdan,
Alart & Jean 1998), each block solved exactly given the others: the normal row by its
projection, then the tangential pair as the 2 x 2 problem min 1/2 l^T D_TT l + b^T l over the
disc |l_T| <= mu l_N: stick if the unconstrained minimiser is inside, else l_T = -(D_TT + a
I)^-1 b on the rim, a >= 0 the root of the secular equation |l_T(a)| = mu l_N (Newton on
1/|l_T| - 1/r, monotone from a = 0; More & Sorensen 1983). On the rim, w_T = D_TT l_T + b =
-a l_T: the local solution is Coulomb's law itself, not a projection in the D_TT metric, so
a fixed point of the sweeps is a solution of the Coulomb problem.

Checked like lcp.solve_checked: the natural residual of Alart & Curnier (1991), in velocity
units (d = diag D turns an impulse into a velocity, as in lcp.py)

    r_e = w_e,  r_N = min(d_N l_N, w_N),  r_T = d_T (l_T - P_{disc(mu l_N+)}(l_T - w_T / d_T))

(d_T: mean of the contact's two tangent diagonals), relative to the velocity scale max(|c|,
|D l|). It is zero exactly at a solution (r_T = 0 <=> -w_T is in the normal cone of the disc
at l_T: Coulomb's law above). The sweeps stop once it is below COULOMB_RTOL; SolverError if
MAX_SWEEPS did not get there. With no friction the step never comes here: lcp.solve_checked
(exact NNLS) is used, unchanged.
"""

from __future__ import annotations

import numba
import numpy as np

from flexmvm.constraints.contact import ContactRows
from flexmvm.errors import SolverError
from flexmvm.integrate.moreau_jean.dense_solve import cho_solve
from flexmvm.integrate.moreau_jean.lcp import eliminate_equalities, solve_checked

# the sweeps stop at this natural residual (relative to the velocity scale): the frictionless
# LCP's bound (lcp.LCP_RTOL), so a frictional step is solved to the same relative accuracy
COULOMB_RTOL = 1e-8
MAX_SWEEPS = 200_000
_CHECK_EVERY = 8  # sweeps between residual evaluations
SLIP_RTOL = 1e-6  # rim and speed thresholds of stick_slip (reporting only)


@numba.njit(cache=True)
def _disc_solve(daa, dab, dbb, ba, bb, r):  # pragma: no cover - compiled
    """argmin 1/2 l^T D_TT l + b^T l over |l| <= r (D_TT = [[daa, dab], [dab, dbb]] SPD)."""
    if r <= 0.0:
        return 0.0, 0.0
    det = daa * dbb - dab * dab
    if det > 0.0:
        xa = -(dbb * ba - dab * bb) / det
        xb = -(daa * bb - dab * ba) / det
        if xa * xa + xb * xb <= r * r:
            return xa, xb
    # eigen-decomposition of the 2 x 2 block: D_TT = Q diag(e1, e2) Q^T
    tr = 0.5 * (daa + dbb)
    dd = 0.5 * (daa - dbb)
    s = np.sqrt(dd * dd + dab * dab)
    e1, e2 = tr + s, tr - s
    if s > 0.0:
        # eigenvector of e1: (dab, e1 - daa) or (e1 - dbb, dab), whichever is larger
        ua, ub = e1 - dbb, dab
        nu = np.sqrt(ua * ua + ub * ub)
        ua, ub = ua / nu, ub / nu
    else:
        ua, ub = 1.0, 0.0
    # b in the eigenbasis: q1 = (ua, ub), q2 = (-ub, ua)
    g1 = ua * ba + ub * bb
    g2 = -ub * ba + ua * bb
    floor = 1e-300 + 1e-14 * max(e1, 0.0)
    e2 = max(e2, floor)
    e1 = max(e1, floor)
    a = 0.0
    for _ in range(100):
        x1 = -g1 / (e1 + a)
        x2 = -g2 / (e2 + a)
        nx = np.sqrt(x1 * x1 + x2 * x2)
        if nx == 0.0:
            break
        if abs(nx - r) <= 1e-15 * r:
            break
        dn = (x1 * x1 / (e1 + a) + x2 * x2 / (e2 + a)) / nx  # -d|x|/da
        step = (nx - r) / dn * (nx / r)  # Newton on 1/|x| - 1/r
        a = max(a + step, 0.0)
        if step <= 1e-16 * max(a, e1):
            break
    x1 = -g1 / (e1 + a)
    x2 = -g2 / (e2 + a)
    nx = np.sqrt(x1 * x1 + x2 * x2)
    if nx > 0.0:
        x1, x2 = x1 * r / nx, x2 * r / nx  # onto the rim exactly (a fraction 1e-15 off)
    return ua * x1 - ub * x2, ub * x1 + ua * x2


@numba.njit(cache=True)
def _residual(D, c, lam, w, normal, t1, t2, mu):  # pragma: no cover - compiled
    """Natural residual (module docstring), absolute [m/s], and the velocity scale."""
    scale = 1e-300
    for j in range(c.shape[0]):
        scale = max(scale, abs(c[j]), abs(w[j] - c[j]))
    r = 0.0
    for i in range(normal.shape[0]):
        n = normal[i]
        dn = max(D[n, n], 0.0)
        r = max(r, abs(min(dn * lam[n], w[n])), max(-lam[n], 0.0) * dn)
        a = t1[i]
        if a >= 0:
            b = t2[i]
            dt = max(0.5 * (D[a, a] + D[b, b]), 1e-300)
            rad = mu[i] * max(lam[n], 0.0)
            ya = lam[a] - w[a] / dt
            yb = lam[b] - w[b] / dt
            ny = np.sqrt(ya * ya + yb * yb)
            if ny > rad:
                ya, yb = ya * rad / ny, yb * rad / ny
            ra, rb = dt * (lam[a] - ya), dt * (lam[b] - yb)
            r = max(r, np.sqrt(ra * ra + rb * rb))
    return r, scale


@numba.njit(cache=True)
def _sweeps(D, c, lam, normal, t1, t2, mu, rtol, max_sweeps, check_every):  # pragma: no cover
    """Projected block Gauss-Seidel from lam (updated in place). Returns (sweeps, relative
    residual at exit)."""
    m = c.shape[0]
    w = D @ lam + c
    res, scale = _residual(D, c, lam, w, normal, t1, t2, mu)
    if res <= rtol * scale:
        return 0, res / scale
    for sweep in range(1, max_sweeps + 1):
        for i in range(normal.shape[0]):
            n = normal[i]
            dnn = D[n, n]
            if dnn > 0.0:
                new = max(0.0, lam[n] - w[n] / dnn)
                d = new - lam[n]
                if d != 0.0:
                    lam[n] = new
                    for j in range(m):
                        w[j] += D[n, j] * d
            a = t1[i]
            if a < 0:
                continue
            b = t2[i]
            daa, dab, dbb = D[a, a], D[a, b], D[b, b]
            ba = w[a] - daa * lam[a] - dab * lam[b]
            bb = w[b] - dab * lam[a] - dbb * lam[b]
            xa, xb = _disc_solve(daa, dab, dbb, ba, bb, mu[i] * lam[n])
            da, db = xa - lam[a], xb - lam[b]
            if da != 0.0 or db != 0.0:
                lam[a], lam[b] = xa, xb
                for j in range(m):
                    w[j] += D[a, j] * da + D[b, j] * db
        if sweep % check_every == 0 or sweep == max_sweeps:
            w = D @ lam + c  # fresh: no drift of the incremental updates
            res, scale = _residual(D, c, lam, w, normal, t1, t2, mu)
            if res <= rtol * scale:
                return sweep, res / scale
    return max_sweeps, res / scale


def _blocks(m: int, n_eq: int, tangent: np.ndarray, mu: np.ndarray, fnormal: np.ndarray):
    """(normal (k,), t1 (k,), t2 (k,), mu (k,)) over the unilateral rows n_eq..m-1, indices
    relative to them: every row that is not a tangent row is a normal row; t1 = t2 = -1 for
    the ones without friction."""
    is_t = np.zeros(m - n_eq, dtype=bool)
    is_t[tangent.ravel() - n_eq] = True
    normal = np.flatnonzero(~is_t)
    pos = np.full(m - n_eq, -1, dtype=np.int64)
    pos[normal] = np.arange(len(normal))
    t1 = np.full(len(normal), -1, dtype=np.int64)
    t2 = np.full(len(normal), -1, dtype=np.int64)
    mus = np.zeros(len(normal))
    k = pos[fnormal - n_eq]
    if np.any(k < 0):
        raise SolverError("friction rows: a contact's normal row is also a tangent row")
    t1[k], t2[k], mus[k] = tangent[:, 0] - n_eq, tangent[:, 1] - n_eq, mu
    return normal.astype(np.int64), t1, t2, mus


def solve_coulomb(
    D: np.ndarray,
    c: np.ndarray,
    n_eq: int,
    normal: np.ndarray,
    tangent: np.ndarray,
    mu: np.ndarray,
    warm: np.ndarray | None = None,
    rtol: float = COULOMB_RTOL,
) -> tuple[np.ndarray, int]:
    """Impulses l (m,) of the problem above and the number of sweeps. normal (k,) and
    tangent (k, 2): row indices (in D) of the k contacts with friction coefficients mu (k,);
    every other row from n_eq on is a frictionless normal row. warm: a starting guess (m,)."""
    m = len(c)
    if not (np.isfinite(D).all() and np.isfinite(c).all()):
        what = "matrix" if not np.isfinite(D).all() else "right-hand side"
        raise SolverError(
            f"constraint problem with friction ({m} rows): non-finite number "
            f"(NaN/inf) in its {what}; the state diverged before this step"
        )
    D = 0.5 * (D + D.T)
    nrm, t1, t2, mus = _blocks(
        m, n_eq, np.asarray(tangent, np.int64), np.asarray(mu, float), np.asarray(normal, np.int64)
    )
    e, u = slice(0, n_eq), slice(n_eq, m)
    # the equality rows scaled to a unit diagonal before their elimination (l_e = s_e l'_e):
    # the Schur complement is the same, but the factor's regularisation (lcp.regularised_cho,
    # _REG times the mean diagonal) is then ~_REG of every row's own scale; unscaled, a ground
    # joint's rotational rows (~1e6) set the mean and shifted its translational rows (~1e2)
    # by ~1e-8, which left a normal row at ~1e-8 of the velocity scale, above COULOMB_RTOL
    # (docs/notes/2026-11-29-rolling-sphere.md)
    s = np.ones(m)
    s[e] = 1.0 / np.sqrt(np.maximum(np.diag(D)[e], 1e-300))
    el = eliminate_equalities(D * np.outer(s, s), c * s, n_eq) if n_eq else None
    Dp, cp = (0.5 * (el.D + el.D.T), el.c) if el is not None else (D, c)
    lu = np.zeros(m - n_eq)
    if warm is not None and len(warm) == m and np.isfinite(warm).all():
        lu = np.array(warm[n_eq:], dtype=float)
        lu[nrm] = np.maximum(lu[nrm], 0.0)
    sweeps, _ = _sweeps(
        np.ascontiguousarray(Dp),
        np.ascontiguousarray(cp),
        lu,
        nrm,
        t1,
        t2,
        mus,
        rtol,
        MAX_SWEEPS,
        _CHECK_EVERY,
    )
    out = np.zeros(m)
    out[u] = lu
    if el is not None:
        out[e] = s[e] * el.equalities(lu)
        cho = el.cho
        assert cho is not None  # n_eq > 0: D_ee was factored (lcp.eliminate_equalities)
        # two refinement sweeps of the equalities with the true D (see lcp._refine)
        for _ in range(2):
            out[e] -= s[e] * cho_solve(cho, s[e] * (D[e] @ out + c[e]))
    return out, sweeps


def coulomb_residual(
    D: np.ndarray,
    c: np.ndarray,
    n_eq: int,
    lam: np.ndarray,
    normal: np.ndarray,
    tangent: np.ndarray,
    mu: np.ndarray,
) -> float:
    """Natural residual of lam for the problem (module docstring), relative to the velocity
    scale max(|c|, |D l|): 0 at a solution."""
    m = len(c)
    if m == 0:
        return 0.0
    w = D @ lam + c
    nrm, t1, t2, mus = _blocks(
        m, n_eq, np.asarray(tangent, np.int64), np.asarray(mu, float), np.asarray(normal, np.int64)
    )
    u = slice(n_eq, m)
    r, scale = _residual(
        np.ascontiguousarray(D[u, u]),
        np.ascontiguousarray(c[u]),
        np.ascontiguousarray(lam[u]),
        np.ascontiguousarray(w[u]),
        nrm,
        t1,
        t2,
        mus,
    )
    scale = max(scale, float(np.abs(c).max()), float(np.abs(w - c).max()))
    if n_eq:
        r = max(r, float(np.abs(w[:n_eq]).max()))
    return float(r) / scale


def solve_coulomb_checked(
    D: np.ndarray,
    c: np.ndarray,
    n_eq: int,
    normal: np.ndarray,
    tangent: np.ndarray,
    mu: np.ndarray,
    warm: np.ndarray | None = None,
    rtol: float = COULOMB_RTOL,
    where: str = "",
) -> tuple[np.ndarray, float]:
    """solve_coulomb, then its natural residual on the full problem; SolverError (naming
    `where`) when it exceeds rtol."""
    Ds = 0.5 * (D + D.T)
    lam, sweeps = solve_coulomb(D, c, n_eq, normal, tangent, mu, warm, rtol)
    res = coulomb_residual(Ds, c, n_eq, lam, normal, tangent, mu)
    inner = rtol
    # the sweeps measure the residual of the Schur-complement problem, on its own velocity
    # scale: continue with a tighter bound while the full problem's is above rtol
    while not res <= rtol and n_eq and inner > 1e-4 * rtol and sweeps < MAX_SWEEPS:
        inner *= 0.1
        lam, more = solve_coulomb(D, c, n_eq, normal, tangent, mu, lam, inner)
        sweeps += more
        res = coulomb_residual(Ds, c, n_eq, lam, normal, tangent, mu)
    if not res <= rtol:
        raise SolverError(
            f"constraint impulses with friction{where}: Coulomb residual "
            f"{res:.2e} exceeds {rtol:.0e} after {sweeps} Gauss-Seidel sweeps "
            f"({len(c)} rows, {n_eq} equalities, {len(mu)} friction cones)"
        )
    return lam, res


def solve_contact_impulses(
    D: np.ndarray, c: np.ndarray, n_joint: int, crows: ContactRows, warm: np.ndarray | None = None
) -> tuple[np.ndarray, float]:
    """The impulses of one step's constraint problem (joint rows first, then crows) and their
    residual: lcp.solve_checked (exact NNLS) without friction, solve_friction with it."""
    if crows.friction is None:
        return solve_checked(D, c, n_joint + crows.n_eq)
    return solve_friction(D, c, n_joint, crows, warm)


def solve_friction(
    D: np.ndarray, c: np.ndarray, n_joint: int, crows: ContactRows, warm: np.ndarray | None = None
) -> tuple[np.ndarray, float]:
    """Constraint impulses of one iteration with rows [joints (n_joint) | contact rows
    crows, which carry friction cones]: solve_coulomb_checked, warm-started from `warm` (the
    last iterate's). Rows without friction cones go to lcp.solve_checked instead (the
    callers branch on crows.friction)."""
    fr = crows.friction
    if fr is None:
        raise SolverError("solve_friction: the contact rows carry no friction cones")
    normal, tangent = n_joint + fr.normal, n_joint + fr.tangent
    lam, res = solve_coulomb_checked(D, c, n_joint + crows.n_eq, normal, tangent, fr.mu, warm)
    crows.stick_slip = stick_slip(D, c, lam, normal, tangent, fr.mu)
    return lam, res


def stick_slip(
    D: np.ndarray,
    c: np.ndarray,
    lam: np.ndarray,
    normal: np.ndarray,
    tangent: np.ndarray,
    mu: np.ndarray,
) -> tuple[int, int]:
    """(sticking, sliding) cones carrying a compressive impulse at the solution lam: sliding
    when l_T is on the rim (|l_T| >= (1 - SLIP_RTOL) mu l_N) and the tangential velocity
    |w_T| exceeds SLIP_RTOL times the velocity scale max(|c|, |D l|) (that of the residual
    check, which bounds its error by COULOMB_RTOL of it)."""
    w = D @ lam + c
    scale = max(float(np.abs(c).max()), float(np.abs(w - c).max()), 1e-300)
    ln = lam[normal]
    on = ln > 0.0
    rim = np.linalg.norm(lam[tangent], axis=1) >= (1.0 - SLIP_RTOL) * mu * ln
    moving = np.linalg.norm(w[tangent], axis=1) > SLIP_RTOL * scale
    slip = on & rim & moving
    return int(on.sum() - slip.sum()), int(slip.sum())
