"""Moreau-Jean theta scheme (Jean 1999) with position-level joints: the implicit midpoint rule
at theta = 1/2 (second order), first order for a fixed theta > 1/2 (DEFAULT_THETA, the only
default of theta in the package), second order with theta(h) computed for each step from a
damping time tau (integrate.theta: 1/2 + h / (4 tau) up to the contact step).

For every body, with v- the velocity at t, v+ at t + h, v_m = theta v+ + (1 - theta) v- and the
configuration x_m = x(t) (+) theta h v_m (Lie-group update of A):

    M(x_m) (v+ - v-) = h F(x_m, v_m) + Phi^T lambda            (impulse-momentum over the step)
    x(t + h) = x(t) (+) h v_m

F = -k_hat q_m (- c_hat q_dot_m) (- s K_G q_m: a spinning body's geometric stiffening,
bodies.stiffening) + gravity + quadratic-velocity terms. theta = 1/2: the implicit midpoint
rule (second order, symplectic, the linear elastic energy conserved exactly); theta > 1/2
(Jean 1999) damps omega h >> 1 (amplification (1 - theta)/theta at infinity), removing the
step-to-step ringing of the contact nodes that makes Lagrange-multiplier contact chatter;
theta(h) from a damping time keeps second order (the rule and its damping: integrate.theta,
docs/contact_law.md).

Constraints (seed eq. 11, at impulse level):
- joints: phi(x(t + h)) = 0 (position level: no drift), rows Phi_v at x_m; at theta > 1/2
  v+ is then projected onto the rows' velocity level at x(t + h) (velocity_projection: no
  ringing at the step's Nyquist frequency);
- contacts (Moreau 1988, Jean 1999): for candidate pairs, u_N(v+) >= min(beta max(0, -g)/h,
  max(0, -u_N-)), lambda_N >= 0, complementary: an impact is an impulse with Newton
  restitution 0 at the contact node, persistent contact keeps u_N = 0, release happens when
  lambda would turn tensile. The penetration recovery is capped by the closing speed u_N-
  (contact.pairs): uncapped, it turned the impact's own penetration h (1 - theta) |u_N-| into
  a separation speed beta (1 - theta) |u_N-| the next step (two rigid rods: restitution
  beta (1 - theta) instead of 0).

Penetration through a step: docs/contact_law.md, "Penetration through a step".

Massless coordinates (contact nodes whose mass was redistributed, fe.mass_redistribution) are
algebraic: after every step they are put in equilibrium at the step's end
(integrate.moreau_jean.massless), which keeps them from alternating about their midpoint equilibrium
(undamped at theta = 1/2).

Solved by modified Newton with the per-body matrix W = M + theta^2 h^2 K (factored once per
h, see body_solver); constraint impulses by the mixed LCP on the Delassus matrix
D = Phi W^-1 Phi^T. This module holds the scheme: the residual, the Newton loop and the
impulses. What makes it fast is elsewhere: the contractions carried with the states
(carried.py), W's refresh policy and solves (iteration_matrix.py), k_hat dq_dot from the
solves' right-hand sides (w_images.py), the threads (body_threads.py), the linear step of
non-rotating frames (nonrotating.py); and what keeps it exact: the massless coordinates'
equilibrium (massless.py), the momentum balance (momentum_balance.py) and the relaxation of
a stalled iteration (relaxation.py).
"""

from __future__ import annotations

import numpy as np

