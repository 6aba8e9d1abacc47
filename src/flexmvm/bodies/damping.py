"""Structural damping of a body: the reduced damping matrix c_hat (nq, nq) [N s/m], the one
place damping lives (the step adds -c_hat q_dot to the elastic force, integrate.moreau_jean;
the dissipated power is q_dot^T c_hat q_dot).

| form     | c_hat                                                    | ratio of mode i        |
|----------|----------------------------------------------------------|------------------------|
| Rayleigh | alpha M_qq + beta k_hat = psi^T (alpha M + beta K) psi   | alpha / (2 w_i)        |
|          | (Rayleigh 1877; Chopra, Dynamics of Structures, 11.4)    | + beta w_i / 2         |
| modal    | modal block M_mm V diag(2 zeta_i w_i) V^T M_mm           | zeta_i                 |
|          | (Chopra 11.5), other coordinates undamped                |                        |

Rayleigh damping of a reduced body is the projection of the full body's C = alpha M + beta K
on its basis (M_qq = psi^T M psi, k_hat = psi^T K psi), so it is consistent with the full
model by construction: mode i of the reduced body decays at the rate alpha / 2 + beta w~_i^2 / 2
of its own frequency w~_i, which differs from the full body's by the reduction's frequency
error.

Modal damping (reduced bodies): V, w^2 the eigenpairs of the modal block (k_mm, M_mm) of the
basis (Craig-Bampton and the interface kind: the last n_modes columns; modal: all;
seed eq. (4) kinds: the first n_modes), V M_mm-orthonormal, in ascending frequency; ratio
zeta_i to the i-th (one ratio: all of them). For a Craig-Bampton basis M_mm = I and
k_mm = diag(w_i^2) (M-normalised fixed-interface modes), so c_mm = diag(2 zeta_i w_i). The
retained (boundary) coordinates and their coupling to the modes are left undamped: with the
ratios read off a Rayleigh curve, zeta_i = alpha / (2 w_i) + beta w_i / 2, the modal block
equals that of the projected Rayleigh matrix (alpha I + beta diag(w_i^2)); the difference is
the boundary block and the mass coupling alpha M_bm (K_bm = 0 for Craig-Bampton), which
vanish for a body clamped at its interface (reduction.clamp: no boundary coordinates left),
where modal and Rayleigh damping agree exactly. Undamped boundary rows also keep a massless
retained node algebraic (integrate.moreau_jean.massless).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from flexmvm.errors import InputError
from flexmvm.reduction.basis import Basis
from flexmvm.reduction.kinds import kind_spec


@dataclass(frozen=True)
class RayleighDamping:
    """C = alpha M + beta K: alpha_per_s [1/s] (mass part), beta_s [s] (stiffness part)."""

    alpha_per_s: float
    beta_s: float

    def __post_init__(self) -> None:
        for name in ("alpha_per_s", "beta_s"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise InputError(f"Rayleigh damping {name} = {value!r}; expected a number >= 0")

    def ratio(self, omega_radps):
        """Damping ratio zeta(w) = alpha / (2 w) + beta w / 2 of a mode of angular frequency
        omega_radps [rad/s] (scalar or array)."""
        w = np.asarray(omega_radps, dtype=float)
        return self.alpha_per_s / (2.0 * w) + self.beta_s * w / 2.0


@dataclass(frozen=True)
class ModalDamping:
    """Damping ratios zeta [-] of a reduced body's modes, ascending in frequency: one ratio
    for every mode, or one per mode (as many as the basis has)."""

    ratios: tuple[float, ...]

    def __post_init__(self) -> None:
        ratios = tuple(self.ratios)
        if not ratios or not all(
            isinstance(z, (int, float)) and math.isfinite(z) and z >= 0 for z in ratios
        ):
            raise InputError(f"modal damping ratios {list(ratios)}; expected numbers >= 0")
        object.__setattr__(self, "ratios", ratios)

    def per_mode(self, n_modes: int, body: str) -> np.ndarray:
        """(n_modes,) ratios; InputError unless one ratio or n_modes are given."""
        if len(self.ratios) == 1:
            return np.full(n_modes, float(self.ratios[0]))
        if len(self.ratios) != n_modes:
            raise InputError(
                f"body {body!r}: {len(self.ratios)} modal damping ratios for {n_modes} "
                "modes; expected one ratio or one per mode"
            )
        return np.asarray(self.ratios, dtype=float)


Damping = RayleighDamping | ModalDamping


def rayleigh_from_ratios(f1_hz: float, zeta1: float, f2_hz: float, zeta2: float) -> RayleighDamping:
    """The Rayleigh damping with ratio zeta1 at f1_hz and zeta2 at f2_hz [Hz] (Chopra 11.4.3):
    zeta(w) = alpha / (2 w) + beta w / 2 at both, so
    alpha = 2 w1 w2 (zeta1 w2 - zeta2 w1) / (w2^2 - w1^2),
    beta = 2 (zeta2 w2 - zeta1 w1) / (w2^2 - w1^2).
    InputError for frequencies not > 0 or equal, ratios < 0, or a pair that needs a
    negative alpha or beta (the curve cannot pass through both points)."""
    for name, value in (("f1_hz", f1_hz), ("f2_hz", f2_hz)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise InputError(f"rayleigh_from_ratios: {name} = {value!r}; expected a number > 0")
    if f1_hz == f2_hz:
        raise InputError(f"rayleigh_from_ratios: f1_hz = f2_hz = {f1_hz!r}; expected two")
    w1, w2 = 2 * math.pi * f1_hz, 2 * math.pi * f2_hz
    den = w2 * w2 - w1 * w1
    alpha = 2 * w1 * w2 * (zeta1 * w2 - zeta2 * w1) / den
    beta = 2 * (zeta2 * w2 - zeta1 * w1) / den
    if alpha < 0 or beta < 0:
        raise InputError(
            f"rayleigh_from_ratios: zeta {zeta1!r} at {f1_hz!r} Hz and {zeta2!r} at {f2_hz!r} "
            f"Hz need alpha = {alpha:.4g} 1/s, beta = {beta:.4g} s; expected both >= 0"
        )
    return RayleighDamping(alpha, beta)


def modal_columns(basis: Basis) -> np.ndarray:
    """Column ids of a basis's modal coordinates (module doc); InputError for a basis with
    none (full FE, or a reduced basis without modes)."""
    kind, n = basis.kind, basis.n_modes
    spec = kind_spec(kind)
    if not spec.reads_modes or not n:
        raise InputError(
            f"modal damping ratios need modes; a {kind.value} basis with {n} modes has none "
            "(give Rayleigh alpha_per_s, beta_s instead)"
        )
    return spec.modal_columns(basis)


def _dense_block(A, cols: np.ndarray) -> np.ndarray:
    """A[cols][:, cols] as a dense array (A dense or sparse)."""
    if sp.issparse(A):
        return sp.csr_matrix(A)[cols][:, cols].toarray()
    return np.asarray(A)[np.ix_(cols, cols)]


def _modal_block(M_qq, k_hat, cols: np.ndarray, zeta: np.ndarray) -> np.ndarray:
    """M_mm V diag(2 zeta w) V^T M_mm on the columns cols, V the M_mm-orthonormal eigenvectors
    of (k_mm, M_mm) in ascending frequency (Chopra 11.5)."""
    M, K = _dense_block(M_qq, cols), _dense_block(k_hat, cols)
    lam, V = sla.eigh(0.5 * (K + K.T), 0.5 * (M + M.T))
    omega = np.sqrt(np.clip(lam, 0.0, None))
    MV = M @ V
    return (MV * (2.0 * zeta * omega)) @ MV.T


def reduced_damping(damping: Damping | None, M_qq, k_hat, basis: Basis, body: str = "body"):
    """c_hat (nq, nq) [N s/m] of ``damping`` for a body of reduced mass M_qq [kg], stiffness
    k_hat [N/m] and basis ``basis`` (module table): csr when M_qq and k_hat are (full FE,
    Rayleigh), else dense; None for no damping. InputError for modal ratios on a basis
    without modes or in the wrong number."""
    if damping is None:
        return None
    if isinstance(damping, RayleighDamping):
        return damping.alpha_per_s * M_qq + damping.beta_s * k_hat
    if not isinstance(damping, ModalDamping):
        raise InputError(f"body {body!r}: damping {damping!r}; expected Rayleigh or modal")
    cols = modal_columns(basis)
    zeta = damping.per_mode(cols.size, body)
    c = np.zeros((basis.nq, basis.nq))
    c[np.ix_(cols, cols)] = _modal_block(M_qq, k_hat, cols, zeta)
    return c


__all__ = [
    "Damping",
    "ModalDamping",
    "RayleighDamping",
    "modal_columns",
    "rayleigh_from_ratios",
    "reduced_damping",
]
