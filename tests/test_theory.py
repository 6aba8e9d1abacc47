"""Physics checks of the 1D two-rod wave solution (flexmvm.theory.wave).

Sign convention: global x, rod 1 moves in +x at v0, compressive contact force F >= 0.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexmvm.errors import InputError
from flexmvm.materials import ALUMINIUM, BRASS
from flexmvm.metrics import contact_intervals, impulse, ncc, peak
from flexmvm.theory import (
    ContactLaw,
    Rod1D,
    hertz_stiffness,
    st_venant_force,
    two_rod_impact,
)

V0 = 0.21
R_SPHERE = 0.01


@pytest.fixture(scope="module")
def seed_rods() -> tuple[Rod1D, Rod1D]:
    return (Rod1D.from_material(BRASS, 1.0, 0.01), Rod1D.from_material(ALUMINIUM, 1.0, 0.01))


@pytest.fixture(scope="module")
def seed_rigid(seed_rods):
    return two_rod_impact(*seed_rods, V0, 2.0e-3, ContactLaw.RIGID)


@pytest.fixture(scope="module")
def seed_hertz(seed_rods):
    return two_rod_impact(*seed_rods, V0, 2.0e-3, ContactLaw.HERTZ, sphere_radius_m=R_SPHERE)


def test_rigid_equal_rods_classic():
    """Equal rods, flat ends (St Venant): F = v0 Z/2 exactly for 0 <= t < T = 2L/c, then 0;
    afterwards rod 1 is at rest (near and far end) and rod 2 moves at v0 (near and far end).
    The RIGID solution is exact at the grid instants: tolerance 1e-12 relative on every sample
    more than 2 steps away from a wave front; the contact interval equals T within 2 steps."""
    rod = Rod1D(length_m=1.0, area_m2=1e-4, E=2.0e11, rho=7800.0, nu=0.3)
    big_t, half = rod.round_trip_s, rod.length_m / rod.c
    s = two_rod_impact(rod, rod, V0, 3.0 * big_t, ContactLaw.RIGID)
    dt = s.params.dt
    f_plateau = V0 * rod.impedance / 2.0
    tol = 1e-12
    during = s.t < big_t - 2 * dt
    after = s.t > big_t + 2 * dt
    assert np.allclose(s.contact_force[during], f_plateau, rtol=tol, atol=0)
    assert np.all(s.contact_force[after] == 0.0)
    assert np.allclose(s.v1_near[during], V0 / 2, rtol=tol)
    assert np.allclose(s.v2_near[during], V0 / 2, rtol=tol)
    assert np.allclose(s.v1_near[after], 0.0, atol=tol * V0)
    assert np.allclose(s.v2_near[after], V0, rtol=tol)
    far_after = s.t > half + 2 * dt
    assert np.allclose(s.v1_far[far_after], 0.0, atol=tol * V0)
    assert np.allclose(s.v2_far[far_after], V0, rtol=tol)
    assert np.allclose(s.v2_far[s.t < half - 2 * dt], 0.0, atol=tol * V0)
    ((start, end),) = contact_intervals(s.t, s.contact_force, 0.5 * f_plateau)
    assert start == 0.0
    assert abs(end - big_t) <= 2 * dt
    assert np.all(s.gap_m >= 0.0)


def test_rigid_seed_plateau_and_far_end(seed_rods, seed_rigid):
    """Seed rods, flat ends (Z1 > Z2): first plateau F = v0 Z1 Z2/(Z1+Z2) (619.38 N) for
    0 <= t < T2 = 2L/c2; the far end of rod 2 is at rest until L/c2 and then moves at twice the
    particle velocity F/Z2 = v0 Z1/(Z1+Z2). Exact: tolerance 1e-12 relative away from fronts."""
    r1, r2 = seed_rods
    s = seed_rigid
    dt = s.params.dt
    f_sv = st_venant_force(r1, r2, V0)
    z1, z2 = r1.impedance, r2.impedance
    assert f_sv == pytest.approx(V0 * z1 * z2 / (z1 + z2), rel=1e-15)
    assert f_sv == pytest.approx(619.38, abs=0.01)
    first = s.t < r2.round_trip_s - 2 * dt
    assert np.allclose(s.contact_force[first], f_sv, rtol=1e-12, atol=0)
    ((start, end),) = contact_intervals(s.t, s.contact_force, 0.5 * f_sv)
    assert start == 0.0
    assert abs(end - r2.round_trip_s) <= 2 * dt
    t_arrive = r2.length_m / r2.c
    assert np.all(s.v2_far[s.t < t_arrive - 2 * dt] == 0.0)
    moving = (s.t > t_arrive + 2 * dt) & (s.t < t_arrive + r2.round_trip_s - 2 * dt)
    assert np.allclose(s.v2_far[moving], 2 * f_sv / z2, rtol=1e-12)
    assert np.allclose(s.v2_far[moving], 2 * V0 * z1 / (z1 + z2), rtol=1e-12)


def test_rigid_is_exact_independent_of_dt(seed_rods):
    """The RIGID solution is piecewise constant and computed event by event: sampling it with
    dt and dt/3 gives the same force and velocities at the common instants (to 1e-12), except
    at the samples within one step of a wave front."""
    r1, r2 = seed_rods
    dt = r2.round_trip_s / 999.7
    a = two_rod_impact(r1, r2, V0, 1.5e-3, ContactLaw.RIGID, dt=dt)
    b = two_rod_impact(r1, r2, V0, 1.5e-3, ContactLaw.RIGID, dt=dt / 3)
    n = a.t.size
    fb = b.contact_force[::3][:n]
    vb = b.v2_far[::3][:n]
    assert np.allclose(a.t, b.t[::3][:n], rtol=1e-12)
    mismatch = ~np.isclose(a.contact_force, fb, rtol=1e-12, atol=1e-9)
    mismatch |= ~np.isclose(a.v2_far, vb, rtol=1e-12, atol=1e-12)
    assert np.count_nonzero(mismatch) <= 6


@pytest.mark.parametrize("law", [ContactLaw.RIGID, ContactLaw.HERTZ])
def test_momentum_and_energy_conserved(seed_rods, seed_rigid, seed_hertz, law):
    """Total momentum m1 v0 and energy m1 v0^2/2, integrated over the wave fields (plus the
    Hertz contact energy 2/5 k delta^{5/2}), are conserved at every time; rod 2's momentum
    equals the impulse int F dt delivered so far, and after separation (t_end) equals
    m2 times its mean velocity. Tolerances: RIGID 1e-4 (the wave fronts are sampled on the grid,
    each jump smeared over one step, dt/T = 5e-5); HERTZ 1e-7 (smooth fields, RK4 + linear
    history interpolation)."""
    r1, r2 = seed_rods
    s = seed_rigid if law is ContactLaw.RIGID else seed_hertz
    tol = 1e-4 if law is ContactLaw.RIGID else 1e-7
    p0, e0 = r1.mass * V0, 0.5 * r1.mass * V0**2
    for k in np.searchsorted(s.t, (1.0e-4, 3.0e-4, 5.0e-4, 8.0e-4, 1.3e-3, s.t[-1])):
        t = s.t[k]
        p1, p2 = s.rod_momenta_at(t)
        assert (p1 + p2) == pytest.approx(p0, rel=tol)
        assert s.energy_at(t) == pytest.approx(e0, rel=tol)
        assert p2 == pytest.approx(impulse(s.t[: k + 1], s.contact_force[: k + 1]), abs=tol * p0)
    assert s.momentum_at(0.0) == pytest.approx(p0, rel=tol)
    assert s.energy_at(0.0) == pytest.approx(e0, rel=tol)
    assert s.contact_force[-1000:].max() == 0.0
    mean_v2 = s.rod_momenta_at(s.t[-1])[1] / r2.mass
    assert r2.mass * mean_v2 == pytest.approx(impulse(s.t, s.contact_force), rel=tol)
    assert 0.0 < mean_v2 < 2 * V0


def test_hertz_stiff_limit_approaches_rigid(seed_rods, seed_rigid):
    """Hertz contact with k -> infinity tends to the St Venant solution: the NCC of the force
    histories against RIGID grows with the sphere radius (k ~ sqrt(R)) and exceeds 0.99 at
    R = 1e4 m (k 1000 times the seed's)."""
    r1, r2 = seed_rods
    scores = []
    for radius in (1.0, 100.0, 1.0e4):
        h = two_rod_impact(r1, r2, V0, 1.5e-3, ContactLaw.HERTZ, sphere_radius_m=radius)
        scores.append(ncc(seed_rigid.t, seed_rigid.contact_force, h.t, h.contact_force))
    assert scores[0] < scores[1] < scores[2]
    assert scores[2] > 0.99


def test_hertz_seed_case(seed_rods, seed_hertz):
    """Seed case with R = 0.01 m. The approach obeys d(delta)/dt = v0 - k delta^{3/2}(1/Z1+1/Z2)
    until the first reflection returns at T2, so F rises monotonically towards the St Venant
    plateau 619.38 N without reaching it: peak 615.07 N within 1 % below the plateau, at
    T2 < t_peak < T2 + 10 us; contact radius at the peak a = sqrt(R delta) = 0.461 mm, within 10 %
    of the Hertz estimate sqrt(R (F_sv/k)^{2/3}) = 0.46 mm."""
    r1, r2 = seed_rods
    s = seed_hertz
    f_sv = st_venant_force(r1, r2, V0)
    t_peak, f_peak = peak(s.t, s.contact_force)
    assert 0.99 * f_sv < f_peak < f_sv
    assert r2.round_trip_s < t_peak < r2.round_trip_s + 10e-6
    i = int(np.argmax(s.contact_force))
    a_peak = math.sqrt(R_SPHERE * -s.gap_m[i])
    a_est = math.sqrt(R_SPHERE * (f_sv / hertz_stiffness(r1, r2, R_SPHERE)) ** (2.0 / 3.0))
    assert a_est == pytest.approx(0.46e-3, rel=0.01)
    assert a_peak == pytest.approx(a_est, rel=0.10)
    assert f_peak == pytest.approx(s.params.hertz_k * (-s.gap_m[i]) ** 1.5, rel=1e-12)
    rise = s.contact_force[s.t <= t_peak]
    assert np.all(np.diff(rise[s.t[: rise.size] < r2.round_trip_s]) >= 0.0)


def test_hertz_dt_convergence(seed_rods):
    """Peak force of the seed Hertz case changes by < 1e-4 relative when dt is halved
    (T2/5000 -> T2/10000), and the approach history converges at least at first order."""
    r1, r2 = seed_rods
    runs = [
        two_rod_impact(
            r1, r2, V0, 8.0e-4, ContactLaw.HERTZ, sphere_radius_m=R_SPHERE, dt=r2.round_trip_s / div
        )
        for div in (2500, 5000, 10000)
    ]
    peaks = [peak(s.t, s.contact_force)[1] for s in runs]
    assert abs(peaks[2] - peaks[1]) / peaks[2] < 1e-4
    t_probe = np.linspace(0.0, 7.9e-4, 80)
    gaps = [np.interp(t_probe, s.t, s.gap_m) for s in runs]
    e1 = np.max(np.abs(gaps[0] - gaps[2]))
    e2 = np.max(np.abs(gaps[1] - gaps[2]))
    assert e2 < e1
    assert e2 < 1e-6 * np.max(np.abs(gaps[2]))


def test_rod_validation_and_arguments(seed_rods):
    """Bad inputs raise one-line InputErrors naming what was received."""
    r1, r2 = seed_rods
    for kwargs in (
        {"length_m": 0.0},
        {"area_m2": -1.0},
        {"E": float("nan")},
        {"rho": "x"},
        {"nu": 0.5},
    ):
        base = {"length_m": 1.0, "area_m2": 1e-4, "E": 1e11, "rho": 8000.0, "nu": 0.3} | kwargs
        with pytest.raises(InputError) as err:
            Rod1D(**base)
        assert "\n" not in str(err.value)
    with pytest.raises(InputError, match="sphere_radius_m"):
        two_rod_impact(r1, r2, V0, 1e-3, ContactLaw.HERTZ)
    with pytest.raises(InputError, match="sphere_radius_m"):
        two_rod_impact(r1, r2, V0, 1e-3, ContactLaw.RIGID, sphere_radius_m=0.01)
    with pytest.raises(InputError, match="dt"):
        two_rod_impact(r1, r2, V0, 1e-3, ContactLaw.RIGID, dt=1e-5)
    with pytest.raises(InputError, match="v0"):
        two_rod_impact(r1, r2, -V0, 1e-3, ContactLaw.RIGID)
    with pytest.raises(InputError, match="law"):
        two_rod_impact(r1, r2, V0, 1e-3, "rigid")
    s = two_rod_impact(r1, r2, V0, 1e-4, ContactLaw.RIGID)
    with pytest.raises(InputError, match="outside"):
        s.energy_at(1.0)
