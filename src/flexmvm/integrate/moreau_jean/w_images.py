"""W_qq dq_dot of a full-FE body's iterate from the right-hand sides of the step's solves,
for k_hat dq_dot without a product with k_hat (4.6 M entries for a full-FE rod of the seed
case; docs/performance.md).

Every velocity increment x = W^-1 b of a step (the free velocity's -W^-1 R, a frame-only
correction W^-1 [R_f; 0], a constraint impulse's W^-1 Phi^T lambda) has
W_qq x_q = b_q - B^T x_f (BodySolver.coupling_transpose), so W_qq dq_dot of the iterate is a
sum of known vectors; with M_qq dq_dot (the trace of the contraction L(dq_dot)) and
W_qq = M_qq + (theta h)^2 k_hat (undamped bodies):
k_hat dq_dot = (W_qq dq_dot - M_qq dq_dot) / (theta h)^2. In the residual it appears times
(theta h)^2, so the subtraction costs round-off of M_qq dq_dot only, the size of the inertia
term's own (and of the summed terms: constraint impulses, frame coupling).
"""

from __future__ import annotations

import numpy as np

from flexmvm.constraints.rows import Rows
from flexmvm.integrate.row_products import body_impulse, flat_product

# Every this many images of a body the product with k_hat is made too, and the two must agree
# to IMAGE_RTOL of the terms they come from, else the body goes back to the product.
IMAGE_CHECK_STEPS = 100
IMAGE_RTOL = 1e-11


class WImages:
    """W_qq dq_dot of the current iterate of each body in ``bodies`` (module doc). Every
    IMAGE_CHECK_STEPS the product is made as well; a body where the two disagree by more than
    IMAGE_RTOL of the largest term (a missed increment: a bug) goes back to the product
    (n_fallbacks counts them). Every method ignores bodies not (or no longer) in `bodies`."""

    def __init__(self, bodies: set[int]):
        self.bodies = set(bodies)
        self.plus: dict[int, np.ndarray] = {}  # image of v_plus - v of the iterate
        self.free: dict[int, np.ndarray] = {}  # image of v_free - v
        self.size: dict[int, float] = {}  # largest entry of the terms summed (check)
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
        phi_t_lam = body_impulse(rows, b, solver.body, lam)[6:]
        bt = solver.coupling_transpose(dv[:6])
        self._term(b, phi_t_lam, bt)
        self.plus[b] = self.plus[b] + (phi_t_lam - bt)

    def k_dq(self, b: int, body, mqq: np.ndarray, dqd: np.ndarray, th_h: float) -> np.ndarray:
        """k_hat dq_dot of body b's iterate (mqq = M_qq dq_dot, th_h = theta h)."""
        if b not in self.bodies:
            return flat_product(body.k_hat, dqd)
        wq = self.plus[b]
        KD = (wq - mqq) / (th_h * th_h)
        self._countdown[b] -= 1
        if self._countdown[b] <= 0:
            self._countdown[b] = IMAGE_CHECK_STEPS
            exact = flat_product(body.k_hat, dqd)
            scale = max(self.size[b], float(np.abs(mqq).max()), 1e-300)
            if float(np.abs(KD - exact).max()) * th_h * th_h > IMAGE_RTOL * scale:
                self.bodies.discard(b)
                self.n_fallbacks += 1
                return exact
        return KD
