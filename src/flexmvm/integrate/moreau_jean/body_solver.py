"""Iteration matrix of one body for the implicit-midpoint step, solved by a bordered system.

    W = [ M_ff(A, q)   M_fq~    ]      W_qq = M_qq + theta h C + theta^2 h^2 K  (constant)
        [ M_fq~^T      W_qq     ]      M_fq~ = [A S1 ; M_wq(0)]

W_qq is factored once per step size h and cached, so a change of step size among a few values
costs no refactorization after the first use. The frame coupling enters through a Schur
complement (6 x 6) with Z = W_qq^-1 M_fq~^T precomputed per h (its rotation-dependent part is
W_qq^-1 S1^T A^T: the A is applied on the fly). W is a modified-Newton matrix: exact for
translation with constant M_wq, approximate otherwise; the residual is always exact.
"""

from __future__ import annotations

import functools
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.errors import SolverError
from flexmvm.fe.solvers.cholesky import cholesky_ldl
from flexmvm.fe.solvers.ordering import elimination_order
from flexmvm.fe.solvers.symbolic import SymbolicFactor
from flexmvm.integrate.moreau_jean.compliance import NodalColumns, NodalCompliance, nodal_compliance
from flexmvm.integrate.moreau_jean.dense_solve import cho_factor, cho_solve, lu_factor, lu_solve

# Factors kept per body, least recently used dropped first: the variable step takes dt_s 2^k
# for k = 0..9 (pendulum_release.toml: 0.5 us to 256 us), and a swing that comes down to the
# contact step level by level and goes back up after the separation must not refactor
# (~3 s per level for a 25,000-DOF rod; a full-FE factor holds ~100 MB).
MAX_CACHED = 10
# W is refactored when the spin squared of a stiffened body moved by this fraction of
# (its value in W + the body's spin_crit): BodySolver.use_spin
SPIN_TOL = 0.1

#: The factorizations as they happen, with the set-up's stages (assembly.build_cache.SETUP_LOG)
SETUP_LOG = logging.getLogger("flexmvm.setup")

T = TypeVar("T")


#: x = W_qq^-1 b for b (nq,) or (nq, k): a factor's back-substitution
Solve = Callable[[np.ndarray], np.ndarray]


@dataclass
class _Factor:
    solve: Solve
    Zr: np.ndarray  # W_qq^-1 S1^T (nq, 3)
    Zw: np.ndarray  # W_qq^-1 M_wq(0)^T (nq, 3)
    S1Zr: np.ndarray
    S1Zw: np.ndarray
    MwZr: np.ndarray
    MwZw: np.ndarray
    # the M_wq of Zw when not M_wq(0) (refresh_coupling, a plastic tangent); None: M_wq(0)
    Mw_used: np.ndarray | None = None
    nodal: NodalColumns | None = None  # the nodal column cache (made on first use: _nodal)


