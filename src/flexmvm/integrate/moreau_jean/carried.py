"""Contractions carried along with the states: every G2 contraction of a body is linear in q
or q_dot, so a step needs one new contraction L(dq_dot) per residual instead of L(q_m),
L(q_dot_m) and M_wq(q) (one pass over the G2 blocks of a full-FE rod instead of ~3;
docs/performance.md).

With the Moreau-Jean midpoint (moreau_jean/scheme.py) q_dot_m = q_dot + theta dq_dot and
q_m = q + theta h q_dot_m, so

    L(q_dot_m) = L(q_dot) + theta L(dq_dot),     L(q_m) = L(q) + theta h L(q_dot_m),
    L(q(t + h)) = L(q) + h L(q_dot_m),           L(q_dot(t + h)) = L(q_dot) + L(dq_dot),

and the same for k_hat q, k_hat q_dot and M_qq q_dot. M_qq = sum_a G2[a][a]
(bodies.invariants), so M_qq dq_dot is the trace of L(dq_dot): no product with M_qq either.
The carried values are recomputed from the state every RESYNC_STEPS steps (round-off).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from flexmvm.errors import SolverError
from flexmvm.integrate.row_products import flat_product
from flexmvm.integrate.state import BodyState

RESYNC_STEPS = 256  # carried contractions are recomputed from the state this often


@dataclass
class CarriedContractions:
    """L(q) and L(q_dot) (body.carried_contractions: (3, 3, nq), or (3, n) for full FE) of
    the state (q, v) they were made for, with k_hat q, k_hat q_dot and M_qq q_dot."""

    q: np.ndarray
    v: np.ndarray
    Lq: np.ndarray
    Lqd: np.ndarray
    Kq: np.ndarray  # k_hat q and k_hat q_dot: the elastic force is linear too
    Kqd: np.ndarray
    Mqd: np.ndarray  # M_qq q_dot (M_qq v_m = M_qq q_dot + theta M_qq dq_dot)
    age: int = 0


@dataclass
class MidpointTerms:
    """What an iterate's residual made at its midpoint and the step's end needs again:
    L(dq_dot), L(q_dot_m), k_hat dq_dot, k_hat q_dot_m, M_qq dq_dot (None: dq_dot = 0)."""

    L_dqd: np.ndarray | None
    L_qd_mid: np.ndarray
    K_dqd: np.ndarray | None
    K_qd_mid: np.ndarray
    M_dqd: np.ndarray


class CarriedState:
    """The carried contractions of every body of a system (module doc). images: the W-images
    k_hat dq_dot is taken from (integrate.moreau_jean.w_images); pool: the G2 contraction's
    threads."""

    def __init__(self, bodies, images, pool=None):
        self.bodies = bodies
        self.images = images
        self.pool = pool
        self._carried: list[CarriedContractions | None] = [None] * len(bodies)
        self._midpoint: list[MidpointTerms | None] = [None] * len(bodies)

    def at(self, b: int, st: BodyState) -> CarriedContractions:
        """Body b's carried contractions at st: the carried ones if st is the state they were
        made for (and younger than RESYNC_STEPS), else computed."""
        c = self._carried[b]
        if c is None or c.q is not st.q or c.v is not st.v or c.age >= RESYNC_STEPS:
            body, pool = self.bodies[b], self.pool
            qd = st.v[6:]
            c = CarriedContractions(
                st.q,
                st.v,
                body.carried_contractions(st.q, pool),
                body.carried_contractions(qd, pool),
                flat_product(body.k_hat, st.q),
                flat_product(body.k_hat, qd),
                flat_product(body.inv.M_qq, qd),
            )
            self._carried[b] = c
        return c

    def of_configuration(self, b: int, st: BodyState) -> CarriedContractions | None:
        """The carried contractions whose q is st's (any velocity), or None."""
        c = self._carried[b]
        return c if (c is not None and c.q is st.q) else None

    def of_state(self, b: int, st: BodyState) -> CarriedContractions | None:
        """The carried contractions made for st itself (q and v), or None."""
        c = self._carried[b]
        return c if (c is not None and c.q is st.q and c.v is st.v) else None

    def mass_increment(self, b: int) -> np.ndarray:
        """M_qq dq_dot of body b's last midpoint (midpoint())."""
        p = self._midpoint[b]
        if p is None:
            raise SolverError(f"body {b}: mass_increment asked before its midpoint()")
        return p.M_dqd

    def set_midpoint(self, b: int, terms: MidpointTerms) -> None:
        """Body b's midpoint terms as an iterate's residual made them elsewhere
        (integrate.moreau_jean.fused_newton: what midpoint() would have kept)."""
        self._midpoint[b] = terms

    def midpoint(self, b: int, st: BodyState, vp: np.ndarray, th: float, h: float):
        """L(q_m), L(q_dot_m) and k_hat q_m at the midpoint of the iterate vp: one contraction
        L(dq_dot) and one k_hat dq_dot per iterate (none on the first, where dq_dot = 0)."""
        c = self.at(b, st)
        body = self.bodies[b]
        dqd = vp[6:] - st.v[6:]
        Lq_m = np.empty(c.Lq.shape)
        if np.any(dqd):
            LD = body.carried_contractions(dqd, self.pool)
            MD = body.contraction_trace(LD)
            KD = self.images.k_dq(b, body, MD, dqd, th * h)
            Lqd_m = np.empty(c.Lqd.shape)
            _midpoint(
                c.Lq.ravel(), c.Lqd.ravel(), LD.ravel(), th, th * h, Lq_m.ravel(), Lqd_m.ravel()
            )
            Kqd_m = c.Kqd + th * KD
        else:  # the first iterate: q_dot_m = q_dot
            LD = KD = None
            MD = np.zeros(body.nq)
            Lqd_m, Kqd_m = c.Lqd, c.Kqd
            _midpoint(c.Lq.ravel(), c.Lqd.ravel(), None, th, th * h, Lq_m.ravel(), None)
        self._midpoint[b] = MidpointTerms(LD, Lqd_m, KD, Kqd_m, MD)
        return Lq_m, Lqd_m, c.Kq + (th * h) * Kqd_m

    def advance(self, states, new_states, h: float) -> None:
        """Advance the carried contractions to the accepted step's end states."""
        for b, (st, new) in enumerate(zip(states, new_states)):
            c, p = self._carried[b], self._midpoint[b]
            self._midpoint[b] = None
            if c is None or p is None or c.q is not st.q or c.v is not st.v:
                self._carried[b] = None
                continue
            Lq = np.empty(c.Lq.shape)
            Lqd = c.Lqd if p.L_dqd is None else np.empty(c.Lqd.shape)
            _advance(
                c.Lq.ravel(),
                c.Lqd.ravel(),
                None if p.L_dqd is None else p.L_dqd.ravel(),
                p.L_qd_mid.ravel(),
                h,
                Lq.ravel(),
                Lqd.ravel(),
            )
            self._carried[b] = CarriedContractions(
                new.q,
                new.v,
                Lq,
                Lqd,
                c.Kq + h * p.K_qd_mid,
                c.Kqd if p.K_dqd is None else c.Kqd + p.K_dqd,
                c.Mqd + p.M_dqd,
                c.age + 1,
            )


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
