"""The quasi-static answer of scenarios/cam_follower.toml (issue 53 item 4): an eccentric cam
turning at a constant speed presses a clamped follower; slowly enough (the cam's frequency far
below the follower's first, 56 Hz) the contact force is the lift the cam imposes times the
follower's stiffness at the contact point.

Kinematics (mesh/cam.py's frames): the cam's shaft at x_a on the follower's face, its disc of
radius R centred e above the shaft at t = 0 and touching the undeformed face, turning at
omega about +y: its centre at x_a + e sin(omega t), height R + e (cos(omega t) - 1) above the
face, so the cam presses the face down by

    delta(t) = e (1 - cos omega t)            at   x(t) = x_a + e sin(omega t) - R beta,

beta the follower's slope there: a face tilted by beta touches the disc at R beta behind its
lowest point (for a cantilever of lever arm x under a point load, beta = 3 delta / (2 x)).
The force is F = delta / c(x), c(x) the follower's static compliance at the contact point
[m/N], computed on the FE model (follower_compliance): the clamp held, a unit downward load
shared by the face nodes within ``radius_m`` of (x, 0, 0), their mean deflection; the local
indentation under the load (~1 um at 90 N) is 2e-4 of the lift and left out, with the tilt's
second-order terms (R beta^2 / 2, 1 - cos beta: < 2e-3).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse.linalg as spla

from flexmvm.errors import InputError
from flexmvm.fe.assembly import FEModel


@dataclass(frozen=True)
class CamMotion:
    """An eccentric cam on a flat follower face [m, rad/s] (module doc): its disc's centre
    (dx, dz) = ``offset_m`` from the shaft at t = 0 (dx = 0, dz = e as designed; a mesh's
    bore centroid, where the revolute joint holds the cam, moves the shaft by microns), the
    shaft at x = ``shaft_x_m``."""

    offset_m: tuple[float, float]
    radius_m: float
    omega_radps: float
    shaft_x_m: float

    def lift(self, t: np.ndarray) -> np.ndarray:
        """delta(t) [m]: how far the cam presses the face down, dz (1 - cos wt) + dx sin wt."""
        (dx, dz), phi = self.offset_m, self.omega_radps * np.asarray(t)
        return dz * (1.0 - np.cos(phi)) + dx * np.sin(phi)

    def contact_x(self, t: np.ndarray) -> np.ndarray:
        """x(t) [m] of the contact point on the face, with the cantilever's tilt (module doc)."""
        (dx, dz), phi = self.offset_m, self.omega_radps * np.asarray(t)
        x = self.shaft_x_m + dx * np.cos(phi) + dz * np.sin(phi)
        return x - self.radius_m * 1.5 * self.lift(t) / x


def follower_compliance(
    fe: FEModel, held_nodes: np.ndarray, top_nodes: np.ndarray, xs: np.ndarray, radius_m: float
) -> np.ndarray:
    """c(x) [m/N] at each x of ``xs`` (module doc): ``held_nodes`` clamped, a unit -z load
    shared equally by the nodes of ``top_nodes`` within radius_m of (x, 0, 0), their mean
    -z displacement. One factorisation of K_ff; InputError when no node is within reach."""
    X = fe.mesh.nodes
    held = np.zeros(fe.n_dof, dtype=bool)
    held[(3 * np.asarray(held_nodes)[:, None] + np.arange(3)).ravel()] = True
    free = np.flatnonzero(~held)
    solve = spla.factorized(fe.K[free][:, free].tocsc())
    top = np.asarray(top_nodes)
    out = np.empty(len(xs))
    for i, x in enumerate(xs):
        near = top[np.linalg.norm(X[top] - np.array([x, 0.0, 0.0]), axis=1) <= radius_m]
        if near.size == 0:
            raise InputError(
                f"follower_compliance: no face node within {radius_m!r} m of x = {x!r} m"
            )
        f = np.zeros(fe.n_dof)
        f[3 * near + 2] = -1.0 / near.size
        u = np.zeros(fe.n_dof)
        u[free] = solve(f[free])
        out[i] = -float(np.mean(u[3 * near + 2]))
    return out


def quasi_static_force(
    motion: CamMotion, t: np.ndarray, xs: np.ndarray, compliance: np.ndarray
) -> np.ndarray:
    """F(t) = delta(t) / c(x(t)) [N], c interpolated in the samples (xs, compliance)."""
    c = np.interp(motion.contact_x(t), xs, compliance)
    return motion.lift(t) / c


__all__ = ["CamMotion", "follower_compliance", "quasi_static_force"]
