"""The step's per-body iteration matrices W (body_solver): when their frame coupling is
refreshed, and the solves the modified Newton iteration makes with them.

The frame Schur complement S = M_ff - B W_qq^-1 B^T is small when the basis nearly spans the
rigid motions (full FE: S ~ the mass within c h of the reference nodes, ~1e-5 of the body),
so W's coupling B must be that of the current configuration: it is refreshed at the start of
a step when it drifted (3 back-substitutions; every step for small bases, by COUPLING_TOL for
large ones; in between S follows it to first order, BodySolver.prepare) and again at the
midpoint when an iteration does not reduce the residual (moreau_jean/scheme.py). The measurements
behind COUPLING_TOL and FRAME_ONLY_FRACTION are in docs/performance.md.
"""

from __future__ import annotations

import numpy as np

from flexmvm.constraints.contact import ContactRows
from flexmvm.constraints.rows import Rows
from flexmvm.integrate.moreau_jean.compliance import DenseCompliance

SMALL_BASIS = 400  # up to this many elastic coordinates: refresh every step (cheap)
# Larger bases: refresh when M_wq moved by this much (relative). The bordered solve uses the
# M_wq of the last refresh and S follows the drift to first order only, so a drift leaves the
# first solve's frame rows off by ~the drift times the rotational coupling, and its elastic
# rows by dM_w^T x_w; on the undamped scheme a full-FE rod's frame rings with its 3-2-1
# reference nodes and dM_w^T x_w grows with it: this tolerance keeps those steps at one
# back-substitution, for ~8 ms a refresh on the seed's rods (docs/performance.md).
COUPLING_TOL = 3e-7
NODAL_CACHE_MIN_NQ = 200  # from this many elastic coordinates, contact rows use nodal columns
# A later iterate whose residual sits in a body's frame rows only (its elastic rows, constraint
# impulses included, below this fraction of rtol) corrects that body's velocity by
# W^-1 [R_f; 0]: the bordered solve without its back-substitution.
FRAME_ONLY_FRACTION = 0.5


