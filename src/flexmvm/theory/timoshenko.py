"""A straight Timoshenko beam: shear coefficient, 1D finite elements and free-free modes.

The beam bends in one plane: w(x) [m] the transverse deflection, psi(x) [rad] the rotation of
the cross-section (psi = w' without shear), gamma = w' - psi the shear strain. With E, G, rho,
the area A = b h and second moment I = b h^3 / 12 (h the depth in the bending plane):

    strain energy  U = 1/2 int [E I psi'^2 + kappa G A (w' - psi)^2] dx
    kinetic energy T = 1/2 int [rho A w_t^2 + rho I psi_t^2] dx          (Timoshenko 1921)

kappa is the shear coefficient; for a rectangle Cowper (1966, J. Appl. Mech. 33, 335, table 1)
gives kappa = 10 (1 + nu) / (12 + 11 nu) (0.85 for nu = 0.33).

Why finite elements and not the closed-form frequency equation: the free-free frequency
equation of a Timoshenko beam changes form above the cut-off omega_c = sqrt(kappa G A / rho I)
(162 kHz for the 10 mm aluminium section), the modes are needed at arbitrary points (the
contact and the probes) and the static flexibility of the modes left out is needed as well.
The two-node "interdependent interpolation" element (cubic w, quadratic psi tied by the
homogeneous equilibrium E I psi'' + kappa G A (w' - psi) = 0; Reddy 1997, Comput. Methods
Appl. Mech. Eng. 149, 113; the stiffness of Przemieniecki 1968, "Theory of Matrix Structural
Analysis", sect. 5.6) is free of shear locking and exact in statics at its nodes (so the
static flexibility at a node is exact); with its consistent mass the frequencies converge as
h^2 (one constant shear strain per element; h^4 without shear): on the 200 mm beam, 200
elements put the first free-free frequency within 3e-7, the 5th within 5e-5, the 10th (48
kHz) within 4e-4 (tests/test_timoshenko.py checks the element against the closed-form
frequencies of the simply supported beam). The contact history needs no more: the modes
above a few tens of kHz answer the pulse quasi-statically (theory.beam_impact). The two
rigid-body modes of the free beam (translation, rotation) come out of the same eigenproblem
at zero frequency.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from scipy.optimize import brentq

from flexmvm.errors import InputError, SolverError
from flexmvm.theory.hertz import positive

#: Gauss-Legendre points and weights on [0, 1], exact to degree 9 (the mass integrand is of
#: degree 6).
_GAUSS_POINTS, _GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(5)
_XI, _W = 0.5 * (_GAUSS_POINTS + 1.0), 0.5 * _GAUSS_WEIGHTS


def cowper_rectangle(nu: float) -> float:
    """Shear coefficient kappa of a rectangular section, 10 (1 + nu) / (12 + 11 nu) (Cowper
    1966, table 1)."""
    return 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)


@dataclass(frozen=True)
class TimoshenkoBeam:
    """A prismatic rectangular beam: length, width b (across the bending plane) and depth h
    (in it) [m], E [Pa], nu, rho [kg/m^3]. shear_coefficient None: Cowper's rectangle.
    shear_deformation False: kappa G A -> infinity (a Rayleigh beam, or Euler-Bernoulli with
    rotary_inertia False too)."""

    length_m: float
    width_m: float
    depth_m: float
    E_pa: float
    nu: float
    rho_kg_m3: float
    shear_coefficient: float | None = None
    rotary_inertia: bool = True
    shear_deformation: bool = True

    def __post_init__(self) -> None:
        for name in ("length_m", "width_m", "depth_m", "E_pa", "rho_kg_m3"):
            positive(name, getattr(self, name))
        if not (-1.0 < self.nu < 0.5):
            raise InputError(f"nu: expected -1 < nu < 0.5, got {self.nu!r}")
        if self.shear_coefficient is not None:
            positive("shear_coefficient", self.shear_coefficient)

    @property
    def area_m2(self) -> float:
        return self.width_m * self.depth_m

    @property
    def second_moment_m4(self) -> float:
        """I = b h^3 / 12 [m^4], about the axis across the bending plane."""
        return self.width_m * self.depth_m**3 / 12.0

    @property
    def kappa(self) -> float:
        return (
            cowper_rectangle(self.nu) if self.shear_coefficient is None else self.shear_coefficient
        )

    @property
    def shear_modulus_pa(self) -> float:
        return self.E_pa / (2.0 * (1.0 + self.nu))

    @property
    def mass_kg(self) -> float:
        return self.rho_kg_m3 * self.area_m2 * self.length_m


def _shape_functions(xi: np.ndarray, length: float, phi: float):
    """Interdependent interpolation (module doc) on an element of length l at local xi in
    [0, 1]: (Nw, Npsi, dNpsi/dx, gamma), each (len(xi), 4) for the DOFs (w1, psi1, w2, psi2);
    phi = 12 E I / (kappa G A l^2); gamma = dNw/dx - Npsi is constant, -phi mu / l (...)."""
    x = np.asarray(xi, dtype=float)[:, None]
    mu = 1.0 / (1.0 + phi)
    one = np.ones_like(x)
    nw = mu * np.hstack(
        [
            1 - 3 * x**2 + 2 * x**3 + phi * (1 - x),
            length * (x - 2 * x**2 + x**3 + 0.5 * phi * (x - x**2)),
            3 * x**2 - 2 * x**3 + phi * x,
            length * (-(x**2) + x**3 + 0.5 * phi * (x**2 - x)),
        ]
    )
    npsi = mu * np.hstack(
        [
            6.0 / length * (x**2 - x),
            1 - 4 * x + 3 * x**2 + phi * (1 - x),
            6.0 / length * (x - x**2),
            -2 * x + 3 * x**2 + phi * x,
        ]
    )
    dnpsi = (
        mu
        / length
        * np.hstack(
            [
                6.0 / length * (2 * x - 1),
                -4 + 6 * x - phi,
                6.0 / length * (1 - 2 * x),
                -2 + 6 * x + phi,
            ]
        )
    )
    gamma = mu * phi / length * np.hstack([-one, -0.5 * length * one, one, -0.5 * length * one])
    return nw, npsi, dnpsi, gamma


def _phi(beam: TimoshenkoBeam, length: float) -> float:
    if not beam.shear_deformation:
        return 0.0
    ga = beam.kappa * beam.shear_modulus_pa * beam.area_m2
    return 12.0 * beam.E_pa * beam.second_moment_m4 / (ga * length**2)


def element_matrices(beam: TimoshenkoBeam, length: float) -> tuple[np.ndarray, np.ndarray]:
    """(K, M) (4, 4) of one element of ``length`` [m] (module doc: U and T integrated with
    the interdependent interpolation; five-point Gauss, exact)."""
    phi = _phi(beam, length)
    nw, npsi, dnpsi, gamma = _shape_functions(_XI, length, phi)
    w = _W * length
    ei, rho = beam.E_pa * beam.second_moment_m4, beam.rho_kg_m3
    k = ei * (dnpsi.T * w) @ dnpsi
    if beam.shear_deformation:
        ga = beam.kappa * beam.shear_modulus_pa * beam.area_m2
        k += ga * (gamma.T * w) @ gamma
    m = rho * beam.area_m2 * (nw.T * w) @ nw
    if beam.rotary_inertia:
        m += rho * beam.second_moment_m4 * (npsi.T * w) @ npsi
    return k, m


def beam_matrices(beam: TimoshenkoBeam, x_nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Assembled dense (K, M) (2 n, 2 n) for nodes at the increasing positions x_nodes [m];
    DOFs ordered (w_0, psi_0, w_1, psi_1, ...), no support."""
    x = np.asarray(x_nodes, dtype=float)
    n = len(x)
    kk, mm = np.zeros((2 * n, 2 * n)), np.zeros((2 * n, 2 * n))
    for e, length in enumerate(np.diff(x)):
        ke, me = element_matrices(beam, float(length))
        s = slice(2 * e, 2 * e + 4)
        kk[s, s] += ke
        mm[s, s] += me
    return kk, mm


