"""The closed-form Hertz impact (theory.hertz) against its own definitions and a direct
integration of the Hertz oscillator m* x'' = -4/3 E* sqrt(R) x^1.5 (the same law, solved
numerically): approach and peak force to 1e-6, duration to 1e-4 (the duration factor
2.94328 is given to 6 digits; the integration's error is below 1e-8)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from flexmvm.errors import InputError
from flexmvm.theory.hertz import effective_modulus, hertz_impact


def test_against_the_hertz_oscillator():
    R, v = 0.01, 0.5
    E = effective_modulus(210e9, 0.3, 70e9, 0.33)
    m1 = 7850.0 * 4.0 / 3.0 * math.pi * R**3
    h = hertz_impact(R, v, E, m1)
    k = 4.0 / 3.0 * E * math.sqrt(R)

    def rhs(_t, y):
        return [y[1], -k * max(y[0], 0.0) ** 1.5 / m1]

    out = solve_ivp(
        rhs,
        (0, 4 * h.duration_s),
        [0.0, v],
        rtol=1e-11,
        atol=1e-15,
        dense_output=True,
        events=lambda t, y: y[0] if t > 0 else 1.0,
    )
    t_end = out.t_events[0][0]
    t = np.linspace(0, t_end, 20001)
    x = out.sol(t)[0]
    assert h.delta_max_m == pytest.approx(x.max(), rel=1e-6)
    assert h.force_max_n == pytest.approx(k * x.max() ** 1.5, rel=1e-6)
    assert h.duration_s == pytest.approx(t_end, rel=1e-4)
    assert h.contact_radius_m == pytest.approx(math.sqrt(R * h.delta_max_m))


def test_recoiling_target_and_bad_input():
    E = effective_modulus(210e9, 0.3, 210e9, 0.3)
    heavy = hertz_impact(0.01, 1.0, E, 0.03)
    equal = hertz_impact(0.01, 1.0, E, 0.03, 0.03)
    assert equal.m_star_kg == pytest.approx(0.015)
    # delta ~ m*^(2/5), F ~ m*^(3/5): half the reduced mass
    assert equal.force_max_n == pytest.approx(heavy.force_max_n * 0.5**0.6)
    with pytest.raises(InputError, match="speed_mps: expected a finite number > 0"):
        hertz_impact(0.01, -1.0, E, 0.03)