class BodySolver:
    """Solves W x = b for one body; factorizations cached per step size."""

    def __init__(
        self,
        body: FlexibleBody,
        theta: float | Callable[[float], float] = 0.5,
        max_cached: int = MAX_CACHED,
        pool=None,
    ):
        self.body = body
        # a thread pool for the back-substitutions of a sparse W (fe.ldl: two etree halves
        # on two threads); None: on the calling thread
        self.pool = pool
        self._symbolic: SymbolicFactor | None = None  # of W's pattern, made by the first _factor
        # theta of the step size h: a fixed one, or a function of h (integrate.theta); W is
        # factored once per h either way
        self.theta = theta
        self._cache: dict[float, _Factor] = {}
        self._order: list[float] = []
        self._max = max_cached
        self.n_factorizations = 0
        self._Mw0 = body.inertia_terms(np.zeros(body.nq))[2] if body.nq else np.zeros((3, 0))
        # the frame block's factor: lu_factor of the 6 x 6 Schur complement (prepare), and
        # the rigid body's cho_factor of M_ff / the translational one's of S_t or its mass
        self._schur: tuple[np.ndarray, np.ndarray] | None = None
        self._rigid: tuple[np.ndarray, bool] | None = None
        self._schur_t: tuple[np.ndarray, bool] | None = None
        self._mass_t = np.zeros(0)  # a rigid body's m (3,) of W_t (prepare_translation)
        self._f: _Factor | None = None  # the factor of the last prepare: None for a rigid body
        self._A = np.eye(3)
        # M_wq(q) - the M_wq in W, when refresh_coupling kept the old one
        self._dMw: np.ndarray | None = None
        # (h, M_wq) of a deferred refresh (refresh_coupling)
        self._pending: tuple[float, np.ndarray] | None = None
        self._frame_args: tuple[float, np.ndarray, np.ndarray] | None = None
        self.n_coupling_updates = 0
        self.spin = 0.0  # s [rad^2/s^2] of the geometric stiffening in W (use_spin)
        self.n_spin_updates = 0
        # (h, _Factor) of a plastic tangent's W (use_tangent)
        self._tangent: tuple[float, _Factor] | None = None
        self.n_tangent_updates = 0

    def use_spin(self, s: float, tol: float = SPIN_TOL) -> None:
        """Take W_qq = M_qq + (theta h)^2 (k_hat + s K_G) (bodies.stiffening) when the spin
        squared s [rad^2/s^2] moved from the one in W by more than tol (s_W + spin_crit):
        the cached factors are dropped and made again on use. The modified Newton iteration
        then contracts the stale part by at least tol per iterate (|ds| x^T K_G x over
        x^T (k_hat + s_W K_G) x <= |ds| / (spin_crit + s_W) for a tensile prestress); tol = 0:
        exactly s. A spin-up from rest to s_end refactors about ln(1 + s_end / spin_crit) /
        ln(1 + tol) times. Bodies without stiffening ignore it."""
        stiffening = self.body.stiffening
        if stiffening is None or s == self.spin:
            return
        if abs(s - self.spin) <= tol * (self.spin + stiffening.spin_crit):
            return
        self.spin = s
        self._cache.clear()
        self._order.clear()
        self._pending = None
        self._dMw = None
        self.n_spin_updates += 1

    def _factor(self, h: float) -> _Factor:
        if self._tangent is not None and self._tangent[0] == h:
            return self._tangent[1]
        f = self._cache.get(h)
        if f is not None:
            if self._order[-1] != h:  # least recently used goes first
                self._order.remove(h)
                self._order.append(h)
            return f
        b = self.body
        solve: Solve
        t0 = time.perf_counter()
        W = self.elastic_matrix(h)
        data = W.data if sp.issparse(W) else np.asarray(W)
        if not np.isfinite(data).all():
            raise SolverError(
                f"body {b.name!r}: iteration matrix M + h^2/4 K holds a non-finite "
                f"number (NaN/inf) at step size h = {h:.3g} s"
            )
        if sp.issparse(W):
            if self._symbolic is None:
                # an order whose elimination tree has two halves, solved on two threads with
                # a pool, in the same arithmetic without one (fe.ordering; one pattern for
                # every h: one order and one symbolic analysis, the order made with the
                # body when it was built by a scenario)
                order = (
                    b.elimination_order if b.elimination_order is not None else elimination_order(W)
                )
                self._symbolic = SymbolicFactor(
                    W, order if order is not None and order.size else None
                )
            try:
                # W is SPD: supernodal L D L^T (fe.cholesky), GIL released
                solve = cholesky_ldl(W, self.pool, self._symbolic).solve
            except SolverError as exc:
                raise SolverError(
                    f"body {b.name!r}: iteration matrix is singular ({exc})"
                ) from None
        else:
            try:
                cho = sla.cho_factor(np.asarray(W))
            except np.linalg.LinAlgError:
                raise SolverError(
                    f"body {b.name!r}: iteration matrix M + h^2/4 K is not positive definite"
                ) from None
            solve = functools.partial(cho_solve, cho)
        self.n_factorizations += 1
        SETUP_LOG.info(
            "body %r: iteration matrix factored at h = %.3g s (%d coordinates): %.1f s",
            b.name,
            h,
            b.nq,
            time.perf_counter() - t0,
        )
        f = self._make_factor(solve, self._Mw0)
        self._cache[h] = f
        self._order.append(h)
        if len(self._order) > self._max:
            self._cache.pop(self._order.pop(0), None)
        return f

    def elastic_matrix(self, h: float):
        """W_qq = M_qq + theta h C + (theta h)^2 (k_hat + s K_G) at step size h (sparse or
        dense as k_hat), without a plastic tangent."""
        b = self.body
        th = self.theta(h) if callable(self.theta) else self.theta
        W = b.inv.M_qq + (th * th * h * h) * b.k_hat
        stiffening = b.stiffening
        if self.spin and stiffening is not None:  # at the spin squared s of use_spin (only
            # a stiffened body's is ever nonzero)
            W = W + (th * th * h * h * self.spin) * stiffening.K_G
        if b.c_hat is not None:
            W = W + (th * h) * b.c_hat
        return W

    def _make_factor(self, solve: Solve, M_wq: np.ndarray) -> _Factor:
        """The factor record of a W_qq solve: its frame columns Z for the coupling M_wq."""
        S1 = self.body.inv.S1
        Zr = np.asarray(solve(np.ascontiguousarray(S1.T)))
        Zw = np.asarray(solve(np.ascontiguousarray(M_wq.T)))
        f = _Factor(solve, Zr, Zw, S1 @ Zr, S1 @ Zw, M_wq @ Zr, M_wq @ Zw)
        if M_wq is not self._Mw0:
            f.Mw_used = M_wq.copy()
        return f

    def elastic_solve(self, h: float) -> Solve:
        """The W_qq^-1 of the elastic W at h (the cached factor; a pending refresh done)."""
        self._flush()
        return self._elastic(lambda: self._factor(h).solve)

    def elastic_nodal_inverse(self, h: float, selector: sp.csr_matrix) -> np.ndarray:
        """nodal_inverse of the elastic W at h (its cached nodal columns)."""
        return self._elastic(lambda: self.nodal_inverse(h, selector))

    def factor_like_w(self, W: sp.spmatrix) -> Solve:
        """The solve of a sparse SPD matrix like W_qq (a plastic tangent's W_t): on W's
        symbolic analysis where the patterns agree, else analysed anew; call after W was
        factored."""
        try:
            return cholesky_ldl(W, self.pool, self._symbolic).solve
        except SolverError as exc:
            raise SolverError(
                f"body {self.body.name!r}: the plastic tangent's iteration matrix ({exc})"
            ) from None

    def _elastic(self, make: Callable[[], T]) -> T:
        tangent, self._tangent = self._tangent, None
        try:
            return make()
        finally:
            self._tangent = tangent

    def use_tangent(self, h: float | None, solve: Solve | None) -> None:
        """Solve with W_qq,t^-1 = ``solve`` at h (a plastic body's tangent W: integrate.
        plastic_tangent) until the next use_tangent; None: the elastic W again. The frame
        columns and the frame block (last prepare) are made for it."""
        self._flush()
        if solve is None:
            if self._tangent is None:
                return
            self._tangent = None
        else:
            assert h is not None  # a tangent is used at a step size
            f_el = self._tangent[1] if self._tangent is not None else self._factor(h)
            self._tangent = (h, self._make_factor(solve, self._mw(f_el)))
            self.n_tangent_updates += 1
        if self._frame_args is not None and self._frame_args[0] == h:
            self.prepare(*self._frame_args)

    def refresh_coupling(self, h: float, M_wq: np.ndarray, tol: float, defer: bool = False) -> None:
        """Use M_wq (3, nq) at the current configuration in W if it moved by more than tol
        (relative Frobenius norm) from the one in use: 3 back-substitutions. Bodies with small
        torsional inertia (thin rods) need it: their frame Schur complement is sensitive to
        M_wq(q). defer: the 3 columns are solved with the right-hand side of the next solve()
        (one 4-column back-substitution instead of a 3-column and a 1-column one: a
        multi-column solve reads the factor once, and a full-FE rod's solve is memory-bound;
        docs/notes/2026-11-27-comment-measurements.md); prepare() then waits for that solve,
        and any other use of W solves them first (_flush)."""
        if not self.body.nq:
            return
        self._pending = None
        f = self._factor(h)
        ref = self._mw(f)
        dMw = M_wq - ref
        if np.linalg.norm(dMw) <= tol * max(float(np.linalg.norm(ref)), 1e-300):
            self._dMw = dMw
            return
        self._dMw = None
        if defer:
            self._pending = (h, M_wq)
            return
        self._install_coupling(f, np.asarray(f.solve(np.ascontiguousarray(M_wq.T))), M_wq)

    def _install_coupling(self, f: _Factor, Zw: np.ndarray, M_wq: np.ndarray) -> None:
        f.Zw, f.S1Zw, f.MwZr, f.MwZw = Zw, self.body.inv.S1 @ Zw, M_wq @ f.Zr, M_wq @ Zw
        f.Mw_used = M_wq.copy()
        self.n_coupling_updates += 1

    def _flush(self, rhs: np.ndarray | None = None) -> np.ndarray | None:
        """Complete a deferred refresh, if any: its 3 columns solved (with rhs (nq,) or (nq, k)
        in the same back-substitution when given), installed, and the frame block made.
        Returns W_qq^-1 rhs (nq, k), or None when nothing was deferred."""
        if self._pending is None:
            return None
        h, M_wq = self._pending
        self._pending = None
        f = self._factor(h)
        cols = M_wq.T if rhs is None else np.column_stack([rhs, M_wq.T])
        Y = np.asarray(f.solve(np.ascontiguousarray(cols)))
        k = Y.shape[1] - 3
        self._install_coupling(f, np.ascontiguousarray(Y[:, k:]), M_wq)
        if self._frame_args is not None:  # made by the prepare() that waited for the columns
            self.prepare(*self._frame_args)
        return Y[:, :k]

    def prepare(self, h: float, A: np.ndarray, Mff: np.ndarray) -> None:
        """Set the step size and the frame block for the coming solves."""
        self._A = A
        if not (np.isfinite(A).all() and np.isfinite(Mff).all()):
            raise SolverError(
                f"body {self.body.name!r}: non-finite number (NaN/inf) in the "
                "frame mass matrix or rotation; the state diverged"
            )
        if not self.body.nq:
            self._f = None
            try:
                self._rigid = cho_factor(Mff)
            except np.linalg.LinAlgError:
                raise SolverError(
                    f"body {self.body.name!r}: rigid-body mass matrix is singular "
                    "(zero mass or zero inertia about an axis)"
                ) from None
            return
        f = self._factor(h)
        self._f = f
        self._frame_args = (h, A, Mff)
        if self._pending is not None:  # the frame block waits for the deferred columns
            return
        # M_fq~ Z with Z = [Zr A^T, Zw]:
        MZ = np.zeros((6, 6))
        MZ[:3, :3] = A @ f.S1Zr @ A.T
        MZ[:3, 3:] = A @ f.S1Zw
        MZ[3:, :3] = f.MwZr @ A.T
        MZ[3:, 3:] = f.MwZw
        if self._dMw is not None:
            # the Schur complement of the current M_wq to first order in the drift dM_w of
            # the one in W (exact in the omega-translation blocks, since Z_r is exact; the
            # omitted dM_w W_qq^-1 dM_w^T is below COUPLING_TOL^2 of M_w Z_w). S is small for
            # full FE (module docstring of iteration_matrix), so a stale M_w changes it by
            # several per cent (later iterates then converge by ~1/16 per iterate). The
            # bordered solve itself keeps the refreshed M_w (in M_fq~ y and Z), so its
            # elastic part misses W_qq^-1 dM_w^T x_w, first order in the drift: hence the
            # small COUPLING_TOL (iteration_matrix)
            dr, dw = self._dMw @ f.Zr, self._dMw @ f.Zw
            MZ[:3, 3:] += A @ dr.T
            MZ[3:, :3] += dr @ A.T
            MZ[3:, 3:] += dw + dw.T
        S = Mff - MZ
        try:
            self._schur = lu_factor(S)
        except (np.linalg.LinAlgError, ValueError):
            raise SolverError(
                f"body {self.body.name!r}: frame Schur complement is singular"
            ) from None

    def solve(self, b: np.ndarray) -> np.ndarray:
        """x = W^-1 b for b of shape (nv,) or (nv, k)."""
        if self._f is None:
            return cho_solve(self._made(self._rigid, "prepare"), b)
        f = self._f
        y = self._flush(b[6:])  # a deferred refresh: [b_q, M_wq^T] in one back-substitution
        if y is not None:
            return self._bordered(b[:6], y[:, 0] if b.ndim == 1 else y)
        y = np.asarray(f.solve(b[6:]))
        if y.ndim == 1 and b.ndim == 2:
            y = y[:, None]
        return self._bordered(b[:6], y)

    def coupling_transpose(self, xf: np.ndarray) -> np.ndarray:
        """B^T xf (nq,) for a frame vector xf (6,), B = [A S1; M_wq] the frame-elastic block
        of the W that solve(), solve_frame() and the contact columns use (with the A and
        M_wq of the last prepare / refresh_coupling). For x = W^-1 b: W_qq x_q = b_q - B^T x_f
        (what integrate.moreau_jean.w_images takes k_hat dq_dot from)."""
        self._flush()
        return (
            self.body.inv.S1.T @ (self._A.T @ xf[:3])
            + self._mw(self._made(self._f, "prepare")).T @ xf[3:6]
        )

    def solve_frame(self, bf: np.ndarray) -> np.ndarray:
        """x = W^-1 [bf; 0] for bf (6,): the frame Schur complement and the cached columns Z,
        no back-substitution."""
        self._flush()
        if self._f is None:
            return cho_solve(self._made(self._rigid, "prepare"), bf)
        return self._bordered(bf, np.zeros(self.body.nq))

    def _bordered(self, bf: np.ndarray, y: np.ndarray) -> np.ndarray:
        """W^-1 [bf; bq] from y = W_qq^-1 bq (the frame Schur complement of prepare())."""
        f, A = self._made(self._f, "prepare"), self._A
        # M_fq~ y
        My = np.concatenate([A @ (self.body.inv.S1 @ y), self._mw(f) @ y])
        xf = lu_solve(self._made(self._schur, "prepare"), bf - My)
        Zx = f.Zr @ (A.T @ xf[:3]) + f.Zw @ xf[3:]
        return np.concatenate([xf, y - Zx])

    def solve_nodal(self, h: float, bf: np.ndarray, selector: sp.csr_matrix) -> np.ndarray:
        """W^-1 Phi^T (6 + nq, m) for the rows Phi = [bf (m, 6), N psi] (N = selector (m,
        3 n_nodes)), its elastic part through the cached nodal columns (nodal_inverse): no
        back-substitution once the DOFs were touched at this h. Needs prepare(h, ...)."""
        if self._f is None:
            raise SolverError(f"body {self.body.name!r}: nodal solves need elastic coordinates")
        return self._bordered(np.ascontiguousarray(bf.T), self.nodal_inverse(h, selector))

    def prepare_translation(self, h: float, A: np.ndarray) -> None:
        """Set up solves with the translational block of W only (frame rotation frozen):

            W_t = [ m I       A S1 ]      Schur complement S_t = m I - A (S1 W_qq^-1 S1^T) A^T
                  [ S1^T A^T  W_qq ]      (3 x 3; S1 W_qq^-1 S1^T is cached per h)

        W_t is constant while A is: the non-rotating step is linear in v+ (see
        integrate.moreau_jean.nonrotating)."""
        self._A = A
        if not np.isfinite(A).all():
            raise SolverError(
                f"body {self.body.name!r}: non-finite number (NaN/inf) in the "
                "frame rotation; the state diverged"
            )
        self.use_spin(0.0, 0.0)  # omega = 0: no prestress, and the step is linear in v+
        m = self.body.inv.mass
        if not self.body.nq:
            self._f = None
            self._mass_t = np.full(3, m)
            return
        f = self._factor(h)
        self._f = f
        St = m * np.eye(3) - A @ f.S1Zr @ A.T
        try:
            self._schur_t = cho_factor(0.5 * (St + St.T))
        except np.linalg.LinAlgError:
            raise SolverError(
                f"body {self.body.name!r}: translational Schur complement is not positive definite"
            ) from None

    def solve_translation(self, b: np.ndarray, yq: np.ndarray | None = None) -> np.ndarray:
        """x = W_t^-1 b for b of shape (3 + nq,) or (3 + nq, k); yq = W_qq^-1 b[3:] when
        already known (contact columns from nodal_inverse; b may then be just its first three
        rows). Needs prepare_translation."""
        if self._f is None:
            return b / self._mass_t[:, None] if b.ndim == 2 else b / self._mass_t
        f, A = self._f, self._A
        bt = b[:3]
        y = np.asarray(f.solve(b[3:])) if yq is None else yq
        if y.ndim == 1 and b.ndim == 2:
            y = y[:, None]
        xt = cho_solve(
            self._made(self._schur_t, "prepare_translation"), bt - A @ (self.body.inv.S1 @ y)
        )
        return np.concatenate([xt, y - f.Zr @ (A.T @ xt)])

    def _mw(self, f: _Factor) -> np.ndarray:
        """The M_wq of f's frame columns."""
        return f.Mw_used if f.Mw_used is not None else self._Mw0

    def _nodal(self, f: _Factor) -> NodalColumns:
        """The nodal column cache of factor f (made on first use)."""
        cache = f.nodal
        if cache is None:
            cache = f.nodal = NodalColumns(self.body.psi, self.body.inv.S1, f.Zr, f.Zw, self._mw(f))
        return cache

    def _made(self, factor: T | None, by: str) -> T:
        """A factor of the last prepare (`by` names it), or SolverError if none was made."""
        if factor is None:
            raise SolverError(f"body {self.body.name!r}: solved before {by}()")
        return factor

    def nodal_inverse(self, h: float, selector: sp.csr_matrix) -> np.ndarray:
        """W_qq^-1 psi^T N^T (nq, m) for the nodal selector N (m, 3 n_nodes), exactly.

        Contact rows are combinations of a few nodal directions that move from step to step;
        the columns W_qq^-1 psi_j^T of the nodal DOFs j they touch are cached per h, so a new
        row costs a small dense product and a back-substitution is needed only for a DOF
        never touched before ("factor once, solve many"). The step itself never forms this
        (nq, m) block: see contact_compliance."""
        self._flush()
        f = self._factor(h)
        cache = self._nodal(f)
        slots, Nd = cache.touch(selector, f.solve)
        return cache.cols[slots].T @ Nd.T

    def contact_compliance(
        self, h: float, bf: np.ndarray, selector: sp.csr_matrix
    ) -> NodalCompliance:
        """D = Phi W^-1 Phi^T (m, m) and the velocity correction W^-1 Phi^T lambda of the
        rows Phi = [bf (m, 6), N psi] (N = selector (m, 3 n_nodes)) from the cached nodal
        columns (integrate.moreau_jean.compliance), with the frame block of the last prepare()."""
        self._flush()
        f = self._factor(h)
        frame = (self._A, self._made(self._schur, "prepare"), f.Zr, f.Zw, self._mw(f))
        return nodal_compliance(self._nodal(f), f.solve, bf, selector, frame)

    def translation_compliance(
        self, h: float, bf: np.ndarray, selector: sp.csr_matrix
    ) -> NodalCompliance:
        """As contact_compliance for W_t (prepare_translation): D (m, m) and the velocity
        correction (3 + nq,) = [dr_dot, dq_dot] of the rows [bf[:, :3], N psi]."""
        f = self._factor(h)
        frame = (self._A, self._made(self._schur_t, "prepare_translation"), f.Zr, None, None)
        return nodal_compliance(self._nodal(f), f.solve, bf, selector, frame)
