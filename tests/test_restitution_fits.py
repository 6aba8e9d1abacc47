"""The FE-fitted sphere-flat law (Jackson and Green 2005 in the form of Ghaednia et al. 2019)
and the restitution it gives with two unloadings (flexmvm.theory.restitution_fits).

No value printed by the papers was at hand (the law was read through an implementation), so
the checks are on the law's own structure and on physics it must respect:

- C(nu), the fitted onset pressure ratio, against theory.hertz_yield's von Mises onset on
  the axis (1.613 Y at nu = 0.3, 1.649 Y at 0.33): within 0.5 % (the fit's constants are
  given to 3-4 digits; measured 0.1 %; a 0.1 change of the exponent 0.736 moves C by 3 %).
- The plastic branch meets Hertz at w = 1.9 (the fit was built to): relative jump < 3e-3
  (measured 1.8e-3; the 4 H / C term alone is 28 % of the force there, so a wrong constant
  in it shows).
- e = 1 up to the speed reaching 1.9 delta_c (both branches Hertz), v_c is Hertz's speed for
  delta_c (1e-10), and past 1.9 delta_c e decreases monotonically.
- The mean pressure F / (pi a^2) at w = 10-100 lies between the onset's 2/3 C Y and the
  fully plastic indentation pressure ~3 Y (Johnson 1985 ch. 6): a loose bound, on purpose.
- The energy balance: 1 - e^2 against the loop area of the loading and unloading curves
  integrated by the trapezoid rule on 200,001 points (error ~1e-9 of the work): to 1e-6.
Runs in about a second.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexmvm.errors import InputError
from flexmvm.theory.hertz import hertz_impact
from flexmvm.theory.hertz_yield import yield_onset
from flexmvm.theory.restitution_fits import (
    ELASTIC_LIMIT,
    FlatteningLaw,
    Unloading,
    critical_pressure_ratio,
    critical_velocity,
    flattening_restitution,
    peak_interference,
)

# the restitution study's block (docs/plasticity.md): rigid R 10 mm sphere, E 70 GPa,
# nu 0.33, Y 620 MPa, m* 2.36 g
R, E, NU, Y, M = 0.010, 70e9, 0.33, 620e6, 2.3553e-3
E_STAR = E / (1.0 - NU**2)
LAW = FlatteningLaw.make(R, E_STAR, Y, NU)


@pytest.mark.parametrize("nu", [0.3, 0.33])
def test_onset_ratio_is_the_von_mises_onset(nu):
    onset = yield_onset(Y, E / (1.0 - nu**2), R, nu).p0_over_y
    assert critical_pressure_ratio(nu) == pytest.approx(onset, rel=5e-3)


def test_plastic_branch_meets_hertz():
    d = ELASTIC_LIMIT * LAW.delta_c
    jump = LAW.force(d * (1.0 + 1e-12)) / LAW.force(d) - 1.0
    assert abs(jump) < 3e-3
    assert LAW.force(d) == pytest.approx(float(LAW.hertz_force(d)), rel=1e-14)


def test_elastic_below_the_limit_then_decreasing():
    v_c = critical_velocity(LAW, M)
    assert hertz_impact(R, v_c, E_STAR, M).delta_max_m == pytest.approx(LAW.delta_c, rel=1e-10)
    v_limit = v_c * ELASTIC_LIMIT**1.25  # Hertz approach ~ v^(4/5)
    for unloading in Unloading:
        below = flattening_restitution(LAW, M, v_limit * np.array([0.1, 0.5, 0.999]), unloading)
        np.testing.assert_array_equal(below, 1.0)
        e = flattening_restitution(LAW, M, v_limit * np.geomspace(1.01, 200.0, 25), unloading)
        assert np.all(np.diff(e) < 0.0) and 0.0 < e[-1] < e[0] < 1.0


def test_mean_pressure_between_onset_and_fully_plastic():
    for w in (10.0, 30.0, 100.0):
        d = w * LAW.delta_c
        p_mean = LAW.force(d) / (math.pi * float(LAW.contact_radius(d)) ** 2)
        assert 2.0 / 3.0 * LAW.c_ratio * Y < p_mean < 3.0 * Y


@pytest.mark.parametrize("unloading", list(Unloading))
def test_loss_is_the_loop_area(unloading):
    v = 30.0 * critical_velocity(LAW, M)
    energy = 0.5 * M * v * v
    d_m = peak_interference(LAW, energy)
    x = np.linspace(0.0, d_m, 200_001)
    w_load = np.trapezoid(LAW.force(x), x)
    if unloading is Unloading.BRAKE:
        d_r, r_u, _ = LAW.unloading(d_m)
    else:
        d_r, r_u, _ = LAW.unloading_at_contact_radius(d_m)
    xu = np.linspace(d_r, d_m, 200_001)
    w_back = np.trapezoid(4.0 / 3.0 * E_STAR * math.sqrt(r_u) * (xu - d_r) ** 1.5, xu)
    assert w_load == pytest.approx(energy, rel=1e-6)
    e = flattening_restitution(LAW, M, v, unloading)
    assert 1.0 - e * e == pytest.approx((w_load - w_back) / w_load, rel=1e-6)
    # the unloading passes through the peak: F(d_m) on the unloading curve
    f_back = 4.0 / 3.0 * E_STAR * math.sqrt(r_u) * (d_m - d_r) ** 1.5
    assert f_back == pytest.approx(LAW.force(d_m), rel=1e-12)


def test_bad_input_is_an_input_error():
    with pytest.raises(InputError, match="Poisson"):
        FlatteningLaw.make(R, E_STAR, Y, 0.6)
    with pytest.raises(InputError, match="radius_m"):
        FlatteningLaw.make(-R, E_STAR, Y, NU)
    with pytest.raises(InputError, match="speeds"):
        flattening_restitution(LAW, M, [1.0, -2.0])
    with pytest.raises(InputError, match="m_star_kg"):
        flattening_restitution(LAW, 0.0, 1.0)
