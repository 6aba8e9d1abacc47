"""The consistent tangent in the Newton iteration of a step whose plastic bodies yield
(docs/plasticity.md, "The dynamic step"; plan item 3, docs/notes/2026-11-27-plastic-region-plan.md).

While points of a plastic body yield, its iteration matrix is

    W_t = W_el + (theta h)^2 psi^T (K_t - K_el) psi

with K_t - K_el the consistent tangent's difference over the yielding cells
(StepHistory.tangent_difference: nonzero on their nodal DOFs r only) and psi the body's basis
(the identity on those DOFs: full FE, and the retained DOFs of an MVM body's allowed cells).
C = (theta h)^2 times the dense difference block on r, U = psi^T E_r (E_r: selector columns):

- full FE: W_el is a large sparse factor, the difference a small dense block: Woodbury
  (Golub and Van Loan 2013, sect. 2.1.4),
      W_t^-1 b = y - Z (I + C U^T Z)^-1 C U^T y,   y = W_el^-1 b,  Z = W_el^-1 U
  with Z the elastic factor's cached nodal columns (BodySolver.nodal_inverse: each DOF is
  back-substituted once per step size in a run, not per update). The selector form is used
  rather than a factor of the points' B matrices: its rank |r| is below the B form's (6 per
  yielding point, and there are more points than nodes), and C is the assembled block.
- a reduced (MVM) body: W is dense and small: W_t is formed and factored (Cholesky).

When (POLICY "lazy"): a step starts from the last step's W_t (the elastic W at another step
size). After the residual of an iterate past the start guess (the returns made at it), the
tangent is made again (dropped, back to the elastic W, if none yields) when the set of
yielding points moved from that of the W in use by more than SET_CHANGE of its size, or moved
at all and the last iterate contracted the residual by less than POOR_CONTRACTION; at most
MAX_UPDATES_PER_STEP times a step. The start guess's returns (v+ = v-) overshoot into the
contact at unloading and are never used. POLICY "every" (the first form): each step from the
elastic W, made again whenever the set changes, at every iterate. A W that changes
within a step takes new contact columns W^-1 Phi^T and a full free-velocity solve
(moreau_jean: the columns must be those of the W the free velocity is solved with, see
_refresh_when_slow). The residual is unchanged: the converged step solves the same equations.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from flexmvm.errors import SolverError
from flexmvm.integrate.moreau_jean.dense_solve import cho_solve, lu_solve

#: The form of a sparse (full-FE) body's W_t: "woodbury" on the elastic factor, or
#: "refactor" (W_t factored; on W's symbolic analysis only where the patterns agree)
SPARSE_FORM = "woodbury"


#: The update policy ("lazy", default; module doc) or "every" (made again whenever the
#: yielding points change, each step from the elastic W: the first form, measured against)
POLICY = "lazy"

#: lazy: W_t is made again when the yielding points differ from those of the W in use by more
#: than this fraction of their number (symmetric difference), ...
SET_CHANGE = 0.25

#: ... or when they differ at all and the last iterate contracted the residual poorly
#: (||R_k|| / ||R_k-1|| above this)
POOR_CONTRACTION = 0.5

#: lazy: at most this many updates of a body's W_t within one step
MAX_UPDATES_PER_STEP = 1


class PlasticTangent:
    """Installs and drops the tangent W_t of the plastic bodies of a run in their BodySolvers
    (module doc): of the bodies whose PlasticPart asks for it (scenario key
    ``model.plastic_tangent``, off by default: on the aluminium sphere-on-block run the lazy
    policy halves the Newton iterations, 1,836 -> 903, but costs 45 % more CPU, one W_t
    factorization and its contact columns almost every yielding step; docs/notes/
    2026-11-27-plastic-tangent.md), or of every plastic body (``enabled`` True) or none
    (False)."""

    def __init__(self, plastic, solvers, enabled: bool | None = None, policy: str | None = None):
        self.plastic, self.solvers = plastic, solvers
        if enabled is None:
            self.bodies = {b for b in plastic.history if plastic.parts[b].tangent}
        else:
            self.bodies = set(plastic.history) if enabled else set()
        self.enabled = bool(self.bodies)
        self.policy = POLICY if policy is None else policy
        self.n_updates = 0  # tangents installed or dropped
        self._points: dict[int, np.ndarray] = {}  # the yielding points of the W in use
        self._h: dict[int, float] = {}  # the step size of the W_t in use
        self._in_step: dict[int, int] = {}  # updates in this step

    def start_step(self, h: float) -> None:
        """A new step: "every" solves with the elastic W of every plastic body; "lazy" keeps
        the last step's W_t (at the same step size h; the elastic W at another)."""
        if not self.enabled:
            return
        self._in_step.clear()
        for b in self.bodies:
            if self.policy == "every" or self._h.get(b, h) != h:
                self.solvers[b].use_tangent(None, None)
                self._points.pop(b, None)
                self._h.pop(b, None)

    def update(self, h: float, th: float, it: int = 1, contraction: float = 0.0) -> bool:
        """After the residual of iterate it (the returns made at it), with ||R_it|| /
        ||R_it-1|| = contraction: the tangent of the plastic bodies whose yielding points call
        for it (policy) installed, the elastic W if none yields; True if a W changed."""
        if not self.enabled:
            return False
        changed = False
        for b in self.bodies:
            hist = self.plastic.history[b]
            points = hist.yielding_points()
            if not self._due(b, points, it, contraction):
                continue
            self._points[b], self._h[b] = points, h
            self._in_step[b] = self._in_step.get(b, 0) + 1
            diff = hist.tangent_difference() if points.size else None
            solve = None if diff is None else tangent_solve(self.solvers[b], h, (th * h) ** 2, diff)
            self.solvers[b].use_tangent(h, solve)
            self.n_updates += 1
            changed = True
        return changed

    def _due(self, b: int, points: np.ndarray, it: int, contraction: float) -> bool:
        in_use = self._points.get(b, points[:0])
        if self.policy == "every":
            return not np.array_equal(points, in_use)
        # lazy: not at the start guess (v+ = v-, whose returns overshoot into the contact at
        # unloading), at most MAX_UPDATES_PER_STEP a step
        if it == 0 or self._in_step.get(b, 0) >= MAX_UPDATES_PER_STEP:
            return False
        moved = np.setxor1d(points, in_use, assume_unique=True).size
        if moved == 0:
            return False
        return moved > SET_CHANGE * max(in_use.size, 1) or contraction > POOR_CONTRACTION