from flexmvm.bodies.momentum import momentum_terms, momentum_terms_nodal
from flexmvm.errors import SolverError
from flexmvm.integrate import DEFAULT_THETA
from flexmvm.integrate.moreau_jean import fused_newton, nonrotating
from flexmvm.integrate.moreau_jean.body_solver import BodySolver
from flexmvm.integrate.moreau_jean.body_threads import BodyThreads
from flexmvm.integrate.moreau_jean.carried import CarriedState
from flexmvm.integrate.moreau_jean.coulomb import solve_contact_impulses
from flexmvm.integrate.moreau_jean.iteration_matrix import IterationMatrices
from flexmvm.integrate.moreau_jean.massless import (
    MasslessCoordinates,
    check_contact_law,
    equilibrate_step_end,
)
from flexmvm.integrate.moreau_jean.momentum_balance import balance_translation, balanced_residuals
from flexmvm.integrate.moreau_jean.newton_iterate import (
    NewtonIterate,
    joint_rows,
    relative_residual,
    roundoff_momenta,
)
from flexmvm.integrate.moreau_jean.plastic_tangent import PlasticTangent
from flexmvm.integrate.moreau_jean.relaxation import AitkenRelaxation, relaxed_iterate
from flexmvm.integrate.moreau_jean.residual_kernels import iterate_velocities, residual_and_scale
from flexmvm.integrate.moreau_jean.stall_report import stall_report
from flexmvm.integrate.moreau_jean.velocity_projection import project_joint_velocities
from flexmvm.integrate.moreau_jean.w_images import WImages
from flexmvm.integrate.plastic_bodies import PlasticBodies
from flexmvm.integrate.row_products import after_step, candidate_rows, flat_product
from flexmvm.integrate.state import BodyState
from flexmvm.integrate.step import StepResult
from flexmvm.integrate.system import System
from flexmvm.integrate.theta import ThetaRule
from flexmvm.loads.applied import midpoint_forces

__all__ = ["MoreauJeanIntegrator", "StepResult"]

SLOW_ITERATIONS = 6  # from this iterate on (or when the residual grows) W is refreshed
# a rigid body's (empty) elastic arguments of momentum_terms: q-sized, (3, 3, 0), (3, 0)
_NO_COORDINATES = (np.zeros(0), np.zeros((3, 3, 0)), np.zeros((3, 0)))


