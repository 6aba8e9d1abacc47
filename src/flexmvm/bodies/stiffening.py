"""Geometric stiffening of a spinning body: the prestress of its own spin in the equations of
motion of its elastic coordinates (Wallrapp and Schwertassek 1991, Int. J. Numer. Meth. Eng.
32, 1833-1850; the floating-frame model with linear elasticity misses it, and a cantilever
spun up past its first bending frequency diverges: Kane, Ryan and Banerjee 1987, J. Guidance
10(2), 139-151).

The geometric stiffness of the prestress of a unit spin about the body's spin axis n
(fe.geometric_stiffness), projected once onto the basis,

    K_G_hat = psi^T K_G(sigma_1) psi        (nq, nq) [kg]: N/m per (rad/s)^2,

enters the elastic rows as a stiffness scaled by the square of the spin,

    Q_q -= s K_G_hat q,     s = (n . omega)^2     [rad^2/s^2]

omega the frame's angular velocity (body frame) at the step's midpoint: the prestress follows
the current spin quasi-statically (the approach of Wallrapp and Schwertassek; exact for a
steady spin, and for a spin-up slow against the body's axial vibration).

spin_crit = 1 / max |lambda(K_G_hat, k_hat)| [rad^2/s^2] is the spin squared at which the
stiffening is as large as the elastic stiffness in some direction; the integrator refreshes
its iteration matrix when s moved by more than a fraction of s + spin_crit (body_solver).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator, eigsh

from flexmvm.errors import InputError
from flexmvm.fe.assembly import FEModel
from flexmvm.fe.geometric_stiffness import spin_axis, spin_geometric_stiffness
from flexmvm.fe.solvers import spd_solver


@dataclass(frozen=True)
class GeometricStiffening:
    """The stiffening of one body (module doc). axis: (3,) unit spin axis, body frame;
    point: (3,) a point of the axis [m], body frame; K_G: (nq, nq) [kg], dense or csr as the
    body's k_hat; spin_crit [rad^2/s^2]."""

    axis: np.ndarray
    point: np.ndarray
    K_G: np.ndarray | sp.csr_matrix
    spin_crit: float

    def scale(self, omega: np.ndarray) -> float:
        """s = (n . omega)^2 [rad^2/s^2] for the frame's angular velocity omega (3,) [rad/s],
        body frame."""
        return float(self.axis @ omega) ** 2

    def force(self, omega: np.ndarray, q: np.ndarray) -> np.ndarray:
        """s K_G_hat q (nq,) [N]: the generalized force the elastic rows lose to the
        prestress of the spin omega (body frame [rad/s]) at the configuration q."""
        s = self.scale(omega)
        if s == 0.0:
            return np.zeros(q.shape[0])
        return s * np.asarray(self.K_G @ q).ravel()


def critical_spin(K_G, k_hat) -> float:
    """1 / max |lambda| of K_G x = lambda k_hat x [rad^2/s^2] (inf when K_G = 0): dense
    matrices by LAPACK, sparse ones by ARPACK with k_hat factored once (fe.solvers)."""
    if sp.issparse(K_G):
        k = sp.csc_matrix(k_hat)
        solve = spd_solver(k)
        n = k.shape[0]
        minv = LinearOperator((n, n), matvec=lambda x: np.asarray(solve(x)).ravel())
        lam = eigsh(sp.csc_matrix(K_G), k=1, M=k, Minv=minv, which="LM", return_eigenvectors=False)
    else:
        lam = sla.eigh(np.asarray(K_G), np.asarray(k_hat), eigvals_only=True)
    top = float(np.abs(lam).max()) if lam.size else 0.0
    return 1.0 / top if top > 0.0 else np.inf


def reduced(matrix: sp.spmatrix, psi) -> np.ndarray | sp.csr_matrix:
    """psi^T matrix psi, symmetrized: dense for a dense psi, csr for a sparse one."""
    if sp.issparse(psi):
        pr = sp.csr_matrix(psi)
        out = sp.csr_matrix(pr.T @ (matrix @ pr))
        return sp.csr_matrix(0.5 * (out + out.T))
    out = psi.T @ np.asarray(matrix @ psi)
    return 0.5 * (out + out.T)


def geometric_stiffening(
    fe: FEModel, psi, k_hat, axis, fixed_dofs, point=(0.0, 0.0, 0.0)
) -> GeometricStiffening:
    """The stiffening of the body with FE model fe, basis psi (3n, nq) and k_hat (nq, nq)
    spinning about ``axis`` through ``point`` (body frame [m]); the unit-spin prestress is
    the static solution with the DOFs ``fixed_dofs`` held (the body's supports: a clamped
    root, or its reference condition's six DOFs). Raises InputError for a zero axis or
    supports that leave the body free."""
    n = spin_axis(axis)
    if psi.shape[0] != fe.n_dof:
        raise InputError(f"basis has {psi.shape[0]} rows, the FE model {fe.n_dof} DOFs")
    K_G, _ = spin_geometric_stiffness(fe, n, fixed_dofs, point)
    K_hat = reduced(K_G, psi)
    return GeometricStiffening(
        n, np.asarray(point, dtype=float), K_hat, critical_spin(K_hat, k_hat)
    )


__all__ = ["GeometricStiffening", "critical_spin", "geometric_stiffening", "reduced"]
