"""Moreau-Jean theta scheme (Jean 1999) with position-level joints: the implicit midpoint rule
at theta = 1/2 (second order), first order for theta > 1/2 (DEFAULT_THETA = 0.55, the seed
scenarios' value and the only default of theta in the package).

For every body, with v- the velocity at t, v+ at t + h, v_m = theta v+ + (1 - theta) v- and the
configuration x_m = x(t) (+) theta h v_m (Lie-group update of A):

    M(x_m) (v+ - v-) = h F(x_m, v_m) + Phi^T lambda            (impulse-momentum over the step)
    x(t + h) = x(t) (+) h v_m

F = -k_hat q_m (- c_hat q_dot_m) + gravity + quadratic-velocity terms. theta = 1/2 is the
implicit midpoint rule: second order, symplectic, conserving the energy of the linear elastic
part exactly. theta > 1/2 (Jean 1999) damps the components with omega h >> 1 (amplification
(1 - theta)/theta at infinity) at a first-order cost (damping ratio ~ (theta - 1/2) omega h / 2
for the resolved modes): it removes the step-to-step ringing of the contact nodes that makes
Lagrange-multiplier contact chatter. With theta - 1/2 proportional to the step (a scenario's
time.hf_damping_time_s tau: theta = 1/2 + h / (4 tau), the seed scenarios' choice) the local
error (theta - 1/2) h^2 y'' is O(h^3), so the scheme stays second order while what the step
cannot resolve decays as exp(-t / tau) at every h (docs/contact_law.md).

Constraints (seed eq. 11, at impulse level):
- joints: phi(x(t + h)) = 0 (position level: no drift), rows Phi_v at x_m;
- contacts (Moreau 1988, Jean 1999): for candidate pairs, u_N(v+) >= min(beta max(0, -g)/h,
  max(0, -u_N-)), lambda_N >= 0, complementary: an impact is an impulse with Newton
  restitution 0 at the contact node, persistent contact keeps u_N = 0, release happens when
  lambda would turn tensile. The penetration recovery is capped by the closing speed u_N-
  (contact.pairs): uncapped, it turned the impact's own penetration h (1 - theta) |u_N-| into
  a separation speed beta (1 - theta) |u_N-| the next step (two rigid rods: restitution
  0.09 at theta = 0.55).

Penetration (measured after every step on both surfaces, contact.penetration). For a pair that
is a row at the start of a step, g(t + h) = g + h (theta u_N+ + (1 - theta) u_N-) with
u_N+ >= min(beta max(0, -g)/h, max(0, -u_N-)): a node arriving with u_N- < 0 goes in by
h (1 - theta) |u_N-| (not h |u_N-| / 2: that is theta = 1/2); a pair held at rest keeps that
penetration (its recovery is capped by its closing speed, 0), and one that closes again
recovers at most its closing speed. A node that is not a row at the start of a step (its
predicted gap g + h u_N above gap_tol) is not held during it, and |u_N-| is the pair's own
approach speed, which the ringing of the contact nodes can make several times the impact
speed: there is no a-priori bound in terms of the impact speed. The constraint holds slave
nodes only; master surface nodes sit inside the slave facets by the chord error of the slave
face over the curved master (about a^2 / (8 R), facet size a, master radius R), independent
of h. Measured (with the recovery uncapped) at h = 0.5 us, theta = 0.55, impact speed
v0 = 0.21 m/s (h (1 - theta) v0 = 4.7e-8 m), slave nodes into master / master nodes into slave: flat faces, b1 full FE and b2
MVM 1-3: 4.7e-8 / 4.7e-8 m, at the first step; both MVM: 5.2e-7 / 5.2e-7 m, 1.5 us into a
re-impact at 66.5 us (the reduced faces chatter); seed case (hemispherical b1), b1 full FE: 3.5e-7 / 1.8e-6 m; both MVM: 1.5e-7 /
1.8e-6 m, at 190 us (of 660 us of contact; peak Hertz approach 21 um). The short full-FE flat
test case (h = 0.25 us): 2.4e-8 m both ways, h (1 - theta) v0.

Massless coordinates (contact nodes whose mass was redistributed, fe.mass_redistribution) are
algebraic: after every step they are put in equilibrium at the step's end (integrate.massless),
which keeps them from alternating about their midpoint equilibrium (undamped at theta = 1/2).

Solved by modified Newton with the per-body matrix W = M + h^2/4 K (factored once per h, see
body_solver); constraint impulses by the mixed LCP on D = Phi W^-1 Phi^T.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numba
import numpy as np

from flexmvm.bodies.momentum import momentum_terms, momentum_terms_nodal
from flexmvm.bodies.rotation import skew
from flexmvm.constraints.contact import ContactLaw, FrictionRows
from flexmvm.constraints.rows import Rows, stack
from flexmvm.errors import SolverError
from flexmvm.integrate import DEFAULT_THETA, nonrotating
from flexmvm.integrate.body_solver import BodySolver
from flexmvm.integrate.compliance import DenseCompliance
from flexmvm.integrate.coulomb import solve_contact_impulses
from flexmvm.integrate.massless import MasslessCoordinates, equilibrate
from flexmvm.integrate.relaxation import ACTIVATE_RATIO, AitkenRelaxation
from flexmvm.integrate.state import BodyState
from flexmvm.integrate.system import ContactRows, System
from flexmvm.threads import ENV_THREADS, worker_threads  # noqa: F401 (ENV_THREADS re-exported)

# The frame Schur complement S = M_ff - B W_qq^-1 B^T is small when the basis nearly spans
# the rigid motions (full FE: S ~ the mass within c h of the reference nodes, ~1e-5 of the
# body), so W's coupling B must be that of the current configuration: it is refreshed at the
# start of a step when it drifted (3 back-substitutions; every step for small bases, by
# COUPLING_TOL for large ones; in between S follows it to first order, BodySolver.prepare)
# and again at the midpoint when an iteration does not reduce the residual.
SLOW_ITERATIONS = 6
ROUNDOFF_FLOOR = 1e-7  # a residual below this that stops decreasing is round-off (large bases)
TRANSLATION_RTOL = 1e-13  # ...but the frame's translational rows (sums: no such floor) must
                          # converge to this, so linear momentum drifts < 1e-9 over an impact
SMALL_BASIS = 400     # up to this many elastic coordinates: refresh every step (cheap)
# Larger bases: refresh when M_wq moved by this much (relative). The bordered solve uses the
# M_wq of the last refresh and S follows the drift to first order only, so a drift leaves the
# first solve's frame rows off by ~the drift times the rotational coupling, and its elastic
# rows by dM_w^T x_w. Seed as shipped, 2 ms (b1 full FE), damped scheme: at 1e-4, b1 refreshed
# 5 times and the steps after the separation (2 us) took 3.41 residuals each; at 1e-6, 2.00
# residuals per step everywhere, 12.0 against 13.9-15.0 ms a step after the separation. On the
# undamped scheme (theta = 1/2) a full-FE rod's frame rings with its 3-2-1 reference nodes
# (its rotation rate changes by 0.01-0.05 rad/s a step, mostly about the rod's axis, which one
# end-B ring node fixes), and dM_w^T x_w grows with it: both rods full FE, 2 ms, at 1e-6 1,755
# of the 3,978 body-steps needed a second back-substitution (elastic rows above the frame-only
# limit), at 5e-7 1,151, at 3e-7 none. The refresh's 3 columns are solved with the first
# iterate's right-hand side (BodySolver.refresh_coupling, defer: 4 columns cost 22 ms where 1
# costs 14 and 3 cost 19 on the seed's rods), so the smaller tolerance costs ~8 ms a refresh.
COUPLING_TOL = 3e-7
NODAL_CACHE_MIN_NQ = 200  # from this many elastic coordinates, contact rows use nodal columns
# A later iterate whose residual sits in a body's frame rows only (its elastic rows, constraint
# impulses included, below this fraction of rtol) corrects that body's velocity by
# W^-1 [R_f; 0]: the bordered solve without its back-substitution. Between refreshes of M_wq
# the frame Schur complement follows it to first order (BodySolver.prepare), which leaves such
# residuals rare in contact (seed as shipped: 1,304 of 1,317 contact steps in one iterate)
# but not after the separation at 2 us steps (2-4 iterates, frame rows at ~1e-10).
FRAME_ONLY_FRACTION = 0.5


RESYNC_STEPS = 256  # carried contractions are recomputed from the state this often

# Full-FE bodies take k_hat dq_dot of their checking residual from W_qq dq_dot, known from
# the right-hand sides of the step's solves (_WImages), not from a product with k_hat (4.6 M
# entries, ~5 ms on the seed rods); every this many such residuals the product is made too and
# the two must agree to IMAGE_RTOL of the terms they come from, else the body goes back to
# the product.
IMAGE_CHECK_STEPS = 100
IMAGE_RTOL = 1e-11


@dataclass
class _Carried:
    """L(q) and L(q_dot) (body.carried_contractions: (3, 3, nq), or (3, n) for full FE) of
    the state (q, v) they were made for."""

    q: np.ndarray
    v: np.ndarray
    Lq: np.ndarray
    Lqd: np.ndarray
    Kq: np.ndarray     # k_hat q and k_hat q_dot: the elastic force is linear too
    Kqd: np.ndarray
    Mqd: np.ndarray    # M_qq q_dot (M_qq v_m = M_qq q_dot + theta M_qq dq_dot)
    age: int = 0


@dataclass
class StepResult:
    states: list[BodyState]
    joint_impulses: np.ndarray
    contact: ContactRows
    contact_impulses: np.ndarray
    iterations: int
    joint_drift: float = 0.0   # max |phi| of the joints at the end of the step [m or -]
    converged: bool = True     # False: stopped on the round-off floor above rtol
    residual: float = 0.0      # largest momentum residual at exit, relative to the body's scale
    translation_residual: np.ndarray | None = None  # (3,) sum over bodies of the exit
                                                    # residual's translational rows [N s]
    # (3,) the linear momentum _balance_translation added to the step's solution [N s]:
    # minus the translational residual sum the step converged to, zero when not taken
    momentum_shift: np.ndarray | None = None
    lcp_residual: float = 0.0  # largest complementarity residual of the step's LCP solves


class MoreauJeanIntegrator:
    """The Moreau-Jean theta scheme: `step(t, states, h)`. `order` is its order of accuracy
    for smooth motion: 2 at theta = 1/2 (implicit midpoint), 1 for theta > 1/2 (error
    ~ (theta - 1/2) h); tests/test_theta_scheme.py measures both."""

    def __init__(self, system: System, *, theta: float = DEFAULT_THETA, rtol: float = 1e-10,
                 max_iter: int = 40, exploit_nonrotating: bool = True):
        if not 0.5 <= theta <= 1.0:
            raise SolverError(f"theta must be in [0.5, 1], got {theta!r}")
        self.system = system
        self.theta = theta
        self.solvers = [BodySolver(b, theta) for b in system.bodies]
        self.rtol = rtol
        self.max_iter = max_iter
        self.n_joint_rows = sum(j.n_rows for j in system.joints)
        self.exploit_nonrotating = exploit_nonrotating
        self.order = 2 if theta == 0.5 else 1
        self.n_nonrotating_steps = 0
        # every G2 contraction is linear in q or q_dot: carried along with the states, a step
        # needs one new contraction L(dq_dot) per residual instead of L(q_m), L(q_dot_m) and
        # M_wq(q) (one pass over b1's 22 MB of G2 blocks instead of ~3 on the seed case)
        self._carried: list[_Carried | None] = [None] * len(system.bodies)
        self._pending: list[tuple | None] = [None] * len(system.bodies)
        self._loads: dict[int, list] = {}
        for load in system.loads:
            self._loads.setdefault(load.body, []).append(load)
        self._gravity = np.asarray(system.gravity, dtype=float)
        # bodies whose per-body work goes on threads (full FE: their kernels release the GIL),
        # and the pool, fixed for the integrator's life (read once: not in the step loop)
        sparse = {b for b, body in enumerate(system.bodies) if body.nq and body.is_sparse}
        self._pool = _thread_pool() if len(sparse) >= 2 else None
        self._threaded = sparse if self._pool is not None else set()
        if len(sparse) == 1:
            # one full-FE body: the threads go to its back-substitutions (fe.ldl, two etree
            # halves; the same results on one thread)
            self.solvers[next(iter(sparse))].pool = _thread_pool()
        # a large dense (MVM) body: its G2 contraction, memory-bound, in two halves on two
        # threads (bit for bit; not while several bodies' work holds the pool's threads)
        self._g2_pool = (_thread_pool() if len(sparse) < 2
                         and any(body.contracts_in_halves for body in system.bodies) else None)
        # coordinates without mass (redistributed contact nodes): equilibrium at step ends
        self._massless = [MasslessCoordinates.of(b) for b in system.bodies]
        # bodies whose k_hat dq_dot comes from W_qq dq_dot (full FE, undamped)
        self._images = _WImages({b for b in sparse if system.bodies[b].c_hat is None})
        # relaxation of a step whose iteration stalls (integrate.relaxation)
        self._relax = AitkenRelaxation([float(np.ptp(body.X, axis=0).max()) if len(body.X)
                                        else 1.0 for body in system.bodies])
        for provider in system.contacts:
            sides = (getattr(provider, "slave", None), getattr(provider, "master", None))
            if (getattr(provider, "law", None) is ContactLaw.VELOCITY
                    and any(b is not None and self._massless[b] is not None for b in sides)):
                raise SolverError("massless (mass-redistributed) contact nodes need the position "
                                  "contact law: under the velocity law their velocities flip "
                                  "every step (docs/contact_law.md)")

    # ----------------------------------------------------------------------------------------
    def _residuals(self, t, states, v_plus, h):
        """Momentum residuals without constraint forces, midpoint and end configurations
        (per body, on threads when several bodies are full FE: see _each_body)."""
        out = self._each_body(lambda b: self._residual(b, t, states[b], v_plus[b], h),
                              range(len(states)))
        R, mids, ends, scales = zip(*(out[b] for b in range(len(states))))
        return list(R), list(mids), list(ends), list(scales)

    def _residual(self, b, t, st, vp, h):
        """Body b's residual, its midpoint and end states and its momentum scale."""
        body, g = self.system.bodies[b], self._gravity
        th = self.theta
        vm = th * vp + (1.0 - th) * st.v
        mid = st.advanced(vm, th * h)
        end = st.advanced(vm, h)
        dv = vp - st.v
        if body.nq:
            Lq_m, Lqd_m, Kq_m = self._mid_contractions(b, st, vp, th, h)
            # M is linear: M v_m = M v- + th M dv, and M_qq v- is carried with the state
            mqq_dv = self._pending[b][4]
            mqq_vm = self._carried_at(b, st).Mqd + th * mqq_dv
            inertia, F, momentum = (np.empty(body.nv) for _ in range(3))
            inv, nodal = body.inv, body.nodal
            if nodal is not None:
                momentum_terms_nodal(mid.A, mid.q, dv, vm, Lq_m, Lqd_m, Kq_m, mqq_dv, mqq_vm,
                                     inv.mass, inv.S0, inv.S1, inv.G0, nodal.MsX, nodal.node,
                                     nodal.comp, g, inertia, F, momentum)
            else:
                momentum_terms(mid.A, mid.q, dv, vm, Lq_m, Lqd_m, Kq_m, mqq_dv, mqq_vm,
                               inv.mass, inv.S0, inv.S1, inv.G0, body.G1_array,
                               g, inertia, F, momentum)
            if body.c_hat is not None:
                F[6:] -= _times(body.c_hat, vm[6:])
        else:
            terms = body.inertia_terms(mid.q)
            inertia = body.mass_times(mid.A, mid.q, dv, terms)
            F = body.velocity_forces(mid.A, mid.q, vm, terms)
            if np.any(g):
                F += body.gravity_forces(mid.A, mid.q, g, terms[0])
            momentum = body.mass_times(mid.A, mid.q, vm, terms)
        for load in self._loads.get(b, ()):
            if t + th * h >= load.t_start_s:
                fvec = np.asarray(load.force_n, float)
                fr, qp = body.point_jacobian(load.node, mid.A, mid.q, fvec)
                F[:6] += fr
                F[6:] += qp
        scale = max(np.abs(inertia).max(), h * np.abs(F).max(), np.abs(momentum).max())
        return inertia - h * F, mid, end, scale

    def carried(self, b: int, st: BodyState) -> tuple[np.ndarray, np.ndarray]:
        """(L(q), L(q_dot)) of body b at state st in the body's carried form
        (FlexibleBody.carried_contractions: compact for full-FE bodies): the carried ones if st
        is the state this integrator produced (and they are younger than RESYNC_STEPS), else
        computed."""
        c = self._carried_at(b, st)
        return c.Lq, c.Lqd

    def carried_products(self, b: int, st: BodyState) -> tuple[np.ndarray, np.ndarray]:
        """(k_hat q, M_qq q_dot) of body b at state st, as carried (see carried): the
        energies of an output need no product with k_hat or M_qq."""
        c = self._carried_at(b, st)
        return c.Kq, c.Mqd

    def _carried_at(self, b: int, st: BodyState) -> _Carried:
        c = self._carried[b]
        if c is None or c.q is not st.q or c.v is not st.v or c.age >= RESYNC_STEPS:
            body = self.system.bodies[b]
            qd = st.v[6:]
            c = _Carried(st.q, st.v, body.carried_contractions(st.q, self._g2_pool),
                         body.carried_contractions(qd, self._g2_pool),
                         _times(body.k_hat, st.q), _times(body.k_hat, qd),
                         _times(body.inv.M_qq, qd))
            self._carried[b] = c
        return c

    def _mid_contractions(self, b, st, vp, th, h):
        """L(q_m), L(q_dot_m) and k_hat q_m at the midpoint of the iterate vp: q_dot_m =
        q_dot + th dq_dot and q_m = q + th h q_dot_m, so one contraction L(dq_dot) and one
        k_hat dq_dot per iterate (none on the first, where dq_dot = 0). M_qq = sum_a G2[a][a]
        (bodies.invariants), so M_qq dq_dot is the trace of L(dq_dot): no product with M_qq
        (4.6 M entries for a full-FE rod). Pending for _carry and _residual: (L(dq_dot),
        L(q_dot_m), k_hat dq_dot, k_hat q_dot_m, M_qq dq_dot)."""
        c = self._carried_at(b, st)
        body = self.system.bodies[b]
        dqd = vp[6:] - st.v[6:]
        Lq_m = np.empty(c.Lq.shape)
        if np.any(dqd):
            LD = body.carried_contractions(dqd, self._g2_pool)
            MD = body.contraction_trace(LD)
            KD = self._images.k_dq(b, body, MD, dqd, th * h)
            Lqd_m = np.empty(c.Lqd.shape)
            _midpoint(c.Lq.ravel(), c.Lqd.ravel(), LD.ravel(), th, th * h, Lq_m.ravel(),
                      Lqd_m.ravel())
            Kqd_m = c.Kqd + th * KD
        else:   # the first iterate: q_dot_m = q_dot
            LD = KD = None
            MD = np.zeros(body.nq)
            Lqd_m, Kqd_m = c.Lqd, c.Kqd
            _midpoint(c.Lq.ravel(), c.Lqd.ravel(), None, th, th * h, Lq_m.ravel(), None)
        self._pending[b] = (LD, Lqd_m, KD, Kqd_m, MD)
        return Lq_m, Lqd_m, c.Kq + (th * h) * Kqd_m

    def _carry(self, states, new_states, h):
        """Advance the carried contractions to the accepted step's end states."""
        for b, (st, new) in enumerate(zip(states, new_states)):
            c, p = self._carried[b], self._pending[b]
            self._pending[b] = None
            if c is None or p is None or c.q is not st.q or c.v is not st.v:
                self._carried[b] = None
                continue
            LD, Lqd_m, KD, Kqd_m, MD = p
            Lq = np.empty(c.Lq.shape)
            Lqd = c.Lqd if LD is None else np.empty(c.Lqd.shape)
            _advance(c.Lq.ravel(), c.Lqd.ravel(), None if LD is None else LD.ravel(),
                     Lqd_m.ravel(), h, Lq.ravel(), Lqd.ravel())
            self._carried[b] = _Carried(new.q, new.v, Lq, Lqd, c.Kq + h * Kqd_m,
                                        c.Kqd if KD is None else c.Kqd + KD, c.Mqd + MD,
                                        c.age + 1)

    def _joint_rows(self, t, h, mids, ends):
        if not self.system.joints:
            return np.zeros(0), Rows.empty()
        bodies = self.system.bodies
        phis, parts = [], []
        for joint in self.system.joints:
            _, rows = joint.evaluate(bodies, mids, t + 0.5 * h)
            phi, _ = joint.evaluate(bodies, ends, t + h)
            phis.append(phi)
            parts.append(rows)
        return np.concatenate(phis), stack(parts)

    def _apply_inverse(self, rows: Rows, h: float):
        """Y_b = W_b^-1 Phi_b^T for every body touched by rows: for large bodies with nodal
        rows (joints at nodes or frame points) through the cached nodal columns, else by
        back-substitution."""
        def one(b):
            bf, bq = rows.blocks[b]
            sel = rows.nodal_selector(b)
            if sel is not None and self.system.bodies[b].nq >= NODAL_CACHE_MIN_NQ:
                return self.solvers[b].solve_nodal(h, bf, sel)
            return self.solvers[b].solve(np.hstack([bf, bq]).T)

        return self._each_body(one, rows.blocks)

    def _contact_inverse(self, crows: ContactRows, h: float) -> dict:
        """Per body touched by the contact rows: its D = Phi_b W_b^-1 Phi_b^T (m, m) and its
        velocity correction W_b^-1 Phi_b^T lambda (integrate.compliance). Large bodies with
        nodal rows go through the cached nodal columns of W_qq^-1 (exact; no (nq, m) block),
        others through explicit columns W^-1 Phi^T."""
        def one(b):
            bf, bq = crows.rows.blocks[b]
            solver = self.solvers[b]
            sel = crows.rows.nodal.get(b)
            if sel is None or not bq.shape[1] or self.system.bodies[b].nq < NODAL_CACHE_MIN_NQ:
                Phi = np.hstack([bf, bq])
                return DenseCompliance(Phi, solver.solve(Phi.T))
            return solver.contact_compliance(h, bf, sel)

        return self._each_body(one, crows.rows.blocks)

    # ----------------------------------------------------------------------------------------
    def step(self, t: float, states: list[BodyState], h: float) -> StepResult:
        """One step from t to t + h. Frames that do not rotate (omega = 0, no joints) take the
        linear step of integrate.nonrotating, verified against the rotational rows; any other
        step, or one whose verification fails, the general modified-Newton step."""
        crows, parts = self._candidate_rows(states, h)
        if self.exploit_nonrotating and nonrotating.applies(self.system, states):
            out = nonrotating.nonrotating_step(self.system, self.solvers, self.theta, self.rtol,
                                               self._loads, t, states, h, crows)
            if out is not None:
                self.n_nonrotating_steps += 1
                new_states, lam_c, res_t, lcp_res = out
                self._equilibrate_massless(t, h, states, new_states, crows.rows, lam_c)
                self._after_step(parts, lam_c, h)
                return StepResult(new_states, np.zeros(0), crows, lam_c, 1, 0.0,
                                  translation_residual=res_t, lcp_residual=lcp_res)
        return self._newton_step(t, states, h, crows, parts)

    def _candidate_rows(self, states, h):
        crows = ContactRows.empty()
        parts = []
        for provider in self.system.contacts:
            part = provider.candidate_rows(self.system.bodies, states, h)
            parts.append((provider, part, crows.rows.m))
            crows = _merge_contacts(crows, part)
        return crows, parts

    @staticmethod
    def _after_step(parts, lam_c, h):
        for provider, part, offset in parts:
            provider.after_step(part, lam_c[offset : offset + part.rows.m], h)

    def _newton_step(self, t, states, h, crows, parts) -> StepResult:
        # a refresh of M_wq due at the start is solved with the first iterate's right-hand
        # side (BodySolver.refresh_coupling, defer): the contact columns come after that solve
        self._prepare(states, h, refresh_tol=None, defer=True)
        Cc, Dcc = None, None
        n_j, m_c = self.n_joint_rows, crows.rows.m
        v_plus = [st.v.copy() for st in states]
        v_free = v_plus                       # set by the first iterate
        images = self._images
        images.start(self.system.bodies)
        lam = np.zeros(n_j + m_c)
        last_norm = last_rel = np.inf
        lcp_max = 0.0
        relax = self._relax
        relax.start()
        relaxed = stalled = False
        for it in range(self.max_iter + 1):
            v_before, image_before = v_plus, dict(images.plus)
            R, mids, ends, scales = self._residuals(t, states, v_plus, h)
            phi, jrows = self._joint_rows(t, h, mids, ends)
            Gj = {b: jrows.body_matrix(b) for b in jrows.blocks} if n_j else {}
            res_norm = max(float(np.abs(r).max()) for r in R) if it else np.inf
            refreshed = False
            if it > 0:
                rel, rel_r, res_t, res = self._relative_residual(R, Gj, crows.rows, lam, n_j,
                                                                 scales)
                phi_ok = not (phi.size and np.abs(phi).max() > 1e-12)
                # below ROUNDOFF_FLOOR a residual that stops decreasing (or still there at
                # max_iter) is round-off: accepted, and counted as not converged (StepResult)
                floor = it > 2 and rel < ROUNDOFF_FLOOR and (rel >= 0.5 * last_rel
                                                             or it >= self.max_iter)
                if phi_ok and (rel <= self.rtol or (floor and (rel_r <= TRANSLATION_RTOL
                                                               or it >= self.max_iter))):
                    break
                # Not accepted: a residual over the tolerance only in its translational rows
                # whose balance (below) would bring it within (ff81900 did; after the
                # separation it raised the seed's 2-ms momentum error 5.8e-11 -> 2.1e-10)
                stalled = it >= 2 and rel > ACTIVATE_RATIO * last_rel
                last_rel = rel
            if it == SLOW_ITERATIONS or (it > 1 and res_norm > last_norm):
                self._prepare(mids, h, refresh_tol=0.0)
                refreshed = True
                if m_c:
                    # the contact columns W^-1 Phi^T must be those of the W the free velocity
                    # is solved with: with the old ones the iteration has a fixed point at
                    # R = W_new W_old^-1 Phi^T lambda, a residual that never goes away
                    Cc = self._contact_inverse(crows, h)
                    Dcc = sum((c.D for c in Cc.values()), np.zeros((m_c, m_c)))
            last_norm = res_norm
            if it == self.max_iter:
                raise SolverError(f"Moreau-Jean step at t = {t:.6e} s (h = {h:.3e} s) did "
                                  f"not converge in {self.max_iter} iterations: "
                                  + self._stall_report(res, scales, crows, lam[n_j:], n_j))
            if it > 0 and not refreshed and not relaxed:
                # bodies whose residual is all in the frame rows: v_free of the last iterate
                # minus W^-1 [R_f; 0] (with the constraint impulses of the last iterate in
                # R_f); the others as on the first iterate, v+ - W^-1 R
                v_free = self._correct(R, res, scales, v_free, v_plus)
            else:
                xs = self._solve_each(R)
                v_free = [vp - x for vp, x in zip(v_plus, xs)]
                for b in range(len(states)):
                    images.solved(b, self.solvers[b], R[b], xs[b])
            if Cc is None:
                Cc = self._contact_inverse(crows, h) if m_c else {}
                Dcc = sum((c.D for c in Cc.values()), np.zeros((m_c, m_c)))
            if n_j + m_c == 0:
                v_plus = v_free
                images.plus = dict(images.free)
                v_plus, relaxed = self._relaxed(relax, v_before, v_plus, image_before, stalled)
                continue
            Yj = self._apply_inverse(jrows, h) if n_j else {}
            D = np.zeros((n_j + m_c, n_j + m_c))
            D[n_j:, n_j:] = Dcc
            for b, Yb in Yj.items():
                D[:n_j, :n_j] += Gj[b] @ Yb
                if b in crows.rows.blocks:
                    D[n_j:, :n_j] += crows.rows.body_matrix(b) @ Yb
            D[:n_j, n_j:] = D[n_j:, :n_j].T
            c = np.zeros(n_j + m_c)
            if n_j:
                c[:n_j] = jrows.times(v_free) - jrows.times(v_plus) + phi / (self.theta * h)
            if m_c:
                c[n_j:] = crows.rows.times(v_free) - crows.lower
            lam, lcp_res = solve_contact_impulses(D, c, n_j, crows, lam if it else None)
            lcp_max = max(lcp_max, lcp_res)
            v_plus = list(v_free)
            images.plus = dict(images.free)   # (every update makes new arrays)
            for b, Yb in Yj.items():
                dv = Yb @ lam[:n_j]
                v_plus[b] = v_plus[b] + dv
                images.impulses(b, self.solvers[b], jrows, lam[:n_j], dv)
            for b, cb in Cc.items():
                dv = cb.velocity(lam[n_j:])
                v_plus[b] = v_plus[b] + dv
                images.impulses(b, self.solvers[b], crows.rows, lam[n_j:], dv)
            v_plus, relaxed = self._relaxed(relax, v_before, v_plus, image_before, stalled)
        shift = np.zeros(3)
        if not n_j:
            converged_t = res_t
            rel, res_t = self._balance_translation(self._balanced(res, scales, mids),
                                                   ends, v_plus, h, rel, res_t)
            shift = res_t - converged_t
        self._after_step(parts, lam[n_j:], h)
        new_states = [e for e in ends]
        for st, vp in zip(new_states, v_plus):
            st.v = vp
        self._carry(states, new_states, h)
        self._equilibrate_massless(t, h, states, new_states, crows.rows, lam[n_j:],
                                   jrows if n_j else None, lam[:n_j])
        drift = float(np.abs(phi).max()) if phi.size else 0.0
        return StepResult(new_states, lam[:n_j], crows, lam[n_j:], it, drift,
                          converged=rel <= self.rtol, residual=rel, translation_residual=res_t,
                          lcp_residual=lcp_max, momentum_shift=shift)

    def _stall_report(self, res, scales, crows: ContactRows, lam_c, n_j) -> str:
        """Where a step's iteration stalled, in one line: the body and row of the largest
        relative residual (frame translation / rotation, or elastic coordinate; for a nodal
        basis the mesh node and direction), and the contact pairs of the step's rows
        (contact, slave node, master facet) with their impulses."""
        worst = max(range(len(res)), key=lambda b: float(np.abs(res[b]).max())
                    / max(scales[b], 1e-300))
        body, r = self.system.bodies[worst], res[worst]
        i = int(np.argmax(np.abs(r)))
        rel = float(abs(r[i])) / max(scales[worst], 1e-300)
        if i < 3:
            row = f"frame translation {'xyz'[i]}"
        elif i < 6:
            row = f"frame rotation {'xyz'[i - 3]}"
        else:
            row = f"elastic coordinate {i - 6}"
            node = body.node_of_coordinate(i - 6)
            if node is not None:
                row += f" (node {node[0]} {'xyz'[node[1]]})"
        text = f"largest residual {rel:.2e} (of rtol {self.rtol:.0e}) in body {body.name!r}, {row}"
        m = crows.rows.m
        if m:
            keys = crows.keys
            on = [k for k, x in zip(keys, lam_c) if x > 0.0]
            shown = ", ".join(f"{k[0]} node {k[1]} on facet {k[2]}" if len(k) >= 3 else str(k)
                              for k in (on or keys)[:3])
            text += (f"; {m} contact row(s), {len(on)} carrying impulse ({shown}"
                     + (" ..." if len(on or keys) > 3 else "") + ")")
        if n_j:
            text += f"; {n_j} joint row(s)"
        return text

    def _relaxed(self, relax: AitkenRelaxation, before, after, image_before, stalled):
        """(v_plus, relaxed): the iterate ``after`` = G(``before``), or once the step has
        stalled Aitken's relaxed one before + w (after - before) (integrate.relaxation),
        the W-images of the full-FE bodies relaxed alike (they are linear in v_plus)."""
        w = relax.factor(before, after, stalled)
        if w == 1.0:
            return after, False
        images = self._images
        for b, img in images.plus.items():
            old = image_before.get(b)
            if old is not None:
                images.plus[b] = old + w * (img - old)
        return [a + w * (c - a) for a, c in zip(before, after)], True

    def _equilibrate_massless(self, t, h, states, new_states, crows: Rows, lam_c,
                              jrows: Rows | None = None, lam_j=None) -> None:
        """Massless coordinates (integrate.massless) to equilibrium at the step's end, under
        the step's constraint impulses as forces lambda / h and the point loads, with the
        rows that carried an impulse held; their velocity the step's mean velocity. The
        carried k_hat q and k_hat q_dot follow (the mass-weighted contractions do not see
        massless coordinates)."""
        todo = [b for b, ml in enumerate(self._massless) if ml is not None]
        if not todo:
            return
        held = [(rows, lam, np.flatnonzero(lam != 0.0))
                for rows, lam in ((crows, lam_c), (jrows, lam_j))
                if rows is not None and lam is not None and len(lam)]
        parts = []
        for b in todo:
            ml, body, new = self._massless[b], self.system.bodies[b], new_states[b]
            force = np.zeros(len(ml.s))    # on the massless coordinates only
            Phi = [np.zeros((len(on), len(ml.s))) for _, _, on in held]
            for k, (rows, lam, on) in enumerate(held):
                blk = rows.blocks.get(b)
                if blk is not None:
                    cols = blk[1][:, ml.s]
                    force += cols.T @ lam
                    Phi[k] = cols[on]
            force /= h
            for load in self._loads.get(b, ()):
                if t + self.theta * h >= load.t_start_s:
                    force += body.point_jacobian(load.node, new.A, new.q,
                                                 np.asarray(load.force_n, float))[1][ml.s]
            P = np.vstack(Phi) if Phi else np.zeros((0, len(ml.s)))
            parts.append((ml, new.q, force, P))
        # rows with no massless column in any body impose nothing here
        if parts and parts[0][3].shape[0]:
            keep = np.any(np.hstack([p[3] for p in parts]) != 0.0, axis=1)
            parts = [(ml, q, f, P[keep]) for ml, q, f, P in parts]
        for b, (ml, q, _, _), dq in zip(todo, parts, equilibrate(parts)):
            st, new = states[b], new_states[b]
            q[ml.s] += dq
            qd = new.v[6:]
            v_s = (q[ml.s] - st.q[ml.s]) / h
            dv = v_s - qd[ml.s]
            qd[ml.s] = v_s
            c = self._carried[b]
            if c is not None and c.q is new.q and c.v is new.v:
                c.Kq = c.Kq + ml.K_cols @ dq
                c.Kqd = c.Kqd + ml.K_cols @ dv

    def _each_body(self, fn, bodies) -> dict:
        """{b: fn(b)} for b in bodies. The back-substitutions of sparse (full-FE) bodies
        release the GIL (fe.ldl): with two or more of them, each body's work runs on a thread
        of its own (results as serial: the work of one body touches nothing of another), up
        to $FLEXMVM_THREADS threads (default: the cores; 1: none)."""
        bodies = list(bodies)
        threaded = [b for b in bodies if b in self._threaded]
        if len(threaded) < 2:
            return {b: fn(b) for b in bodies}
        futures = {b: self._pool.submit(fn, b) for b in threaded[1:]}
        done = {b: fn(b) for b in bodies if b not in futures}
        return {b: done[b] if b in done else futures[b].result() for b in bodies}

    def _solve_each(self, R: list[np.ndarray]) -> list[np.ndarray]:
        """W_b^-1 R_b for every body b."""
        x = self._each_body(lambda b: self.solvers[b].solve(R[b]), range(len(R)))
        return [x[b] for b in range(len(R))]

    def _correct(self, R, res, scales, v_free, v_plus) -> list[np.ndarray]:
        """The free velocities of a later iterate. res[b] is body b's residual with the last
        iterate's constraint impulses, R_b - Phi_b^T lambda. With W unchanged since that
        iterate, v_plus_b = v_free_b + W_b^-1 Phi_b^T lambda, so v_plus_b - W_b^-1 R_b =
        v_free_b - W_b^-1 res_b: a body whose elastic rows of res_b are below
        FRAME_ONLY_FRACTION rtol gets v_free_b - W_b^-1 [res_f; 0] (no back-substitution,
        solve_frame), the others v_plus_b - W_b^-1 R_b."""
        frame = [bool(self.system.bodies[b].nq) and np.abs(res[b][6:]).max()
                 <= FRAME_ONLY_FRACTION * self.rtol * max(scales[b], 1e-300)
                 for b in range(len(R))]
        full = [b for b in range(len(R)) if not frame[b]]
        x = self._each_body(lambda b: self.solvers[b].solve(R[b]), full)
        out = []
        for b in range(len(R)):
            if frame[b]:
                x[b] = self.solvers[b].solve_frame(res[b][:6])
                out.append(v_free[b] - x[b])
                self._images.frame_corrected(b, self.solvers[b], x[b])
            else:
                out.append(v_plus[b] - x[b])
                self._images.solved(b, self.solvers[b], R[b], x[b])
        return out

    def _balance_translation(self, balanced, ends, v_plus, h, rel, res_t):
        """Zero the translational rows of an accepted step's residual (no joints).

        The residual is linear in each body's frame velocity r_dot+ with the midpoint mass
        matrix's columns [m I; S~ A^T; S1^T A^T] (bodies.body.mass_times; the forces do not
        depend on r_dot, the contact rows are those of the step's start), so r_dot+ += d with
        d = -res_t / m zeroes the body's translational rows exactly and moves its other rows by
        [S~ A^T d; S1^T A^T d], of the size of m d times a lever (~1e-11 relative where the
        rows were at the tolerance). Taken only if every row stays within rtol. Without it the
        step's linear momentum error is the translational residuals it was accepted with, and
        one-iterate steps leave them with a sign: the short seed case with b1 full FE summed
        them to 5.5e-9 of the momentum over 407 steps (random signs after a second iterate:
        4.9e-10). balanced: _balanced of the accepted residual. Returns the new (relative
        residual, translational residual sum)."""
        new_rel, new_t, moves = balanced
        if new_rel > max(rel, self.rtol):
            return rel, res_t
        for b, d in enumerate(moves):
            v_plus[b] = v_plus[b].copy()
            v_plus[b][:3] += d
            ends[b].r = ends[b].r + (self.theta * h) * d
        return new_rel, new_t

    def _balanced(self, res, scales, mids):
        """(relative residual, translational residual sum, per-body r_dot moves d) of the
        residuals res once their translational rows are balanced (_balance_translation)."""
        new_rel, new_t, moves = 0.0, np.zeros(3), []
        for b, (r, mid) in enumerate(zip(res, mids)):
            body = self.system.bodies[b]
            d = -r[:3] / body.inv.mass
            Ad = mid.A.T @ d
            r = r.copy()
            r[:3] += body.inv.mass * d
            r[3:6] += skew(body.first_moment(mid.q)) @ Ad
            if body.nq:
                r[6:] += body.inv.S1.T @ Ad
            new_rel = max(new_rel, float(np.abs(r).max()) / max(scales[b], 1e-300))
            new_t += r[:3]
            moves.append(d)
        return new_rel, new_t, moves

    def _prepare(self, states, h, refresh_tol, defer=False):
        """Frame blocks of W at `states`; M_wq refreshed when it drifted (always for small
        bases, by COUPLING_TOL for large ones, unconditionally when refresh_tol = 0); defer:
        with the next solve (BodySolver.refresh_coupling)."""
        self._each_body(lambda b: self._prepare_body(b, states[b], h, refresh_tol, defer),
                        range(len(states)))

    def _prepare_body(self, b, st, h, refresh_tol, defer=False):
        body, solver = self.system.bodies[b], self.solvers[b]
        # an iteration matrix: M_wq exact (thin rods' frame Schur complement depends on
        # it), J exact where it is cheap (below), else to first order in q (its quadratic
        # part is (|u|/L)^2 of it)
        if body.nq:
            tol = refresh_tol if refresh_tol is not None else (
                0.0 if body.nq <= SMALL_BASIS else COUPLING_TOL)
            c = self._carried[b]
            Lq = c.Lq if (c is not None and c.q is st.q) else None
            solver.refresh_coupling(h, body.rotational_coupling(st.q, Lq), tol, defer)
        if body.nodal is not None:
            # a nodal (full-FE) body: its frame Schur complement is the inertia near the 3-2-1
            # nodes only (~1e-5 of the body), of the size of J's quadratic part q^T G2 q once
            # the body vibrates, so the first-order J leaves the iteration with a factor
            # near -1 (a free tet10 beam struck at mid-span stalled in its frame rows, at every
            # h); its exact J costs O(nodes) from the compact contraction
            c = self._carried[b]
            Lc = c.Lq if (c is not None and c.q is st.q) else body.carried_contractions(st.q)
            J = body.inertia_terms(st.q, Lc)[1]
        elif body.nq and self._carried[b] is not None and self._carried[b].q is st.q:
            # a reduced body whose q is carried: its exact J costs O(9 nq) (a reduced arm
            # swung into a stop lost the positive definiteness of its joint rows' D with the
            # first-order J after the rebound)
            J = body.inertia_terms(st.q, self._carried[b].Lq)[1]
        else:
            J = body.frame_inertia_first_order(st.q)
        solver.prepare(h, st.A, body.frame_mass(st.A, body.first_moment(st.q), J))

    def _relative_residual(self, R, Gj, crows: Rows, lam, n_j, scales) -> tuple:
        """Largest momentum residual (constraint impulses included) relative to each body's
        momentum scale (the largest of its inertia, force, momentum and constraint impulse
        terms); the same for the translational rows alone; the sum over bodies of
        the translational rows [N s] (the step's linear-momentum error: internal and constraint
        forces cancel between bodies); and per body its residual with the constraint impulses."""
        worst, worst_r = 0.0, 0.0
        res_t = np.zeros(3)
        residuals = []
        for b, (r, sc) in enumerate(zip(R, scales)):
            res = r
            # the scale includes the constraint impulses on the body: a body held still by a
            # joint (a grounded wall) balances them alone, with no momentum of its own
            if b in Gj:
                imp = Gj[b].T @ lam[:n_j]
                res = res - imp
                sc = max(sc, float(np.abs(imp).max()))
            if b in crows.blocks:
                imp = _transpose_times(crows, b, self.system.bodies[b], lam[n_j:])
                res = res - imp
                sc = max(sc, float(np.abs(imp).max()))
            worst = max(worst, float(np.abs(res).max()) / max(sc, 1e-300))
            worst_r = max(worst_r, float(np.abs(res[:3]).max()) / max(sc, 1e-300))
            res_t += res[:3]
            residuals.append(res)
        return worst, worst_r, res_t, residuals


