"""Natural frequencies of a body about a steady spin: the linearized equations of its elastic
coordinates with the frame turning at a constant angular velocity (a driven hub).

With omega constant (body frame), W = skew(omega) and Om = W W, the q-linear terms of the
floating-frame equations (bodies.body: Q_q = -sum_ab Om_ab C[b][a] - 2 sum_ab W_ab G2[a][b]
q_dot, C[b][a] = G1[b][a] + G2[a][b] q; Shabana, *Dynamics of Multibody Systems*, ch. 5) give

    M_qq q'' + G q' + (k_hat + s K_G_hat + K_W) q = f_1 Omega^2     (the static part aside)

    K_W = sum_ab Om_ab G2[a][b]      spin softening (negative semi-definite: -Omega^2 times the
                                     mass of the motion across the axis)
    G   = 2 sum_ab W_ab G2[a][b]     Coriolis (antisymmetric)
    s K_G_hat                        geometric stiffening, s = (n . omega)^2 (bodies.stiffening)

Their eigenvalues lambda = i w come from the first-order form [I 0; 0 M] z' = [0 I; -K -G] z
(dense: for reduced bodies). For a cantilever clamped on the axis (hub radius 0) the first
flapwise frequency follows the Southwell relation w^2 = w_0^2 + K1 Omega^2 with K1 = 1.193
(Southwell and Gough 1921; the exact coefficient in Wright, Smith, Thresher and Wang 1982,
J. Appl. Mech. 49, 197-202); without K_G_hat it stays w_0.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.rotation import skew
from flexmvm.errors import InputError, SolverError

#: The largest body spin_matrices makes dense (a reduced body; a full-FE body would be a dense
#: eigenproblem of twice its size)
DENSE_MAX_NQ = 2000
#: An eigenvalue whose real part exceeds this fraction of its modulus is a growing motion
UNSTABLE_RTOL = 1e-8


def _dense(a) -> np.ndarray:
    return a.toarray() if sp.issparse(a) else np.array(a, dtype=float)  # a copy


def spin_matrices(
    body: FlexibleBody, omega, stiffening: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(M, G, K) (nq, nq) dense of the linearized elastic equations about the steady spin
    omega (3,) [rad/s], body frame (module doc); stiffening False leaves out s K_G_hat (the
    linear floating-frame model). Raises InputError for a rigid body or one above
    DENSE_MAX_NQ coordinates."""
    if not 0 < body.nq <= DENSE_MAX_NQ:
        raise InputError(
            f"body {body.name!r}: spin frequencies need 1..{DENSE_MAX_NQ} elastic "
            f"coordinates (a reduced body), got {body.nq}"
        )
    w = np.asarray(omega, dtype=float)
    W = skew(w)
    Om = W @ W
    G2 = body.inv.G2
    K = _dense(body.k_hat)
    G = np.zeros_like(K)
    for a in range(3):
        for b in range(3):
            if Om[a, b] != 0.0 or W[a, b] != 0.0:
                g2 = _dense(G2[a][b])
                K += Om[a, b] * g2
                G += 2.0 * W[a, b] * g2
    if stiffening and body.stiffening is not None:
        K += body.stiffening.scale(w) * _dense(body.stiffening.K_G)
    return _dense(body.inv.M_qq), G, 0.5 * (K + K.T)


def spin_frequencies(body: FlexibleBody, omega, stiffening: bool = True) -> np.ndarray:
    """The natural frequencies w (nq,) [rad/s], ascending, of body about the steady spin omega
    (3,) [rad/s], body frame (module doc). Raises SolverError when a motion grows (the linear
    model diverges at this spin: a real eigenvalue > 0) and InputError as spin_matrices."""
    M, G, K = spin_matrices(body, omega, stiffening)
    n = M.shape[0]
    eye, zero = np.eye(n), np.zeros((n, n))
    lhs = np.block([[eye, zero], [zero, M]])
    rhs = np.block([[zero, eye], [-K, -G]])
    lam = sla.eig(rhs, lhs, right=False)
    if not np.all(np.isfinite(lam)):
        raise SolverError(f"body {body.name!r}: singular mass matrix in the spin eigenproblem")
    grow = lam.real > UNSTABLE_RTOL * np.abs(lam)
    if np.any(grow):
        worst = lam[grow][np.argmax(lam[grow].real)]
        raise SolverError(
            f"body {body.name!r} diverges at the spin {np.linalg.norm(omega):.6g} rad/s: "
            f"a motion grows as exp({worst.real:.4g} t)"
        )
    return np.sort(lam.imag[lam.imag > 0.0])


def spin_quasi_static(body: FlexibleBody, omega, alpha, stiffening: bool = True) -> np.ndarray:
    """q (nq,) [m]: the elastic coordinates that balance, at rest in the frame, its spin omega
    and angular acceleration alpha (3,) [rad/s, rad/s^2], body frame, the frame's origin at
    rest: (k_hat + s K_G_hat + K_W) q = -sum_ab Om_ab G1[b][a] - M_wq(0)^T alpha (the
    centrifugal load of the undeformed body and the Euler load; module doc). The lag of a
    cantilever spun up slowly against its first period follows it (docs/spin_up.md). Raises
    as spin_matrices, and SolverError when K is singular."""
    _, _, K = spin_matrices(body, omega, stiffening)
    W = skew(np.asarray(omega, dtype=float))
    Om = W @ W
    G1 = body.G1_array  # [a, b] = G1[a][b]
    load = -np.einsum("ab,bak->k", Om, G1) - body.rotational_coupling(np.zeros(body.nq)).T @ alpha
    try:
        return sla.solve(K, load, assume_a="sym")
    except (sla.LinAlgError, ValueError):
        raise SolverError(f"body {body.name!r}: singular stiffness at this spin") from None


__all__ = ["DENSE_MAX_NQ", "spin_frequencies", "spin_matrices", "spin_quasi_static"]