class IterationMatrices:
    """W of every body of a step (module doc): solvers (BodySolver per body), threads
    (BodyThreads), carried (CarriedState: its L(q) gives the exact frame inertia J cheaply),
    images (WImages, kept up to date with every solve)."""

    def __init__(self, bodies, solvers, threads, carried, images):
        self.bodies, self.solvers = bodies, solvers
        self.threads, self.carried, self.images = threads, carried, images

    def prepare(self, states, h: float, refresh_tol: float | None, defer: bool = False) -> None:
        """Frame blocks of W at `states`; M_wq refreshed when it drifted (always for small
        bases, by COUPLING_TOL for large ones, unconditionally when refresh_tol = 0); defer:
        with the next solve (BodySolver.refresh_coupling)."""
        self.threads.each(
            lambda b: self._prepare_body(b, states[b], h, refresh_tol, defer), range(len(states))
        )

    def _prepare_body(self, b, st, h, refresh_tol, defer=False):
        body, solver = self.bodies[b], self.solvers[b]
        if body.stiffening is not None:  # W's stiffening at this spin (BodySolver.use_spin)
            solver.use_spin(body.stiffening.scale(st.v[3:6]))
        if not body.nq:
            solver.prepare(
                h,
                st.A,
                body.frame_mass(
                    st.A, body.first_moment(st.q), body.frame_inertia_first_order(st.q)
                ),
            )
            return
        # W's frame block is the mass matrix of ONE configuration: J(q) and M_wq(q) from the
        # same contraction L(q) (the carried one, else made here: O(nodes) for full FE,
        # 9 nq^2 for a dense basis, only where nothing is carried: the first step and the
        # midpoint refresh of a slow iteration). The frame Schur complement
        # S = J - M_wq W_qq^-1 M_wq^T is what the basis cannot absorb of the frame's motion:
        # ~1e-5 of the body for full FE (the inertia near the 3-2-1 nodes), and as small for a
        # reduced body whose modes hold the quasi-rigid motions of a 3-2-1 support on soft
        # point nodes (a Craig-Bampton arm referenced at its hub: 2.5e-10 to 3e-9 kg m^2
        # against J = 4.9e-3). A J without its quadratic part q^T G2 q (relative size
        # (|u|/L)^2) is of that size once the body vibrates: a free full-FE beam struck at
        # mid-span stalled in its frame rows (a factor near -1 per iterate), and beside an
        # exact M_wq the reduced arm's S went indefinite, and the joint rows' D = Phi W^-1
        # Phi^T with it (docs/notes/2026-11-27-arm-stop.md).
        c = self.carried.of_configuration(b, st)
        Lq = c.Lq if c is not None else body.carried_contractions(st.q)
        tol = (
            refresh_tol
            if refresh_tol is not None
            else (0.0 if body.nq <= SMALL_BASIS else COUPLING_TOL)
        )
        solver.refresh_coupling(h, body.rotational_coupling(st.q, Lq), tol, defer)
        J = body.inertia_terms(st.q, Lq)[1]
        solver.prepare(h, st.A, body.frame_mass(st.A, body.first_moment(st.q), J))

    def joint_columns(self, rows: Rows, h: float) -> dict:
        """Y_b = W_b^-1 Phi_b^T for every body touched by rows: for large bodies with nodal
        rows (joints at nodes or frame points) through the cached nodal columns, else by
        back-substitution."""

        def one(b):
            bf, bq = rows.blocks[b]
            sel = rows.nodal_selector(b)
            if sel is not None and self.bodies[b].nq >= NODAL_CACHE_MIN_NQ:
                return self.solvers[b].solve_nodal(h, bf, sel)
            return self.solvers[b].solve(np.hstack([bf, bq]).T)

        return self.threads.each(one, rows.blocks)

    def contact_compliance(self, crows: ContactRows, h: float) -> dict:
        """Per body touched by the contact rows: its D = Phi_b W_b^-1 Phi_b^T (m, m) and its
        velocity correction W_b^-1 Phi_b^T lambda (integrate.moreau_jean.compliance). Large bodies
        with nodal rows go through the cached nodal columns of W_qq^-1 (exact; no (nq, m) block),
        others through explicit columns W^-1 Phi^T."""

        def one(b):
            bf, bq = crows.rows.blocks[b]
            solver = self.solvers[b]
            sel = crows.rows.nodal.get(b)
            if sel is None or not bq.shape[1] or self.bodies[b].nq < NODAL_CACHE_MIN_NQ:
                Phi = np.hstack([bf, bq])
                return DenseCompliance(Phi, solver.solve(Phi.T))
            return solver.contact_compliance(h, bf, sel)

        return self.threads.each(one, crows.rows.blocks)

    def free_velocities(self, R, v_plus) -> list[np.ndarray]:
        """v_plus_b - W_b^-1 R_b for every body b (images updated)."""
        x = self.threads.each(lambda b: self.solvers[b].solve(R[b]), range(len(R)))
        for b in range(len(R)):
            self.images.solved(b, self.solvers[b], R[b], x[b])
        return [v_plus[b] - x[b] for b in range(len(R))]

    def corrected_free_velocities(
        self, R, res, scales, v_free, v_plus, rtol: float
    ) -> list[np.ndarray]:
        """The free velocities of a later iterate. res[b] is body b's residual with the last
        iterate's constraint impulses, R_b - Phi_b^T lambda. With W unchanged since that
        iterate, v_plus_b = v_free_b + W_b^-1 Phi_b^T lambda, so v_plus_b - W_b^-1 R_b =
        v_free_b - W_b^-1 res_b: a body whose elastic rows of res_b are below
        FRAME_ONLY_FRACTION rtol gets v_free_b - W_b^-1 [res_f; 0] (no back-substitution,
        solve_frame), the others v_plus_b - W_b^-1 R_b."""
        frame = [
            bool(self.bodies[b].nq)
            and np.abs(res[b][6:]).max() <= FRAME_ONLY_FRACTION * rtol * max(scales[b], 1e-300)
            for b in range(len(R))
        ]
        full = [b for b in range(len(R)) if not frame[b]]
        x = self.threads.each(lambda b: self.solvers[b].solve(R[b]), full)
        out = []
        for b in range(len(R)):
            if frame[b]:
                x[b] = self.solvers[b].solve_frame(res[b][:6])
                out.append(v_free[b] - x[b])
                self.images.frame_corrected(b, self.solvers[b], x[b])
            else:
                out.append(v_plus[b] - x[b])
                self.images.solved(b, self.solvers[b], R[b], x[b])
        return out
