"""Thornton's (1997) restitution of an elastic-perfectly plastic sphere on a flat
(flexmvm.theory.thornton) against its own force-approach law and against Hertz.

- e = 1 at and below the yield velocity, continuous there, strictly decreasing past it.
- The asymptote: e (v / v_y)^(1/4) -> (6 sqrt3 / 5)^(1/2) (2 sqrt(6/5))^(-1/4) = 1.18499
  (Thornton's 1.185, to his three digits), approached with the first correction of the
  closed form, -(v_y / v) / (8 sqrt(6/5)) relative (checked to 1e-3 of that correction at
  v / v_y = 1e4, where the next term is ~1e-4 of it).
- The closed form against the model it summarises, recomputed by quadrature: Hertz loading
  to alpha_y, then F = F_y + pi p_y R (alpha - alpha_y) up to the approach where the work
  equals 1/2 m* v^2 (root of the integrated work), then Hertz unloading with the radius
  R_p = 4 E* a_p^3 / (3 F*), a_p^2 = R alpha*; e^2 = unloading work / initial energy.
  Quadrature and root to ~1e-13 (measured: e and F* agree to 2e-15 at v / v_y = 1.5-1000),
  so 1e-10 relative on e and F*; a wrong constant in the closed form moves e by >= 1e-3.
- v_y is Hertz's speed for a peak pressure p_y: hertz_impact at v_y gives p0 = 1.61 Y to
  round-off (1e-12), and against theory.hertz_yield's von Mises onset (p0 = 1.613 Y at
  nu = 0.3, computed; Johnson's 1.60 to two digits) the two speeds differ by exactly
  (1.61 / 1.613)^(5/2) = 0.996, the ratio of the two onset pressures to the power 5/2
  (v_y ~ p_y^(5/2)), to 1e-12.
Runs in well under a second.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from flexmvm.errors import InputError
from flexmvm.theory.hertz import hertz_impact
from flexmvm.theory.hertz_yield import yield_onset
from flexmvm.theory.thornton import (
    ASYMPTOTE,
    ONSET_PRESSURE_RATIO,
    peak_force_ratio,
    restitution,
    yield_velocity,
)

# a 10 mm steel ball on aluminium (any positive values do: e depends on v / v_y only)
R, E_STAR, M, Y = 0.01, 70e9, 0.033, 276e6


def test_elastic_up_to_yield_velocity_then_decreasing():
    below = np.array([1e-3, 0.1, 0.5, 0.999, 1.0])
    np.testing.assert_array_equal(restitution(below), 1.0)
    assert restitution(1.0) == 1.0 and isinstance(restitution(1.0), float)
    # continuous at v_y: the closed form itself is 1 there (to round-off)
    assert restitution(1.0 + 1e-9) == pytest.approx(1.0, abs=1e-8)
    s = np.geomspace(1.0, 1e4, 400)
    e = restitution(s)
    assert np.all(np.diff(e) < 0.0)
    assert 0.0 < e[-1] < e[0]


def test_asymptote_is_thorntons():
    assert ASYMPTOTE == pytest.approx(1.185, abs=5e-4)
    s = 1e4
    rel = restitution(s) * s**0.25 / ASYMPTOTE - 1.0
    first = -(1.0 / s) / (8.0 * math.sqrt(1.2))
    assert rel / first == pytest.approx(1.0, abs=1e-3)


def _model_restitution(speed_ratio: float) -> tuple[float, float]:
    """e and F* / F_y by quadrature of Thornton's force-approach law (module doc)."""
    p_y = ONSET_PRESSURE_RATIO * Y
    a_y = math.pi * p_y * R / (2.0 * E_STAR)
    alpha_y = a_y**2 / R
    f_y = 4.0 / 3.0 * E_STAR * math.sqrt(R) * alpha_y**1.5
    assert f_y == pytest.approx(2.0 / 3.0 * math.pi * p_y * a_y**2, rel=1e-12)
    energy = 0.5 * M * (speed_ratio * yield_velocity(R, E_STAR, M, Y)) ** 2

    def loading(alpha):
        if alpha <= alpha_y:
            return 4.0 / 3.0 * E_STAR * math.sqrt(R) * alpha**1.5
        return f_y + math.pi * p_y * R * (alpha - alpha_y)

    def work(alpha):
        w, _ = quad(loading, 0.0, min(alpha, alpha_y), epsabs=0, epsrel=1e-13)
        if alpha > alpha_y:
            w += quad(loading, alpha_y, alpha, epsabs=0, epsrel=1e-13)[0]
        return w - energy

    alpha_max = brentq(work, 1e-3 * alpha_y, 10 * alpha_y * speed_ratio**2, xtol=1e-16 * alpha_y)
    f_max = loading(alpha_max)
    a_p = math.sqrt(R * alpha_max)
    r_p = 4.0 * E_STAR * a_p**3 / (3.0 * f_max)
    rebound = a_p**2 / r_p  # the approach recovered on unloading
    alpha_p = alpha_max - rebound
    w_back, _ = quad(
        lambda alpha: 4.0 / 3.0 * E_STAR * math.sqrt(r_p) * (alpha - alpha_p) ** 1.5,
        alpha_p,
        alpha_max,
        epsabs=0,
        epsrel=1e-13,
    )
    return math.sqrt(w_back / energy), f_max / f_y


@pytest.mark.parametrize("speed_ratio", [1.5, 3.0, 10.0, 100.0])
def test_closed_form_is_the_models_energy_balance(speed_ratio):
    e, force = _model_restitution(speed_ratio)
    assert restitution(speed_ratio) == pytest.approx(e, rel=1e-10)
    assert peak_force_ratio(speed_ratio) == pytest.approx(force, rel=1e-10)


def test_yield_velocity_is_hertz_at_the_limiting_pressure():
    v_y = yield_velocity(R, E_STAR, M, Y)
    h = hertz_impact(R, v_y, E_STAR, M)
    p0 = 3.0 * h.force_max_n / (2.0 * math.pi * h.contact_radius_m**2)
    assert p0 == pytest.approx(ONSET_PRESSURE_RATIO * Y, rel=1e-12)
    assert peak_force_ratio(0.5) == pytest.approx(0.5**1.2, rel=1e-12)
    # theory.hertz_yield's von Mises onset: the speed whose Hertz approach is its delta
    onset = yield_onset(Y, E_STAR, R, 0.3)
    v_onset = math.sqrt(16.0 * E_STAR * math.sqrt(R) * onset.delta_m**2.5 / (15.0 * M))
    assert hertz_impact(R, v_onset, E_STAR, M).delta_max_m == pytest.approx(
        onset.delta_m, rel=1e-12
    )
    assert onset.p0_over_y == pytest.approx(1.613, abs=5e-4)
    assert v_y / v_onset == pytest.approx((1.61 / onset.p0_over_y) ** 2.5, rel=1e-12)
    assert yield_velocity(R, E_STAR, M, Y, pressure_ratio=onset.p0_over_y) == pytest.approx(
        v_onset, rel=1e-12
    )


def test_bad_input_is_one_line_error():
    with pytest.raises(InputError, match="speed ratio"):
        restitution(0.0)
    with pytest.raises(InputError, match="speed ratio"):
        peak_force_ratio([1.0, float("nan")])
    with pytest.raises(InputError, match="yield_pa"):
        yield_velocity(R, E_STAR, M, -1.0)
