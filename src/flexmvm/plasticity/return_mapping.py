"""Radial return of small-strain J2 plasticity with linear isotropic and kinematic hardening,
and its consistent (algorithmic) tangent, vectorized over integration points.

Simo and Hughes (1998, *Computational Inelasticity*), box 3.2 and eq. 3.3.13; de Souza Neto,
Peric, Owen (2008, *Computational Methods for Plasticity*), box 7.3 and 7.4. With bulk
modulus kappa, shear modulus mu and the state (eps_p, alpha, beta) of step n:

    s_tr  = 2 mu dev(eps - eps_p_n),   xi_tr = s_tr - beta_n
    f_tr  = ||xi_tr|| - sqrt(2/3) (Y + H_iso alpha_n)            (elastic if f_tr <= 0)
    dgam  = f_tr / (2 mu + 2/3 (H_iso + H_kin)),   n = xi_tr / ||xi_tr||
    sigma = kappa tr(eps) 1 + s_tr - 2 mu dgam n
    eps_p = eps_p_n + dgam n,  alpha = alpha_n + sqrt(2/3) dgam,  beta = beta_n + 2/3 H_kin dgam n
    C     = kappa 1 (x) 1 + 2 mu theta (I - 1/3 1 (x) 1) - 2 mu theta_bar n (x) n
    theta = 1 - 2 mu dgam / ||xi_tr||,  theta_bar = 1 / (1 + (H_iso + H_kin) / (3 mu)) - (1 - theta)

The compiled per-point kernel is kernels.return_point; kernels_numpy.py keeps the numpy form.

Voigt storage, order (xx, yy, zz, xy, yz, zx): strains (the input strain and the plastic
strain) carry engineering shears gamma_ij = 2 eps_ij, as B u gives them; stresses and the
back stress carry tensor components. The tangent D (6 x 6) is d sigma / d strain in that
pairing, so that the element stiffness is B^T D B.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError
from flexmvm.materials import Material
from flexmvm.plasticity.kernels import return_points
from flexmvm.plasticity.material import J2Plasticity

#: Tensor-component inner product weights in Voigt order: a : b = sum_I w_I a_I b_I.
_WEIGHT = np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])
_ONE = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])
#: d eps (tensor components) / d strain (engineering shears): the symmetric identity.
_I_DEV = np.diag([1.0, 1.0, 1.0, 0.5, 0.5, 0.5]) - np.outer(_ONE, _ONE) / 3.0


@dataclass(frozen=True)
class PointState:
    """History of n integration points: plastic_strain (n, 6) [-] (engineering shears),
    equivalent_plastic_strain (n,) [-] (alpha, accumulated), back_stress (n, 6) [Pa]."""

    plastic_strain: np.ndarray
    equivalent_plastic_strain: np.ndarray
    back_stress: np.ndarray

    @classmethod
    def virgin(cls, n: int) -> PointState:
        """n points that have never yielded."""
        return cls(np.zeros((n, 6)), np.zeros(n), np.zeros((n, 6)))

    @property
    def n_points(self) -> int:
        return len(self.equivalent_plastic_strain)

    def take(self, points: np.ndarray) -> PointState:
        """The history of the points ``points`` (index array or slice), in that order."""
        return PointState(
            self.plastic_strain[points],
            self.equivalent_plastic_strain[points],
            self.back_stress[points],
        )

    def put(self, points: np.ndarray, part: PointState) -> PointState:
        """A copy of this history with the points ``points`` replaced by ``part`` (the
        inverse of take: ``state.put(ids, state.take(ids))`` equals ``state``)."""
        out = PointState(
            self.plastic_strain.copy(),
            self.equivalent_plastic_strain.copy(),
            self.back_stress.copy(),
        )
        out.plastic_strain[points] = part.plastic_strain
        out.equivalent_plastic_strain[points] = part.equivalent_plastic_strain
        out.back_stress[points] = part.back_stress
        return out


@dataclass(frozen=True)
class PointResponse:
    """Result of a strain increment at n points: stress (n, 6) [Pa], tangent (n, 6, 6) [Pa]
    (consistent, d stress / d strain), state (the updated PointState) and yielding (n,) bool
    (the points that returned to the yield surface in this increment)."""

    stress: np.ndarray
    tangent: np.ndarray
    state: PointState
    yielding: np.ndarray


def elastic_tangent(material: Material) -> np.ndarray:
    """Isotropic Hooke matrix D (6, 6) [Pa], engineering shear strains: kappa 1(x)1 + 2 mu I_dev."""
    lam, mu = material.lame
    kappa = lam + 2.0 * mu / 3.0
    return kappa * np.outer(_ONE, _ONE) + 2.0 * mu * _I_DEV


def tensor_norm(a: np.ndarray) -> np.ndarray:
    """Frobenius norm of symmetric tensors stored with tensor components, (..., 6) -> (...)."""
    return np.sqrt(np.sum(_WEIGHT * a * a, axis=-1))


def deviator(a: np.ndarray) -> np.ndarray:
    """dev a = a - tr(a)/3 1 of tensor-component Voigt vectors (..., 6)."""
    return a - _ONE * (a[..., :3].sum(axis=-1, keepdims=True) / 3.0)


def von_mises(stress: np.ndarray) -> np.ndarray:
    """Von Mises equivalent stress sqrt(3/2) ||dev sigma|| [Pa], (..., 6) -> (...)."""
    return math.sqrt(1.5) * tensor_norm(deviator(stress))


def radial_return(
    material: Material, plastic: J2Plasticity, strain: np.ndarray, state: PointState
) -> PointResponse:
    """Stress, consistent tangent and new state at n points for total strain ``strain``
    (n, 6) (engineering shears) from the converged state ``state`` of the last step (module
    doc; Simo and Hughes box 3.2). Raises InputError if the shapes do not agree."""
    strain = np.asarray(strain, dtype=float)
    if strain.ndim != 2 or strain.shape[1] != 6 or len(strain) != state.n_points:
        raise InputError(
            f"radial_return: strain must have shape ({state.n_points}, 6), got {strain.shape}"
        )
    mat = material_constants(material, plastic)
    n = len(strain)
    stress, tangent = np.empty((n, 6)), np.empty((n, 6, 6))
    new = PointState(np.empty((n, 6)), np.empty(n), np.empty((n, 6)))
    yielding = np.empty(n, dtype=np.bool_)
    return_points(
        np.ascontiguousarray(strain),
        *_contiguous(state),
        mat,
        stress,
        tangent,
        *_arrays(new),
        yielding,
    )
    return PointResponse(stress, tangent, new, yielding)


def material_constants(material: Material, plastic: J2Plasticity) -> np.ndarray:
    """(kappa, mu, Y, H_iso, H_kin) [Pa], the material vector of the kernels."""
    lam, mu = material.lame
    return np.array(
        [
            lam + 2.0 * mu / 3.0,
            mu,
            plastic.yield_pa,
            plastic.hardening_pa,
            plastic.kinematic_hardening_pa,
        ]
    )


def _arrays(state: PointState) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return state.plastic_strain, state.equivalent_plastic_strain, state.back_stress


def _contiguous(state: PointState) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The state's arrays as float64 C-contiguous arrays (no copy when they are)."""
    eps_p, eq_p, back = (np.ascontiguousarray(a, dtype=float) for a in _arrays(state))
    return eps_p, eq_p, back
