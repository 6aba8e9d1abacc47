"""Rotation utilities: skew matrices and the exponential map on SO(3)."""

from __future__ import annotations

import math

import numpy as np

from flexmvm.errors import SolverError


def cross3(a, b) -> np.ndarray:
    """a x b for two 3-vectors (np.cross is slow for single vectors)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def cross_rows(w, s: np.ndarray) -> np.ndarray:
    """w x s_k for a 3-vector w and every row of s (n, 3): np.cross(w, s) bit for bit (the
    same products and differences), without its ~30 us of axis handling per call (the
    recorder's probe velocities, twice per output)."""
    out = np.empty(s.shape)
    out[:, 0] = w[1] * s[:, 2] - w[2] * s[:, 1]
    out[:, 1] = w[2] * s[:, 0] - w[0] * s[:, 2]
    out[:, 2] = w[0] * s[:, 1] - w[1] * s[:, 0]
    return out


def skew(v: np.ndarray) -> np.ndarray:
    """Skew-symmetric matrix v~ with v~ w = v x w."""
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def expm_so3(theta: np.ndarray) -> np.ndarray:
    """exp(theta~) by Rodrigues' formula (theta: rotation vector [rad], shape (3,)):
    I + (sin a / a) K + ((1 - cos a) / a^2) K^2, a = |theta|, K = theta~, K^2 = theta theta^T -
    a^2 I; below a = 1e-8 the series I + K + K^2 / 2. Written out on scalars: it runs several
    times per body and time step, where numpy's eye, norm and 3 x 3 products cost ~17 us.
    SolverError when theta is not finite (a run whose motion overflowed)."""
    x, y, z = float(theta[0]), float(theta[1]), float(theta[2])
    xx, yy, zz = x * x, y * y, z * z
    angle = math.sqrt(xx + yy + zz)
    if angle < 1e-8:
        s, c = 1.0, 0.5
    elif not angle < math.inf:  # inf or NaN: the state has overflowed
        raise SolverError(
            f"rotation vector {[x, y, z]} is not finite: the motion overflowed "
            "(expected finite angular velocities and forces)"
        )
    else:
        s, c = math.sin(angle) / angle, (1.0 - math.cos(angle)) / angle**2
    xy, xz, yz = c * (x * y), c * (x * z), c * (y * z)
    return np.array(
        [
            [1.0 - c * (yy + zz), xy - s * z, xz + s * y],
            [xy + s * z, 1.0 - c * (xx + zz), yz - s * x],
            [xz - s * y, yz + s * x, 1.0 - c * (xx + yy)],
        ]
    )


def axis_angle(axis, angle_rad: float) -> np.ndarray:
    """Rotation matrix about a (normalised) axis by angle_rad."""
    a = np.asarray(axis, dtype=float)
    return expm_so3(a / np.linalg.norm(a) * angle_rad)