def beam_nodes(length_m: float, n_elements: int, through: tuple[float, ...] = ()) -> np.ndarray:
    """Node positions [m] on [0, length_m], about n_elements equal elements, with a node at
    every point of ``through`` (each stretch between them divided evenly)."""
    if n_elements < 1:
        raise InputError(f"n_elements: expected >= 1, got {n_elements!r}")
    cuts = sorted({0.0, length_m, *(float(p) for p in through)})
    if cuts[0] < 0.0 or cuts[-1] > length_m:
        raise InputError(f"node positions {through!r} m: expected within [0, {length_m!r}] m")
    parts = [
        np.linspace(a, b, max(1, round(n_elements * (b - a) / length_m)) + 1)[:-1]
        for a, b in itertools.pairwise(cuts)
        if b > a
    ]
    return np.concatenate([*parts, [length_m]])


@dataclass(frozen=True)
class BeamModes:
    """Free-free modes of a beam: x_nodes (n,) [m]; omega (2 n,) [rad/s], increasing, the
    two rigid-body modes first at exactly 0; shapes (2 n, 2 n), mass-normalized columns
    (shapes.T M shapes = I) over the DOFs (w_0, psi_0, ...); K, M the assembled matrices."""

    beam: TimoshenkoBeam
    x_nodes: np.ndarray
    omega: np.ndarray
    shapes: np.ndarray
    K: np.ndarray
    M: np.ndarray

    def at(self, x_m) -> tuple[np.ndarray, np.ndarray]:
        """(Nw, Npsi), each (len(x_m), 2 n): the rows that give w [m] and psi [rad] at the
        points x_m [m] from the nodal DOFs (the element's own interpolation)."""
        x = np.atleast_1d(np.asarray(x_m, dtype=float))
        lo, hi = self.x_nodes[0], self.x_nodes[-1]
        if np.any((x < lo) | (x > hi)):
            raise InputError(f"points {x.tolist()} m: expected within the beam [{lo}, {hi}] m")
        e = np.clip(np.searchsorted(self.x_nodes, x, side="right") - 1, 0, len(self.x_nodes) - 2)
        nw, npsi = (
            np.zeros((len(x), 2 * len(self.x_nodes))),
            np.zeros((len(x), 2 * len(self.x_nodes))),
        )
        for i, (xi, ei) in enumerate(zip(x, e)):
            length = self.x_nodes[ei + 1] - self.x_nodes[ei]
            w, p, _, _ = _shape_functions(
                np.array([(xi - self.x_nodes[ei]) / length]), length, _phi(self.beam, length)
            )
            nw[i, 2 * ei : 2 * ei + 4], npsi[i, 2 * ei : 2 * ei + 4] = w[0], p[0]
        return nw, npsi