@numba.njit(cache=True, nogil=True)
def _midpoint(Lq, Lqd, LD, th, th_h, Lq_m, Lqd_m):  # pragma: no cover - compiled
    """Lqd_m = Lqd + th LD and Lq_m = Lq + th_h Lqd_m in one pass over the (flattened)
    contractions (as numpy's two-step expressions, bit for bit); LD None: Lq_m = Lq + th_h
    Lqd (Lqd_m not written)."""
    if LD is None:
        for i in range(Lq.shape[0]):
            Lq_m[i] = Lq[i] + th_h * Lqd[i]
        return
    for i in range(Lq.shape[0]):
        x = Lqd[i] + th * LD[i]
        Lqd_m[i] = x
        Lq_m[i] = Lq[i] + th_h * x


@numba.njit(cache=True, nogil=True)
def _advance(Lq, Lqd, LD, Lqd_m, h, Lq_new, Lqd_new):  # pragma: no cover - compiled
    """The carried contractions at the step's end in one pass: Lq_new = Lq + h Lqd_m,
    Lqd_new = Lqd + LD (LD None: Lqd_new is Lqd itself, not written)."""
    for i in range(Lq.shape[0]):
        Lq_new[i] = Lq[i] + h * Lqd_m[i]
    if LD is not None:
        for i in range(Lq.shape[0]):
            Lqd_new[i] = Lqd[i] + LD[i]


