"""The Timoshenko beam + Hertz reference of a sphere striking a free beam
(flexmvm.theory.timoshenko, beam_impact): its beam against closed-form frequencies, its
impact against the conservation laws and against Hertz's half-space impact. About 6 s in all
(1D matrices of a few hundred DOF; the impacts over 0.2 ms)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg as sla

from flexmvm.errors import InputError
from flexmvm.theory.beam_impact import SphereOnBeam
from flexmvm.theory.hertz import hertz_impact
from flexmvm.theory.timoshenko import (
    TimoshenkoBeam,
    beam_matrices,
    beam_nodes,
    cowper_rectangle,
    euler_bernoulli_free_free_beta,
    euler_bernoulli_omega,
    free_free_modes,
    simply_supported_omega,
)

# the shipped scenario's beam: aluminium 200 x 10 x 10 mm (L / h = 20)
BEAM = TimoshenkoBeam(0.2, 0.01, 0.01, 72.71e9, 0.33, 2700.0)
E_STAR = BEAM.E_pa / (1.0 - BEAM.nu**2)  # rigid sphere on aluminium [Pa]
M_SPHERE = 7850.0 * 4.0 / 3.0 * math.pi * 0.01**3  # steel, R 10 mm [kg]


def _simply_supported_fe(beam: TimoshenkoBeam, n_elements: int, n: int) -> np.ndarray:
    """The n lowest FE frequencies [rad/s] with w = 0 at both ends."""
    x = beam_nodes(beam.length_m, n_elements)
    k, m = beam_matrices(beam, x)
    keep = np.setdiff1d(np.arange(2 * len(x)), [0, 2 * len(x) - 2])
    lam = sla.eigh(k[np.ix_(keep, keep)], m[np.ix_(keep, keep)], eigvals_only=True)
    return np.sqrt(lam[:n])


@pytest.mark.parametrize(
    ("shear", "rotary", "order", "bound"),
    [
        (True, True, 2.0, 6e-4),
        (True, False, 2.0, 6e-4),
        (False, True, 4.0, 1e-5),
        (False, False, 4.0, 1e-5),
    ],
)
def test_element_converges_to_the_simply_supported_closed_form(shear, rotary, order, bound):
    """The simply supported beam's frequencies solve (kGA a^2 - rho A w^2)(EI a^2 + kGA -
    rho I w^2) = (kGA a)^2, a = n pi / L (simply_supported_omega; with each term on or off).
    The element's frequency error of the first five modes falls with the element size at the
    rate of its interpolation: h^2 with shear (one constant shear strain per element), h^4
    without (the Hermite cubic). The fitted rates between 25 and 50 elements must be within
    0.3 of these (measured 2.03-2.04 and 3.99-4.01), and at 50 elements the errors below
    6e-4 and 1e-5 (measured at most 5.7e-4 and 6.7e-6, mode 5): a wrong mass or stiffness
    term stalls the rate or shifts a frequency by far more."""
    beam = replace(BEAM, shear_deformation=shear, rotary_inertia=rotary)
    exact = np.array([simply_supported_omega(beam, n) for n in range(1, 6)])
    err = {ne: np.abs(_simply_supported_fe(beam, ne, 5) / exact - 1.0) for ne in (25, 50)}
    rate = np.log2(err[25] / err[50])
    assert np.all(np.abs(rate - order) < 0.3), rate
    assert err[50].max() < bound


def test_slender_free_free_beam_approaches_euler_bernoulli():
    """At L / h = 1000 the shear and rotary-inertia corrections are ~ (beta r)^2 (1 +
    E / kappa G) < 1e-4 (r = h / sqrt 12): the first four elastic free-free frequencies must
    be Euler-Bernoulli's (beta L = 4.7300, 7.8532, 10.9956, 14.1372) within 1e-4, and below
    them. The roots of cos(bL) cosh(bL) = 1 match Blevins' table to its 7 digits."""
    for n, table in enumerate((4.7300407, 7.8532046, 10.9956078, 14.1371655), start=1):
        assert abs(euler_bernoulli_free_free_beta(n) - table) < 1e-7
    slender = replace(BEAM, length_m=10.0)
    modes = free_free_modes(slender, 200)
    assert np.all(modes.omega[:2] == 0.0)
    eb = np.array(
        [euler_bernoulli_omega(slender, euler_bernoulli_free_free_beta(n)) for n in range(1, 5)]
    )
    ratio = modes.omega[2:6] / eb
    assert np.all(ratio < 1.0) and np.all(ratio > 1.0 - 1e-4), ratio


