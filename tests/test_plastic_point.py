"""J2 material point (flexmvm.plasticity.return_mapping) against closed forms.

Along proportional paths (uniaxial stress, pure shear) the radial return of linear hardening
is exact: each step's stress equals the 1D rate-independent model with the same moduli
(Simo and Hughes 1998, box 1.5, combined linear isotropic/kinematic hardening):

    sigma = E (eps - eps_p),  |sigma - b| <= Y + H_iso a,  b = H_kin eps_p,  a = int |d eps_p|

(uniaxial stress: E, Y, H_iso, H_kin; pure shear: G, Y/sqrt3, H_iso/3, H_kin/3, in tau and
gamma). The 3D point is compared with that model to round-off (relative 1e-12 of Y), and
with the points every textbook names: elastic slope E up to Y, slope E H / (E + H) past it,
elastic unloading, reverse yield at -sigma_max (isotropic) or sigma_max - 2Y (kinematic).
The tangent is checked against central differences of the stress (relative 1e-6: step 1e-7
of the yield strain, truncation and round-off both below 1e-8). Runs in about 1 s.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexmvm.errors import InputError
from flexmvm.materials import Material
from flexmvm.plasticity.material import J2Plasticity
from flexmvm.plasticity.return_mapping import (
    PointState,
    elastic_tangent,
    radial_return,
    von_mises,
)

STEEL = Material(E=200e9, nu=0.3, rho=7800.0, name="steel")
Y = 250e6
EPS_Y = Y / STEEL.E
CASES = {
    "perfect": J2Plasticity(Y),
    "isotropic": J2Plasticity(Y, hardening_pa=10e9),
    "kinematic": J2Plasticity(Y, kinematic_hardening_pa=10e9),
    "combined": J2Plasticity(Y, hardening_pa=4e9, kinematic_hardening_pa=6e9),
}


def _one_d(modulus, yield_stress, h_iso, h_kin, strains):
    """The 1D combined-hardening return mapping (Simo and Hughes box 1.5) along ``strains``."""
    eps_p = back = acc = 0.0
    out = []
    for eps in strains:
        xi = modulus * (eps - eps_p) - back
        f = abs(xi) - (yield_stress + h_iso * acc)
        if f > 0:
            dg = f / (modulus + h_iso + h_kin)
            eps_p += dg * math.copysign(1.0, xi)
            back += h_kin * dg * math.copysign(1.0, xi)
            acc += dg
        out.append(modulus * (eps - eps_p))
    return np.array(out)


def _uniaxial_path(plastic, strains):
    """sigma_xx along eps_xx = strains with the other five stresses held at zero (the lateral
    strains found by Newton on the consistent tangent, to round-off)."""
    state, lateral, out = PointState.virgin(1), np.zeros(5), []
    for eps in strains:
        for _ in range(20):
            strain = np.concatenate([[eps], lateral])[None, :]
            resp = radial_return(STEEL, plastic, strain, state)
            rest = resp.stress[0, 1:]
            if np.max(np.abs(rest)) < 1e-13 * Y:
                break
            lateral = lateral - np.linalg.solve(resp.tangent[0, 1:, 1:], rest)
        else:
            raise AssertionError("lateral strains did not converge")
        state = resp.state
        out.append(resp.stress[0, 0])
    return np.array(out), state


def _path(peak, low, n=40):
    """Load to ``peak``, unload and reverse to ``low``, reload to ``peak`` (strain units)."""
    return np.concatenate(
        [np.linspace(0, peak, n), np.linspace(peak, low, 2 * n), np.linspace(low, peak, 2 * n)]
    )


@pytest.mark.parametrize("name", sorted(CASES))
def test_uniaxial_stress_matches_one_d_return(name):
    plastic = CASES[name]
    strains = _path(5 * EPS_Y, -5 * EPS_Y)
    got, _ = _uniaxial_path(plastic, strains)
    want = _one_d(STEEL.E, Y, plastic.hardening_pa, plastic.kinematic_hardening_pa, strains)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * Y)


@pytest.mark.parametrize("name", sorted(CASES))
def test_pure_shear_matches_one_d_return(name):
    plastic = CASES[name]
    _, mu = STEEL.lame
    gamma_y = Y / math.sqrt(3) / mu
    gammas = _path(4 * gamma_y, -4 * gamma_y)
    state, got = PointState.virgin(1), []
    for g in gammas:
        resp = radial_return(STEEL, plastic, np.array([[0, 0, 0, g, 0, 0]], float), state)
        state = resp.state
        np.testing.assert_allclose(np.delete(resp.stress[0], 3), 0.0, atol=1e-12 * Y)
        got.append(resp.stress[0, 3])
    want = _one_d(
        mu,
        Y / math.sqrt(3),
        plastic.hardening_pa / 3,
        plastic.kinematic_hardening_pa / 3,
        gammas,
    )
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * Y)


def test_uniaxial_textbook_points():
    """Slope E H/(E+H) past yield, elastic unloading, and the reverse yield stress: -sigma_max
    with isotropic, sigma_max - 2Y with kinematic hardening (Bauschinger)."""
    h = 10e9
    e1, e2 = 3 * EPS_Y, 4 * EPS_Y
    for plastic in (CASES["isotropic"], CASES["kinematic"]):
        (s1, s2), _ = _uniaxial_path(plastic, np.linspace(0, e2, 41)[[30, 40]])
        assert (s2 - s1) / (e2 - e1) == pytest.approx(STEEL.E * h / (STEEL.E + h), rel=1e-12)
    strains = np.concatenate([np.linspace(0, e2, 41), np.linspace(e2, -e2, 401)[1:]])
    for plastic, reverse in ((CASES["isotropic"], "iso"), (CASES["kinematic"], "kin")):
        sig, _ = _uniaxial_path(plastic, strains)
        s_max = sig[40]
        unload = sig[41:] - s_max
        slope = unload / (strains[41:] - e2)
        first_plastic = np.argmax(np.abs(slope - STEEL.E) > 1e-6 * STEEL.E)
        assert np.allclose(slope[:first_plastic], STEEL.E, rtol=1e-9)
        # the reverse yield stress lies between the last elastic and the first plastic step
        expected = -s_max if reverse == "iso" else s_max - 2 * Y
        assert sig[41 + first_plastic] <= expected + 1e-9 * Y
        assert sig[41 + first_plastic - 1] >= expected - 1e-9 * Y


@pytest.mark.parametrize("name", sorted(CASES))
def test_consistent_tangent_matches_central_differences(name):
    plastic = CASES[name]
    rng = np.random.default_rng(7)
    n = 40
    # a converged plastic history, then a random increment that yields most points again
    state = radial_return(STEEL, plastic, rng.normal(0, 3 * EPS_Y, (n, 6)), PointState.virgin(n))
    strain = state.state.plastic_strain + rng.normal(0, 3 * EPS_Y, (n, 6))
    resp = radial_return(STEEL, plastic, strain, state.state)
    assert resp.yielding.sum() > n // 2
    h = 1e-7 * EPS_Y
    fd = np.empty((n, 6, 6))
    for j in range(6):
        step = np.zeros(6)
        step[j] = h
        plus = radial_return(STEEL, plastic, strain + step, state.state).stress
        minus = radial_return(STEEL, plastic, strain - step, state.state).stress
        fd[:, :, j] = (plus - minus) / (2 * h)
    scale = np.abs(resp.tangent).max(axis=(1, 2))[:, None, None]
    assert np.max(np.abs(fd - resp.tangent) / scale) < 1e-6


def test_stress_returns_to_yield_surface_and_elastic_tangent_below_it():
    plastic = CASES["isotropic"]
    rng = np.random.default_rng(3)
    strain = rng.normal(0, 4 * EPS_Y, (200, 6))
    resp = radial_return(STEEL, plastic, strain, PointState.virgin(200))
    radius = Y + plastic.hardening_pa * resp.state.equivalent_plastic_strain
    vm = von_mises(resp.stress)
    assert np.allclose(vm[resp.yielding], radius[resp.yielding], rtol=1e-12)
    assert np.all(vm[~resp.yielding] <= Y)
    np.testing.assert_array_equal(
        resp.tangent[~resp.yielding],
        np.broadcast_to(elastic_tangent(STEEL), resp.tangent[~resp.yielding].shape),
    )
    # plastic flow is isochoric: the plastic strain has no trace
    assert np.max(np.abs(resp.state.plastic_strain[:, :3].sum(axis=1))) < 1e-15


def test_bad_input_is_one_line_error():
    with pytest.raises(InputError, match="yield_pa must be > 0"):
        J2Plasticity(0.0)
    with pytest.raises(InputError, match="hardening_pa must be >= 0"):
        J2Plasticity(1e6, hardening_pa=-1.0)
    with pytest.raises(InputError, match="kinematic_hardening_pa must be >= 0"):
        J2Plasticity(1e6, kinematic_hardening_pa=-1.0)
    with pytest.raises(InputError, match="finite"):
        J2Plasticity(float("nan"))
    with pytest.raises(InputError, match="strain must have shape"):
        radial_return(STEEL, CASES["perfect"], np.zeros((3, 5)), PointState.virgin(3))