class _WImages:
    """W_qq dq_dot of the current iterate of each full-FE body, from the right-hand sides of
    the step's solves, for k_hat dq_dot without a product with k_hat.

    Every velocity increment x = W^-1 b of a step (the free velocity's -W^-1 R, a frame-only
    correction W^-1 [R_f; 0], a constraint impulse's W^-1 Phi^T lambda) has
    W_qq x_q = b_q - B^T x_f (BodySolver.coupling_transpose), so W_qq dq_dot of the iterate is
    a sum of known vectors; with M_qq dq_dot (the trace of the contraction L(dq_dot)) and
    W_qq = M_qq + (theta h)^2 k_hat (undamped bodies):
    k_hat dq_dot = (W_qq dq_dot - M_qq dq_dot) / (theta h)^2. In the residual it appears times
    (theta h)^2, so the subtraction costs round-off of M_qq dq_dot only, the size of the inertia
    term's own (and of the summed terms: constraint impulses, frame coupling). Every
    IMAGE_CHECK_STEPS checks the product is made as well; a body where the two disagree by
    more than IMAGE_RTOL of the largest term (a missed increment: a bug) goes back to the
    product (n_fallbacks counts them). Every method ignores bodies not (or no longer) in
    `bodies`."""

    def __init__(self, bodies: set[int]):
        self.bodies = set(bodies)
        self.plus: dict[int, np.ndarray] = {}    # image of v_plus - v of the iterate
        self.free: dict[int, np.ndarray] = {}    # image of v_free - v
        self.size: dict[int, float] = {}         # largest entry of the terms summed (check)
        self._countdown = dict.fromkeys(bodies, 0)
        self.n_fallbacks = 0

    def start(self, bodies) -> None:
        """A new step: v_plus = v."""
        self.plus = {b: np.zeros(bodies[b].nq) for b in self.bodies}
        self.free = {}
        self.size = dict.fromkeys(self.bodies, 0.0)

    def _term(self, b: int, *terms: np.ndarray) -> None:
        self.size[b] = max(self.size[b], *(float(np.abs(t).max(initial=0.0)) for t in terms))

    def solved(self, b: int, solver, R_b: np.ndarray, x: np.ndarray) -> None:
        """v_free = v_plus - x with x = W^-1 R_b."""
        if b not in self.bodies:
            return
        bt = solver.coupling_transpose(x[:6])
        self._term(b, R_b[6:], bt)
        self.free[b] = self.plus[b] - (R_b[6:] - bt)

    def frame_corrected(self, b: int, solver, x: np.ndarray) -> None:
        """v_free -= x with x = W^-1 [R_f; 0]."""
        if b not in self.bodies:
            return
        bt = solver.coupling_transpose(x[:6])
        self._term(b, bt)
        self.free[b] = self.free[b] + bt

    def impulses(self, b: int, solver, rows: Rows, lam: np.ndarray, dv: np.ndarray) -> None:
        """v_plus += dv with dv = W^-1 Phi^T lam (Phi: body b's part of rows)."""
        if b not in self.bodies:
            return
        phi_t_lam = _transpose_times(rows, b, solver.body, lam)[6:]
        bt = solver.coupling_transpose(dv[:6])
        self._term(b, phi_t_lam, bt)
        self.plus[b] = self.plus[b] + (phi_t_lam - bt)

    def k_dq(self, b: int, body, mqq: np.ndarray, dqd: np.ndarray, th_h: float
             ) -> np.ndarray:
        """k_hat dq_dot of body b's iterate (mqq = M_qq dq_dot)."""
        if b not in self.bodies:
            return _times(body.k_hat, dqd)
        wq = self.plus[b]
        KD = (wq - mqq) / (th_h * th_h)
        self._countdown[b] -= 1
        if self._countdown[b] <= 0:
            self._countdown[b] = IMAGE_CHECK_STEPS
            exact = _times(body.k_hat, dqd)
            scale = max(self.size[b], float(np.abs(mqq).max()), 1e-300)
            if float(np.abs(KD - exact).max()) * th_h * th_h > IMAGE_RTOL * scale:
                self.bodies.discard(b)
                self.n_fallbacks += 1
                return exact
        return KD