def free_free_modes(
    beam: TimoshenkoBeam, n_elements: int = 200, through: tuple[float, ...] = ()
) -> BeamModes:
    """All modes of the free-free beam from n_elements elements (nodes at ``through`` [m]).
    SolverError unless exactly two eigenvalues are rigid-body ones (|omega^2| below 1e-8 of
    the first elastic one), which are then set to 0."""
    x = beam_nodes(beam.length_m, n_elements, through)
    kk, mm = beam_matrices(beam, x)
    lam, vec = sla.eigh(kk, mm)
    scale = lam[np.abs(lam) > 1e-8 * np.max(np.abs(lam))]
    rigid = np.abs(lam) < 1e-8 * (scale.min() if scale.size else 1.0)
    if rigid.sum() != 2 or not np.all(rigid[:2]) or np.any(lam[~rigid] <= 0):
        raise SolverError(
            f"free-free beam: expected two rigid-body modes and positive "
            f"elastic eigenvalues, got omega^2 = {lam[:4].tolist()} ..."
        )
    lam = np.where(rigid, 0.0, lam)
    return BeamModes(beam, x, np.sqrt(lam), vec, kk, mm)


def euler_bernoulli_free_free_beta(n: int) -> float:
    """beta_n L of the n-th (n >= 1) elastic free-free Euler-Bernoulli mode, the n-th root of
    cos(bL) cosh(bL) = 1 (4.7300, 7.8532, 10.9956, ...; Blevins, "Formulas for Natural
    Frequency and Mode Shape", table 8-1)."""
    guess = (n + 0.5) * math.pi
    return brentq(lambda b: math.cos(b) - 1.0 / math.cosh(b), guess - 0.3, guess + 0.3, xtol=1e-14)


def euler_bernoulli_omega(beam: TimoshenkoBeam, beta_l: float) -> float:
    """omega = (beta L)^2 sqrt(E I / (rho A L^4)) [rad/s]."""
    return beta_l**2 * math.sqrt(
        beam.E_pa * beam.second_moment_m4 / (beam.rho_kg_m3 * beam.area_m2 * beam.length_m**4)
    )


def simply_supported_omega(beam: TimoshenkoBeam, n: int) -> float:
    """omega [rad/s] of the n-th bending mode of the simply supported Timoshenko beam: w =
    W sin(a x), psi = P cos(a x), a = n pi / L in the equations of motion give
    (kGA a^2 - rho A w^2)(E I a^2 + kGA - rho I w^2) = (kGA a)^2 (Timoshenko 1921), the
    smaller root in w^2."""
    a = n * math.pi / beam.length_m
    rho_a = beam.rho_kg_m3 * beam.area_m2
    rho_i = beam.rho_kg_m3 * beam.second_moment_m4 if beam.rotary_inertia else 0.0
    ei = beam.E_pa * beam.second_moment_m4
    if not beam.shear_deformation:  # kGA -> infinity: E I a^4 = (rho A + rho I a^2) w^2
        return math.sqrt(ei * a**4 / (rho_a + rho_i * a**2))
    ga = beam.kappa * beam.shear_modulus_pa * beam.area_m2
    # (ga a^2 - rho_a s)(ei a^2 + ga - rho_i s) - (ga a)^2 = qa s^2 + qb s + qc = 0, s = w^2
    qa = rho_a * rho_i
    qb = -(rho_a * (ei * a**2 + ga) + rho_i * ga * a**2)
    qc = ga * a**2 * ei * a**2
    return math.sqrt(2.0 * qc / (-qb + math.sqrt(qb * qb - 4.0 * qa * qc)))  # no cancellation


__all__ = [
    "BeamModes",
    "TimoshenkoBeam",
    "beam_matrices",
    "beam_nodes",
    "cowper_rectangle",
    "element_matrices",
    "euler_bernoulli_free_free_beta",
    "euler_bernoulli_omega",
    "free_free_modes",
    "simply_supported_omega",
]