def tangent_solve(solver, h: float, th2h2: float, diff: sp.csr_matrix):
    """The solve of W_t = W_el + th2h2 psi^T diff psi (module doc) of a BodySolver at step
    size h: Woodbury on the elastic factor (sparse W), or W_t factored (dense W)."""
    body = solver.body
    rows = np.flatnonzero(np.diff(diff.indptr))  # the yielding cells' nodal DOFs
    C = th2h2 * diff[rows][:, rows].toarray()
    if not sp.issparse(body.k_hat):
        p = np.asarray(body.psi)[rows]
        W = np.array(solver.elastic_matrix(h), dtype=float) + p.T @ C @ p
        try:
            cho = sla.cho_factor(W)
        except np.linalg.LinAlgError:
            raise SolverError(
                f"body {body.name!r}: the plastic tangent's iteration matrix is not positive "
                "definite"
            ) from None
        return lambda rhs, cho=cho: cho_solve(cho, rhs)
    if SPARSE_FORM == "refactor":  # W_t has W's pattern: a numeric factorization
        psi = sp.csr_matrix(body.psi)
        return solver.factor_like_w(solver.elastic_matrix(h) + th2h2 * (psi.T @ diff @ psi))
    # U = psi^T E_rows; Z = W_el^-1 U from the elastic factor's nodal columns (each DOF
    # solved once per step size in a run)
    n = len(rows)
    selector = sp.csr_matrix((np.ones(n), (np.arange(n), rows)), shape=(n, body.psi.shape[0]))
    Z = np.asarray(solver.elastic_nodal_inverse(h, selector))
    Ut = sp.csr_matrix(body.psi)[rows]
    try:
        cap = sla.lu_factor(np.eye(n) + C @ (Ut @ Z))
    except (np.linalg.LinAlgError, ValueError):
        raise SolverError(
            f"body {body.name!r}: the plastic tangent's capacitance matrix is singular"
        ) from None
    return WoodburySolve(solver.elastic_solve(h), Z, C, Ut, cap)


class WoodburySolve:
    """x = W_t^-1 b = y - Z (I + C U^T Z)^-1 C U^T y, y = W_el^-1 b, for b (nq,) or (nq, k)
    (module doc; Ut = U^T)."""

    def __init__(self, el_solve, Z, C, Ut, cap):
        self.el_solve, self.Z, self.C, self.Ut, self.cap = el_solve, Z, C, Ut, cap

    def __call__(self, rhs):
        rhs = rhs.toarray() if sp.issparse(rhs) else rhs
        y = np.asarray(self.el_solve(rhs))
        return y - self.Z @ lu_solve(self.cap, self.C @ (self.Ut @ y))