def _transpose_times(rows: Rows, b: int, body, lam: np.ndarray) -> np.ndarray:
    """Phi_b^T lam (6 + nq,) for body b's part Phi_b = [bf, bq] of rows: with a nodal
    selector N and a sparse basis (full FE) bq^T lam = psi^T (N^T lam), a few nodes' worth,
    instead of a product with the dense (m, nq) block."""
    bf, bq = rows.blocks[b]
    sel = rows.nodal_selector(b) if body.is_sparse else None
    if sel is None:
        elastic = bq.T @ lam
    elif body.nodal is not None:
        # psi selects DOFs: psi^T y = y at each coordinate's DOF; N^T lam summed entry by
        # entry in row order (as the transposed product does) from N's CSR arrays (a
        # NodalSelector's or a csr matrix's), no transposed matrices made
        nt_lam = np.bincount(sel.indices, weights=sel.data * np.repeat(lam, np.diff(sel.indptr)),
                             minlength=sel.shape[1])
        elastic = nt_lam[body.nodal.dof]
    else:
        elastic = np.asarray(body.psi.T @ (sel.tocsr().T @ lam)).ravel()
    return np.concatenate([bf.T @ lam, elastic])


_POOL: tuple[int, ThreadPoolExecutor] | None = None   # (threads, pool)