class MoreauJeanIntegrator:
    """The Moreau-Jean theta scheme: `step(t, states, h)`. theta: a fixed theta, or a
    ThetaRule (theta of each step size). `order` is its order of accuracy for smooth motion:
    2 at theta = 1/2 (implicit midpoint) or with theta(h) - 1/2 = O(h), 1 for a fixed
    theta > 1/2 (error ~ (theta - 1/2) h); tests/test_theta_scheme.py measures them."""

    def __init__(
        self,
        system: System,
        *,
        theta: float | ThetaRule = DEFAULT_THETA,
        rtol: float = 1e-10,
        max_iter: int = 40,
        exploit_nonrotating: bool = True,
    ):
        if not isinstance(theta, ThetaRule):
            if not 0.5 <= theta <= 1.0:
                raise SolverError(f"theta must be in [0.5, 1], got {theta!r}")
            theta = ThetaRule(theta)
        self.system = system
        self.theta_rule = theta
        self.theta = theta.theta  # the fixed theta (with a damping time: not used)
        bodies = system.bodies
        self.threads = BodyThreads(bodies)
        self.solvers = [
            BodySolver(body, theta.at, pool=pool)
            for body, pool in zip(bodies, self.threads.solve_pool)
        ]
        self.rtol = rtol
        self.roundoff_kgm = roundoff_momenta(bodies)
        self.max_iter = max_iter
        self.n_joint_rows = sum(j.n_rows for j in system.joints)
        self.exploit_nonrotating = exploit_nonrotating
        self.order = theta.order
        self.n_nonrotating_steps = 0
        self.loads = tuple(system.loads)
        self.gravity = np.asarray(system.gravity, dtype=float)
        # coordinates without mass (redistributed contact nodes): equilibrium at step ends
        self.massless = [MasslessCoordinates.of(b) for b in bodies]
        check_contact_law(system, self.massless)
        # elastic-plastic bodies: their history beside the states (integrate.plastic_bodies)
        self.plastic = PlasticBodies(system)
        if any(self.massless[b] is not None for b in self.plastic.history):
            raise SolverError("plastic bodies cannot have massless (redistributed) contact nodes")
        # bodies whose k_hat dq_dot comes from W_qq dq_dot (full FE, undamped, not stiffened)
        plain = {b for b in self.threads.sparse if bodies[b].c_hat is None}
        # the consistent tangent of yielding bodies (plastic_tangent); their W_qq is not
        # M_qq + (theta h)^2 k_hat then, so they take k_hat dq_dot by the product
        self.tangent = PlasticTangent(self.plastic, self.solvers)
        tangent = self.tangent.bodies
        self.images = WImages({b for b in plain - tangent if bodies[b].stiffening is None})
        self.carried_state = CarriedState(bodies, self.images, self.threads.contraction_pool)
        self.matrices = IterationMatrices(
            bodies, self.solvers, self.threads, self.carried_state, self.images
        )
        self.fused = [fused_newton.applies(self, b) for b in range(len(bodies))]
        # relaxation of a step whose iteration stalls (integrate.moreau_jean.relaxation)
        self.relax = AitkenRelaxation(
            [float(np.ptp(body.X, axis=0).max()) if len(body.X) else 1.0 for body in bodies]
        )

    @property
    def n_factorizations(self) -> int:
        """Factorizations of W made so far, over all bodies."""
        return sum(s.n_factorizations for s in self.solvers)

    def carried(self, b: int, st: BodyState) -> tuple[np.ndarray, np.ndarray]:
        """(L(q), L(q_dot)) of body b at state st in the body's carried form
        (FlexibleBody.carried_contractions: compact for full-FE bodies): the carried ones if st
        is the state this integrator produced, else computed (integrate.moreau_jean.carried)."""
        c = self.carried_state.at(b, st)
        return c.Lq, c.Lqd

    def carried_products(self, b: int, st: BodyState) -> tuple[np.ndarray, np.ndarray]:
        """(k_hat q, M_qq q_dot) of body b at state st, as carried (see carried): the
        energies of an output need no product with k_hat or M_qq."""
        c = self.carried_state.at(b, st)
        return c.Kq, c.Mqd

    # ---------------------------------------------------------------- the momentum balance
    def _residuals(self, t, states, v_plus, h, th):
        """Momentum residuals without constraint forces, midpoint and end configurations
        (per body, on threads when several bodies are full FE: integrate.moreau_jean.body_threads);
        th: the step's theta."""
        applied = midpoint_forces(self.loads, self.system.bodies, states, v_plus, h, th, t)
        out = self.threads.each(
            lambda b: self._residual(b, t, states[b], v_plus[b], h, th, applied.get(b)),
            range(len(states)),
        )
        R, mids, ends, scales = zip(*(out[b] for b in range(len(states))))
        return list(R), list(mids), list(ends), list(scales)

    def _residual(self, b, t, st, vp, h, th, applied=None):
        """Body b's residual M(x_m) (v+ - v-) - h F(x_m, v_m), its midpoint and end states
        and its momentum scale; applied: the applied loads' force on it (loads.applied)."""
        if self.fused[b]:  # one compiled call (integrate.moreau_jean.fused_newton; bit for bit)
            return fused_newton.fused_residual(self, b, t, st, vp, h, th, applied)
        body, g = self.system.bodies[b], self.gravity
        vm, dv = iterate_velocities(st.v, vp, th)  # th vp + (1 - th) v-, vp - v- (bit for bit)
        mid = st.advanced(vm, th * h)
        end = st.advanced(vm, h)
        if body.nq:
            Lq_m, Lqd_m, Kq_m = self.carried_state.midpoint(b, st, vp, th, h)
            if b in self.plastic:  # the return at the midpoint (integrate.plastic_bodies)
                c_q = self.plastic.midpoint_force(b, mid.q)
                Kq_m = Kq_m if c_q is None else Kq_m + c_q
            # M is linear: M v_m = M v- + th M dv, and M_qq v- is carried with the state
            mqq_dv = self.carried_state.mass_increment(b)
            mqq_vm = self.carried_state.at(b, st).Mqd + th * mqq_dv
            inertia, F, momentum = (np.empty(body.nv) for _ in range(3))
            inv, nodal = body.inv, body.nodal
            if nodal is not None:
                momentum_terms_nodal(
                    mid.A, mid.q, dv, vm, Lq_m, Lqd_m, Kq_m, mqq_dv, mqq_vm, inv.mass, inv.S0,
                    inv.S1, inv.G0, nodal.MsX, nodal.node, nodal.comp, g, inertia, F, momentum,
                )  # fmt: skip
            else:
                momentum_terms(
                    mid.A, mid.q, dv, vm, Lq_m, Lqd_m, Kq_m, mqq_dv, mqq_vm, inv.mass, inv.S0,
                    inv.S1, inv.G0, body.G1_array, g, inertia, F, momentum,
                )  # fmt: skip
            if body.c_hat is not None:
                F[6:] -= flat_product(body.c_hat, vm[6:])
            if body.stiffening is not None:  # the spin's prestress (bodies.stiffening)
                F[6:] -= body.stiffening.force(vm[3:6], mid.q)
        else:
            # a rigid body: the same kernel with no elastic coordinates (one call instead of
            # ~40 small numpy ones; the same terms as inertia_terms, mass_times, velocity_forces
            # and gravity_forces to round-off: tests/test_compiled_step.py)
            inertia, F, momentum = (np.empty(6) for _ in range(3))
            inv, e = body.inv, _NO_COORDINATES
            momentum_terms(
                mid.A, e[0], dv, vm, e[1], e[1], e[0], e[0], e[0], inv.mass, inv.S0,
                e[2], inv.G0, e[1], g, inertia, F, momentum,
            )  # fmt: skip
        # F += applied, R = inertia - h F and the momentum scale in one call (bit for bit)
        R, scale = residual_and_scale(
            inertia, F, momentum, _NO_COORDINATES[0] if applied is None else applied, h
        )
        return R, mid, end, scale

    # ---------------------------------------------------------------- the step
    def step(self, t: float, states: list[BodyState], h: float) -> StepResult:
        """One step from t to t + h. Frames that do not rotate (omega = 0, no joints) take the
        linear step of integrate.moreau_jean.nonrotating, verified against the rotational rows; any
        other step, or one whose verification fails, the general modified-Newton step."""
        th = self.theta_rule.at(h)
        self.tangent.start_step(h)  # the W a step starts from (plastic_tangent)
        crows, parts = candidate_rows(self.system, states, h)
        if self.exploit_nonrotating and nonrotating.applies(self.system, states):
            out = nonrotating.nonrotating_step(
                self.system, self.solvers, th, self.rtol, self.loads, t, states, h, crows
            )
            if (
                out is not None
                and self.plastic
                and not self.plastic.elastic_step(states, out[0], th)
            ):
                out = None  # a plastic body yields: the Newton step with its return
            if out is not None:
                self.plastic.commit(states, out[0])
                self.n_nonrotating_steps += 1
                new_states, lam_c, res_t, lcp_res = out
                self._equilibrate_massless(t, h, th, states, new_states, [(crows.rows, lam_c)])
                after_step(parts, lam_c, h)
                return StepResult(
                    new_states,
                    np.zeros(0),
                    crows,
                    lam_c,
                    1,
                    0.0,
                    translation_residual=res_t,
                    lcp_residual=lcp_res,
                )
        return self._newton_step(t, states, h, th, crows, parts)

    def _newton_step(self, t, states, h, th, crows, parts) -> StepResult:
        """The modified Newton iteration: v_free = v+ - W^-1 R(v+), then the constraint
        impulses of the LCP on D = Phi W^-1 Phi^T, v+ = v_free + W^-1 Phi^T lambda, until
        the residual with the impulses is within rtol (or on the round-off floor)."""
        # a refresh of M_wq due at the start is solved with the first iterate's right-hand
        # side (BodySolver.refresh_coupling, defer): the contact columns come after that solve
        self.matrices.prepare(states, h, refresh_tol=None, defer=True)
        n_j = self.n_joint_rows
        v0 = [st.v.copy() for st in states]
        s = NewtonIterate(v0, v0, np.zeros(n_j + crows.rows.m))  # v_free set by the first iterate
        self.images.start(self.system.bodies)
        self.relax.start()
        for it in range(self.max_iter + 1):
            v_before, image_before = s.v_plus, dict(self.images.plus)
            R, mids, ends, scales = self._residuals(t, states, s.v_plus, h, th)
            phi, jrows = joint_rows(self.system, t, h, mids, ends)
            jacobian = {b: jrows.body_matrix(b) for b in jrows.blocks} if n_j else {}
            res_norm = max(float(np.abs(r).max()) for r in R) if it else np.inf
            if it > 0 and self._accepted(s, it, h, R, jacobian, crows, phi, scales):
                break
            refreshed = self._refresh_when_slow(s, it, res_norm, mids, h, crows)
            if self.tangent.update(h, th, it, res_norm / s.last_norm if it > 1 else 0.0):
                refreshed = self._contact_columns(s, h, crows) if it else True
            s.last_norm = res_norm
            if it == self.max_iter:
                raise SolverError(
                    f"Moreau-Jean step at t = {t:.6e} s (h = {h:.3e} s) did "
                    f"not converge in {self.max_iter} iterations: "
                    + stall_report(
                        self.system.bodies, s.residuals, scales, self.rtol, crows, s.lam[n_j:], n_j
                    )
                )
            if it > 0 and not refreshed and not s.relaxed:
                # bodies whose residual is all in the frame rows: v_free of the last iterate
                # minus W^-1 [R_f; 0] (with the constraint impulses of the last iterate in
                # R_f); the others as on the first iterate, v+ - W^-1 R
                s.v_free = self.matrices.corrected_free_velocities(
                    R, s.residuals, scales, s.v_free, s.v_plus, self.rtol
                )
            else:
                s.v_free = self.matrices.free_velocities(R, s.v_plus)
            self._impulses(s, it, h, th, crows, phi, jrows, jacobian)
            s.v_plus, s.relaxed = relaxed_iterate(
                self.relax, self.images.plus, v_before, s.v_plus, image_before, s.stalled
            )
        return self._end_of_step(
            s, it, t, h, th, states, crows, parts, phi, jrows, mids, ends, scales
        )

    def _accepted(self, s: NewtonIterate, it, h, R, jacobian, crows, phi, scales) -> bool:
        """Convergence test of iterate it > 0 (NewtonIterate.converged_at) on the residual
        with the last impulses."""
        s.rel, s.rel_translation, s.translation_sum, s.residuals = relative_residual(
            self.system.bodies, R, jacobian, crows.rows, s.lam, self.n_joint_rows, scales
        )
        stall = self.plastic.stall_ratio(0.5)  # yielding returns converge slower (plastic_bodies)
        return s.converged_at(it, h, phi, self.rtol, self.max_iter, stall, self.roundoff_kgm)

    def _refresh_when_slow(self, s: NewtonIterate, it, res_norm, mids, h, crows) -> bool:
        """W's coupling refreshed at the midpoint configuration when the iteration is slow
        (SLOW_ITERATIONS) or its residual grew; True if refreshed."""
        if not (it == SLOW_ITERATIONS or (it > 1 and res_norm > s.last_norm)):
            return False
        self.matrices.prepare(mids, h, refresh_tol=0.0)
        if crows.rows.m:
            # the contact columns W^-1 Phi^T must be those of the W the free velocity is
            # solved with: with the old ones the iteration has a fixed point at
            # R = W_new W_old^-1 Phi^T lambda, a residual that never goes away
            self._contact_columns(s, h, crows)
        return True

    def _contact_columns(self, s: NewtonIterate, h, crows) -> bool:
        m_c = crows.rows.m
        s.contact_compliance = self.matrices.contact_compliance(crows, h) if m_c else {}
        s.contact_delassus = sum((c.D for c in s.contact_compliance.values()), np.zeros((m_c, m_c)))
        return True

    def _impulses(self, s: NewtonIterate, it, h, th, crows, phi, jrows, jacobian) -> None:
        """v+ = v_free + W^-1 Phi^T lambda with the impulses lambda of the mixed LCP on
        D = Phi W^-1 Phi^T (joints: equalities closing phi at the step's end; contacts:
        u_N(v+) >= the lower bounds of contact.pairs, lambda_N >= 0, complementary)."""
        n_j, m_c = self.n_joint_rows, crows.rows.m
        images = self.images
        if s.contact_compliance is None:
            self._contact_columns(s, h, crows)
        compliance = s.contact_compliance
        assert compliance is not None  # made by _contact_columns
        if n_j + m_c == 0:
            s.v_plus = s.v_free
            images.plus = dict(images.free)
            return
        joint_columns = self.matrices.joint_columns(jrows, h) if n_j else {}
        D = np.zeros((n_j + m_c, n_j + m_c))
        D[n_j:, n_j:] = s.contact_delassus
        for b, Yb in joint_columns.items():
            D[:n_j, :n_j] += jacobian[b] @ Yb
            if b in crows.rows.blocks:
                D[n_j:, :n_j] += crows.rows.body_times(b, Yb, self.system.bodies[b].psi)
        D[:n_j, n_j:] = D[n_j:, :n_j].T
        c = np.zeros(n_j + m_c)
        if n_j:
            c[:n_j] = jrows.times(s.v_free) - jrows.times(s.v_plus) + phi / (th * h)
        if m_c:
            c[n_j:] = crows.rows.times(s.v_free) - crows.lower
        s.lam, lcp_res = solve_contact_impulses(D, c, n_j, crows, s.lam if it else None)
        s.lcp_max = max(s.lcp_max, lcp_res)
        lam = s.lam
        v_plus = list(s.v_free)
        images.plus = dict(images.free)  # (every update makes new arrays)
        for b, Yb in joint_columns.items():
            dv = Yb @ lam[:n_j]
            v_plus[b] = v_plus[b] + dv
            images.impulses(b, self.solvers[b], jrows, lam[:n_j], dv)
        for b, cb in compliance.items():
            dv = cb.velocity(lam[n_j:])
            v_plus[b] = v_plus[b] + dv
            images.impulses(b, self.solvers[b], crows.rows, lam[n_j:], dv)
        s.v_plus = v_plus

    def _end_of_step(
        self, s: NewtonIterate, it, t, h, th, states, crows, parts, phi, jrows, mids, ends, scales
    ) -> StepResult:
        """The accepted iterate as the step's result: translational rows balanced (no
        joints), end states with v+, carried contractions advanced, massless coordinates
        to equilibrium."""
        self.plastic.check()  # before anything moves on: a refused step raises
        n_j = self.n_joint_rows
        lam, v_plus = s.lam, s.v_plus
        rel, res_t = s.rel, s.translation_sum
        converged_t, shift = res_t, np.zeros(3)  # the solves' translational rows, unbalanced
        if not n_j:
            rel, res_t = balance_translation(
                balanced_residuals(self.system.bodies, s.residuals, scales, mids),
                ends,
                v_plus,
                th * h,
                rel,
                res_t,
                self.rtol,
            )
            shift = res_t - converged_t
        after_step(parts, lam[n_j:], h)
        new_states = [e for e in ends]
        for st, vp in zip(new_states, v_plus):
            st.v = vp
        self.carried_state.advance(states, new_states, h)
        if n_j and th > 0.5:  # v+ onto the joints' velocity rows: no Nyquist ringing
            # (velocity_projection; not at theta = 1/2, whose energy it would not keep); its
            # impulses count as the joints' (a drive's torque includes them)
            lam = lam.copy()
            lam[:n_j] += project_joint_velocities(
                self.system, self.matrices, self.carried_state, new_states, t + h, h
            )
        plastic_work = self.plastic.commit(states, new_states)
        self._equilibrate_massless(
            t,
            h,
            th,
            states,
            new_states,
            [(crows.rows, lam[n_j:]), (jrows if n_j else None, lam[:n_j])],
        )
        drift = float(np.abs(phi).max()) if phi.size else 0.0
        return StepResult(
            new_states,
            lam[:n_j],
            crows,
            lam[n_j:],
            it,
            drift,
            converged=rel <= self.rtol or s.at_roundoff,
            residual=rel,
            translation_residual=converged_t,
            lcp_residual=s.lcp_max,
            momentum_shift=shift,
            plastic_work=plastic_work,
        )

    def _equilibrate_massless(self, t, h, th, states, new_states, held) -> None:
        """Massless coordinates to equilibrium at the step's end (integrate.moreau_jean.massless);
        the carried k_hat q and k_hat q_dot follow (the mass-weighted contractions do not see
        massless coordinates)."""
        for b, _, _, k_dq, k_dv in equilibrate_step_end(
            self.massless, self.system.bodies, self.loads, t + th * h, h, states, new_states, held
        ):
            c = self.carried_state.of_state(b, new_states[b])
            if c is not None:
                c.Kq = c.Kq + k_dq
                c.Kqd = c.Kqd + k_dv