def test_shear_and_rotary_inertia_lower_the_frequencies_more_for_higher_modes():
    """On the stocky beam (L / h = 20) each correction lowers every free-free frequency below
    Euler-Bernoulli's, both together most, and the relative lowering grows with the mode
    number (the wavelength nears the depth); from the third elastic mode on shear lowers more
    than rotary inertia (on a simply supported beam their first-order ratio is E / kappa G =
    3.1 for every mode; the free ends' large rotation gives rotary inertia the larger share
    of the first two free-free modes: measured 0.51 % against 0.40 % for the first).
    Cowper's kappa for nu = 0.33 is 0.851."""
    assert cowper_rectangle(0.33) == pytest.approx(0.85093, abs=1e-5)
    variants = {
        "eb": replace(BEAM, shear_deformation=False, rotary_inertia=False),
        "rotary": replace(BEAM, shear_deformation=False),
        "shear": replace(BEAM, rotary_inertia=False),
        "timoshenko": BEAM,
    }
    om = {k: free_free_modes(b, 100).omega[2:8] for k, b in variants.items()}
    for one in ("shear", "rotary"):
        assert np.all(om["timoshenko"] < om[one]) and np.all(om[one] < om["eb"])
    assert np.all(om["shear"][2:] < om["rotary"][2:])
    drop = 1.0 - om["timoshenko"] / om["eb"]
    assert np.all(np.diff(drop) > 0), drop


def _impact(beam=BEAM, **kw) -> SphereOnBeam:
    return SphereOnBeam(beam, 0.1, 0.01, M_SPHERE, E_STAR, 0.5, **kw)


def test_momentum_and_energy_are_conserved_through_the_contacts():
    """The sphere's momentum goes into the beam's rigid translation (rho A int w_t dx) and
    nowhere else: over 0.2 ms (the first impact, its release and the second contact) the
    total momentum and energy must stay within 1e-8 of m v0 and of the initial energy; the
    integration (rtol 1e-10, event-to-event) keeps them to ~1e-10 (measured 1.4e-10 and
    6e-9), and a force missing on either body or a lost mode would move them by O(1)."""
    sol = _impact(n_modes=20).solve(0.2e-3, 0.5e-6)
    assert len(sol.contacts) == 2
    p0 = M_SPHERE * 0.5
    assert np.ptp(sol.momentum) < 1e-8 * p0
    assert np.ptp(sol.energy) < 1e-8 * sol.energy[0]
    assert np.all(sol.force >= 0.0)


def test_a_rigid_heavy_beam_gives_hertz_impact_on_a_half_space():
    """A beam 1e6 times denser and 1e4 times stiffer (the contact's E* kept) neither moves nor
    bends: the contact is then Hertz's impact of the sphere on a half-space (theory.hertz:
    peak force, duration 2.94328 delta_max / v). What separates the two is below 1e-5: the
    beam's mass (m* / m - 1 = 6e-7), its compliance (below 1e-6 of Hertz's at the peak),
    the duration factor's six digits (3e-6) and the sampling of the peak on a 0.05 us grid
    (< 1e-6); 1e-4 keeps a margin while a wrong Hertz constant or mass (percents) fails."""
    rigid = replace(BEAM, E_pa=BEAM.E_pa * 1e4, rho_kg_m3=BEAM.rho_kg_m3 * 1e6)
    hz = hertz_impact(0.01, 0.5, E_STAR, M_SPHERE)
    sol = _impact(rigid, n_modes=10).solve(1.2 * hz.duration_s, 0.05e-6)
    assert len(sol.contacts) == 1
    t_close, t_open = sol.contacts[0]
    assert (t_open - t_close) / hz.duration_s == pytest.approx(1.0, abs=1e-4)
    assert sol.force.max() / hz.force_max_n == pytest.approx(1.0, abs=1e-4)
    assert sol.sphere_velocity[-1] == pytest.approx(-0.5, rel=1e-4)


def test_residual_flexibility_makes_few_modes_enough():
    """The quasi-static correction of the modes left out (beam_impact module doc) must give
    the first impact's peak force with 10 modes within 2e-3 of 80 modes (measured 8.4e-4);
    without it the 10-mode peak is off by more than that (measured 3.2 %; 0.26 % still with
    80 modes: the point load's modal series converges as 1 / N once shear dominates)."""
    peak = {
        (n, r): _impact(n_modes=n, residual_flexibility=r).solve(0.1e-3, 0.25e-6).force.max()
        for n, r in ((10, True), (80, True), (10, False))
    }
    assert abs(peak[10, True] / peak[80, True] - 1.0) < 2e-3
    assert abs(peak[10, False] / peak[80, True] - 1.0) > 2e-3


def test_bad_input_is_one_line():
    with pytest.raises(InputError, match="contact_x_m: expected inside the beam"):
        _impact().__class__(BEAM, 0.3, 0.01, M_SPHERE, E_STAR, 0.5)
    with pytest.raises(InputError, match="method: expected one of"):
        _impact().solve(1e-4, 1e-6, method="Euler")
    with pytest.raises(InputError, match="nu: expected"):
        replace(BEAM, nu=0.7)