def _thread_pool() -> ThreadPoolExecutor | None:
    """One pool for the process (studies make many integrators), or None for one thread."""
    global _POOL
    n = worker_threads()   # FLEXMVM_THREADS (flexmvm.threads)
    if n < 2:
        return None
    if _POOL is None or _POOL[0] != n:
        _POOL = (n, ThreadPoolExecutor(max_workers=n, thread_name_prefix="flexmvm-body"))
    return _POOL[1]


def _times(matrix, x: np.ndarray) -> np.ndarray:
    """matrix @ x as a flat (n,) array, for dense or sparse matrices."""
    return np.asarray(matrix @ x).ravel()


def _merge_contacts(a: ContactRows, b: ContactRows) -> ContactRows:
    if a.rows.m == 0:
        return b
    if b.rows.m == 0:
        return a
    if a.n_eq or b.n_eq:
        raise SolverError("several bonded contact definitions are not supported in one system")
    wa = a.normal_weight if a.normal_weight is not None else np.ones(a.rows.m)
    wb = b.normal_weight if b.normal_weight is not None else np.ones(b.rows.m)
    friction = None
    if a.friction is not None or b.friction is not None:
        parts = [f for f in (a.friction, b.friction.shifted(a.rows.m) if b.friction else None)
                 if f is not None]
        friction = FrictionRows(*(np.concatenate([getattr(f, k) for f in parts])
                                  for k in ("normal", "tangent", "mu", "directions")))
    return ContactRows(stack([a.rows, b.rows]), np.concatenate([a.lower, b.lower]),
                       a.keys + b.keys, np.concatenate([a.gaps, b.gaps]), 0,
                       np.concatenate([wa, wb]), friction)
