"""Rotation utilities: skew matrices and the exponential map on SO(3)."""

from __future__ import annotations

import numpy as np


def cross3(a, b) -> np.ndarray:
    """a x b for two 3-vectors (np.cross is slow for single vectors)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def skew(v: np.ndarray) -> np.ndarray:
    """Skew-symmetric matrix v~ with v~ w = v x w."""
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def expm_so3(theta: np.ndarray) -> np.ndarray:
    """exp(theta~) by Rodrigues' formula (theta: rotation vector [rad], shape (3,))."""
    angle = float(np.linalg.norm(theta))
    K = skew(theta)
    if angle < 1e-8:
        return np.eye(3) + K + 0.5 * K @ K
    return np.eye(3) + np.sin(angle) / angle * K + (1 - np.cos(angle)) / angle**2 * K @ K


def axis_angle(axis, angle_rad: float) -> np.ndarray:
    """Rotation matrix about a (normalised) axis by angle_rad."""
    a = np.asarray(axis, dtype=float)
    return expm_so3(a / np.linalg.norm(a) * angle_rad)
