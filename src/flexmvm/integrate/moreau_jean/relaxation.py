"""Aitken's dynamic relaxation of the step's fixed-point iteration (Irons and Tuck 1969;
Kuettler and Wall 2008, "Fixed-point fluid-structure interaction solvers with dynamic
relaxation", Comput. Mech. 43).

The Moreau-Jean step iterates v+ <- G(v+) with a modified-Newton matrix W (body_solver): the
frame blocks leave out the velocity derivatives of the quadratic-velocity forces (gyroscopic
and Coriolis terms, relative size theta h |omega|). For a reduced body that is nothing; for a
full-FE body, whose floating frame is nearly redundant with its nodal coordinates (the frame
Schur complement is the mass near the 3-2-1 nodes, ~1e-5 of the body), it is not: a free
beam struck at mid-span whose reference nodes spin its frame at 2 rad/s iterates with a
contraction factor of -1.02 in its translational rows (measured), an oscillation that never
converges. Aitken's relaxation x_{k+1} = x_k + w_k r_k, r_k = G(x_k) - x_k, with

    w_k = -w_{k-1} r_{k-1}^T (r_k - r_{k-1}) / |r_k - r_{k-1}|^2

removes one dominant mode of the iteration error exactly (for a linear map with factor rho it
gives w = 1 / (1 - rho): 0.5 for the oscillation above) and adapts as the mode changes. It is
switched on only once a step's iteration stops contracting (ACTIVATE_RATIO), so steps that
converge as before take bit for bit the same iterates.

Velocities of different kinds are weighed to one unit: a body's angular velocity components
times its size (its node cloud's extent) become m/s, like the translational and nodal rates.
"""

from __future__ import annotations

import numpy as np

#: A step switches relaxation on once its relative residual falls by less than this factor
#: from one iterate to the next (a modified Newton iteration that converges normally falls by
#: 1e-2..1e-6 per iterate).
ACTIVATE_RATIO = 0.5
#: Bounds of the relaxation factor (an oscillation with factor rho = -1 wants 0.5; a slowly
#: converging mode rho = 0.9 wants 10, capped here).
OMEGA_MIN, OMEGA_MAX = 0.02, 4.0


class AitkenRelaxation:
    """Relaxation factors of one step's iterates (module doc). ``sizes``: per body, the length
    [m] that turns its angular velocity into m/s."""

    def __init__(self, sizes: list[float]):
        self.sizes = [float(s) for s in sizes]
        self.start()

    def start(self) -> None:
        """A new step: relaxation off, no history."""
        self.active = False
        self.omega = 1.0
        self._prev: np.ndarray | None = None
        self.n_relaxed = 0

    def _weighted(self, old: list[np.ndarray], new: list[np.ndarray]) -> np.ndarray:
        parts = []
        for size, a, b in zip(self.sizes, old, new):
            d = b - a
            if d.size >= 6:
                d = d.copy()
                d[3:6] *= size
            parts.append(d)
        return np.concatenate(parts) if parts else np.zeros(0)

    def factor(self, old: list[np.ndarray], new: list[np.ndarray], stalled: bool) -> float:
        """The factor w to take from ``old`` toward ``new`` (G(old)): 1 while the step
        converges normally; once ``stalled`` (the caller's test of ACTIVATE_RATIO) Aitken's
        w from this and the last increment."""
        r = self._weighted(old, new)
        prev, self._prev = self._prev, r
        if not (self.active or stalled) or prev is None:
            return 1.0
        self.active = True
        d = r - prev
        dd = float(d @ d)
        if dd > 0.0 and np.isfinite(dd):
            w = -self.omega * float(prev @ d) / dd
            self.omega = min(max(w, OMEGA_MIN), OMEGA_MAX) if np.isfinite(w) else 0.5
        self.n_relaxed += 1
        return self.omega


def relaxed_iterate(
    relax: AitkenRelaxation, images: dict, before, after, image_before: dict, stalled: bool
) -> tuple[list[np.ndarray], bool]:
    """(v_plus, relaxed): the iterate ``after`` = G(``before``), or once the step has stalled
    Aitken's relaxed one before + w (after - before); images (the W-images of the full-FE
    bodies, integrate.moreau_jean.w_images: linear in v_plus) relaxed alike, in place, from
    image_before."""
    w = relax.factor(before, after, stalled)
    if w == 1.0:
        return after, False
    for b, img in images.items():
        old = image_before.get(b)
        if old is not None:
            images[b] = old + w * (img - old)
    return [a + w * (c - a) for a, c in zip(before, after)], True
