"""Drives and prescribed motions (issue 35): the time histories, the driven revolute joint's
row and torque, prescribed paths of a point and of a frame, against closed forms.

Rigid bodies of five point masses (FlexibleBody.build with an empty basis); theta = 1/2 (the
implicit midpoint rule: second order). The whole file runs in ~15 s on the shared 2-core
machine (the simulations: 60 to 240 steps of a rigid body each)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.integrate import quad

from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.rotation import axis_angle, expm_so3
from flexmvm.constraints.drives import DrivenAngle, driven_revolute_joint
from flexmvm.constraints.joints import BodyPoint
from flexmvm.constraints.prescribed import PrescribedPath, prescribed_frame
from flexmvm.errors import InputError
from flexmvm.integrate.driver import simulate
from flexmvm.integrate.run_result import TimeGrid
from flexmvm.integrate.state import BodyState
from flexmvm.integrate.system import System
from flexmvm.time_functions import Constant, Integral, SpinUp, Table

G = 9.81  # [m/s^2]
ARM = 0.5  # pendulum: distance of the masses' centre from the pivot [m]
MASS = 1.0  # five point masses of 0.2 kg [kg]


def _masses(centre) -> FlexibleBody:
    """Five 0.2 kg point masses: one at ``centre`` (frame coordinates [m]) and four 10 mm
    around it in x and y (a rigid body, nq = 0)."""
    c = np.asarray(centre, float)
    X = c + np.array([[0, 0, 0], [0.01, 0, 0], [-0.01, 0, 0], [0, 0.01, 0], [0, -0.01, 0]])
    return FlexibleBody.build("p", X, sp.diags([0.2] * 5), np.zeros((15, 0)), np.zeros((0, 0)))


def _at_rest(body, r=(0.0, 0.0, 0.0)) -> list[BodyState]:
    return [BodyState(np.asarray(r, float), np.eye(3), np.zeros(0), np.zeros(body.nv))]


def test_table_values_rates_and_integrals():
    """A piecewise-linear table against its hand values: f, f' (right-sided at knots, zero
    outside), int_0^t f (trapezoids; the held end values outside): exact to round-off (1e-15)."""
    f = Table.of_rows([[0.0, 0.0], [1.0, 2.0], [3.0, -1.0]])
    cases = {  # t: (f, f', int_0^t f)
        -1.0: (0.0, 0.0, 0.0),
        0.5: (1.0, 2.0, 0.25),
        1.0: (2.0, -1.5, 1.0),
        2.0: (0.5, -1.5, 2.25),
        4.0: (-1.0, 0.0, 1.0),
    }
    for t, (v, r, i) in cases.items():
        assert (f.value(t), f.rate(t), f.integral(t)) == pytest.approx((v, r, i), abs=1e-15)
    vec = Table.of_rows([[0.0, 0.0, 0.0, 0.0], [2.0, 2.0, 4.0, -2.0]], width=3)
    np.testing.assert_allclose(vec.value(1.0), [1.0, 2.0, -1.0], atol=1e-15)
    np.testing.assert_allclose(Integral(vec).value(2.0), [2.0, 4.0, -2.0], atol=1e-15)


def test_spin_up_derivatives_and_integral():
    """SpinUp (Kane et al. 1987): f' and f'' against central differences of f and f' (step
    1e-6 s: error ~1e-12 f''', bound 1e-8), int_0^t f against adaptive quadrature (1e-12),
    the steady value f_s and the angle f_s (t - T/2) after T exactly."""
    f = SpinUp(5.0, 2.0)
    d = 1e-6
    for t in (0.3, 1.0, 1.7):
        assert f.rate(t) == pytest.approx((f.value(t + d) - f.value(t - d)) / (2 * d), abs=1e-8)
        fd = (f.rate(t + d) - f.rate(t - d)) / (2 * d)
        assert f.acceleration(t) == pytest.approx(fd, abs=1e-8)
        assert f.integral(t) == pytest.approx(quad(f.value, 0.0, t)[0], abs=1e-12)
    assert f.value(2.5) == 5.0 and f.rate(2.5) == 0.0
    assert f.integral(3.0) == pytest.approx(5.0 * (3.0 - 1.0), abs=1e-14)


@pytest.mark.parametrize(
    ("rows", "words"),
    [
        ([[0.0, 1.0]], "at least 2 rows"),
        ([[0.0, 1.0], [0.0, 2.0]], "times must increase strictly, got t = 0.0 then 0.0"),
        ([[0.0, 1.0, 2.0], [1.0, 2.0, 3.0]], "expected rows [t_s, 1 value(s)]"),
        ([[0.0, math.nan], [1.0, 2.0]], "every entry must be finite"),
    ],
)
def test_bad_tables_are_one_line_errors(rows, words):
    with pytest.raises(InputError) as info:
        Table.of_rows(rows)
    assert words in str(info.value) and "\n" not in str(info.value)


def test_drive_row_is_the_derivative_of_its_angle():
    """Phi_v v + phi_t = d phi / d t along any motion, the axes of the two bodies not aligned
    (the row is exact, not only for the revolute's aligned axes): central difference of phi
    over +-1e-6 s of a random motion, agreement 1e-8 (the difference's error ~1e-12 phi''')."""
    rng = np.random.default_rng(3)
    bodies = [_masses((0, 0, 0)), _masses((0, 0, 0))]
    A1, A2 = expm_so3(rng.normal(size=3)), expm_so3(rng.normal(size=3))
    place = [BodyState(np.zeros(3), A, np.zeros(0), np.zeros(6)) for A in (A1, A2)]
    drive = DrivenAngle.at_placement("d", 0, 1, [0.3, 0.2, 1.0], place, Integral(SpinUp(3.0, 1.0)))
    tilt = expm_so3(0.3 * rng.normal(size=3))
    w = [rng.normal(size=3), rng.normal(size=3)]
    t, d = 0.4, 1e-6

    def states(s):
        return [
            BodyState(np.zeros(3), A @ expm_so3(wb * s), np.zeros(0), np.r_[0, 0, 0, wb])
            for A, wb in ((tilt @ A1, w[0]), (A2, w[1]))
        ]

    dphi = (
        drive.evaluate(bodies, states(d), t + d)[0] - drive.evaluate(bodies, states(-d), t - d)[0]
    ) / (2 * d)
    _, rows = drive.evaluate(bodies, states(0.0), t)
    rate = rows.times([s.v for s in states(0.0)]) + drive.time_rate(bodies, states(0.0), t)
    np.testing.assert_allclose(rate, dphi, rtol=0, atol=1e-8)


def test_angle_is_unwrapped_across_pi():
    """A body turned about the drive's axis through two turns while the drive prescribes the
    same angle: the measured relative angle (angle_p + phi) follows without a jump at +-pi
    (round-off: 1e-12), and with the body 0.1 rad ahead it reads 0.1 rad ahead throughout."""
    body = _masses((0, 0, -ARM))
    place = _at_rest(body)
    drive = DrivenAngle.at_placement("d", 0, None, [0, 1, 0], place, Integral(Constant(1.0)))
    for t in np.linspace(0.0, 4 * math.pi, 97):
        for ahead in (0.0, 0.1):
            st = [
                BodyState(np.zeros(3), axis_angle([0, 1, 0], t + ahead), np.zeros(0), np.zeros(6))
            ]
            assert drive.relative_angle(st, t) == pytest.approx(t + ahead, abs=1e-12)
            assert drive.evaluate([body], st, t)[0][0] == pytest.approx(ahead, abs=1e-12)


def _pendulum_run(angle, t_end, h, output_dt):
    """A pendulum (five 0.2 kg masses 0.5 m below the pivot) on a revolute joint about the
    global y axis driven by ``angle``, under gravity, starting at the drive's speed (a start
    that violates the drive is an impulse, and at theta = 1/2 a velocity alternating about
    the drive's ever after); (run, I about the pivot)."""
    body = _masses((0, 0, -ARM))
    states = _at_rest(body)
    states[0].v[4] = angle.rate(0.0)
    joints = driven_revolute_joint(
        BodyPoint(0, local=(0, 0, 0)), np.zeros(3), (0, 1, 0), states, angle, "motor"
    )
    system = System((body,), tuple(joints), (), np.array([0.0, 0.0, -G]))
    res = simulate(system, states, TimeGrid(t_end, h, h, output_dt, theta=0.5))
    return res, body.inv.G0[0, 0] + body.inv.G0[2, 2]


def _swing_angle(res) -> np.ndarray:
    """The frames' rotation about +y from the outputs [rad], unwrapped."""
    return np.unwrap([math.atan2(A[0, 2], A[2, 2]) for A in res.frame_A[:, 0]])


def test_driven_pendulum_torque_and_spin_up_angle():
    """Spin-up of the drive's speed to 2 rad/s over T = 0.5 s, then steady, gravity on. Closed
    form: tau = I alpha + m g l sin(theta) (I = m l^2 + the masses' spread, about the pivot).
    The recorded torque is the drive row's impulse over each output interval, compared with the
    exact interval mean I (w_b - w_a)/D + (m g l / D) int sin(theta) dt. The midpoint rule's
    error is second order: its velocities carry e_n+1 = -e_n - h^2 w''/6 (the trapezoid error
    of the position-level closure) and its impulse the midpoint quadrature's h^3/24 (m g l
    sin theta)'' per step, so the error bound is C h^2 with C = I max|w''| / (3 D) +
    m g l max|(sin theta)''| / 24: checked at h = 12.5 and 6.25 ms (measured 2.4e-3 and
    6.1e-4 N m, 0.18 of the bound, on a torque of ~5 N m; ratio 4.0). The angle follows
    the prescription to round-off (the step closes phi to 1e-12)."""
    angle = Integral(SpinUp(2.0, 0.5))
    D = 0.05  # output interval [s]
    t_end = 0.6
    errors = []
    steps = (12.5e-3, 6.25e-3)  # [s]
    for h in steps:
        res, inertia = _pendulum_run(angle, t_end, h, D)
        t = res.t
        exact = [
            (
                inertia * (angle.rate(b) - angle.rate(a))
                + MASS * G * ARM * quad(lambda s: math.sin(angle.value(s)), a, b)[0]
            )
            / D
            for a, b in itertools.pairwise(t)
        ]
        errors.append(np.abs(res.drive_torque["motor"][1:] - exact).max())
        np.testing.assert_allclose(
            _swing_angle(res), [angle.value(s) for s in t], rtol=0, atol=1e-11
        )
    s = np.linspace(0.0, t_end, 6001)
    w2 = np.abs([SpinUp(2.0, 0.5).acceleration(x) for x in s]).max()
    sin2 = np.abs(np.gradient(np.gradient(np.sin([angle.value(x) for x in s]), s), s)).max()
    bound = (inertia * w2 / (3 * D) + MASS * G * ARM * sin2 / 24) * np.array(steps) ** 2
    assert np.all(np.array(errors) < bound), (errors, bound)
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.05)


def test_driven_pendulum_turns_through_pi():
    """A drive at a constant 20 rad/s turns the pendulum through three turns (past +-pi six
    times): the angle follows the prescription to round-off (no jump), and the torque is the
    mean of m g l sin(theta) over each output interval (alpha = 0) to the midpoint quadrature's
    h^2 w^2 / 24 = 1.7e-3 relative at h = 10 ms (w h = 0.2 rad): bound 2e-3 m g l."""
    angle = Integral(Constant(20.0))
    h = 1e-2
    res, _ = _pendulum_run(angle, 1.0, h, h)
    t = res.t
    np.testing.assert_allclose(_swing_angle(res), 20.0 * t, rtol=0, atol=1e-10)
    mean = [(math.cos(20 * a) - math.cos(20 * b)) / (20 * h) for a, b in itertools.pairwise(t)]
    tau = res.drive_torque["motor"][1:] / (MASS * G * ARM)
    assert np.abs(tau - mean).max() < 2e-3


def test_point_on_a_velocity_table_and_a_frame_on_a_path():
    """A free rigid body's centre of mass on a path given by a table of velocities (piecewise
    linear: constant acceleration on each segment), under gravity: its position is the
    table's integral to round-off (1e-12 m), and the path's force on each output interval
    within a segment is m (a - g) to 1e-9 relative (the midpoint rule integrates constant
    accelerations exactly). Then the same body's frame on a displacement table while turning
    about z at 3 rad/s: position and rotation follow to round-off."""
    body = _masses((0, 0, 0))
    states = _at_rest(body)
    table = Table.of_rows([[0.0, 0, 0, 0], [0.2, 1.0, 0, 0.5], [0.4, 1.0, -1.0, 0.5]], width=3)
    path = PrescribedPath(BodyPoint(0, local=(0, 0, 0)), np.zeros(3), Integral(table))
    system = System((body,), (path,), (), np.array([0.0, 0.0, -G]))
    h = 0.01
    res = simulate(system, states, TimeGrid(0.4, h, h, 0.05, theta=0.5))
    np.testing.assert_allclose(
        res.frame_r[:, 0], [Integral(table).value(s) for s in res.t], rtol=0, atol=1e-12
    )
    a1 = np.array([5.0, 0.0, 2.5])  # first segment's acceleration [m/s^2]
    force = res.joint_force[1:5]  # outputs at 0.05 ... 0.2 s: inside the first segment
    # the multiplier is the force on the body (phi = x - x_p: Phi^T lambda = lambda)
    np.testing.assert_allclose(force, np.tile(MASS * (a1 - [0, 0, -G]), (4, 1)), rtol=1e-9)

    disp = Table.of_rows([[0.0, 0, 0, 0], [0.4, 0.2, 0.1, 0.0]], width=3)
    joints = prescribed_frame(
        BodyPoint(0, local=(0, 0, 0)),
        disp,
        (0, 0, 1),
        Integral(Constant(3.0)),
        states,
        [body],
        "frame",
    )
    res = simulate(System((body,), tuple(joints)), states, TimeGrid(0.4, h, h, 0.05, theta=0.5))
    np.testing.assert_allclose(
        res.frame_r[:, 0], [disp.value(s) for s in res.t], rtol=0, atol=1e-12
    )
    for A, s in zip(res.frame_A[:, 0], res.t, strict=True):
        np.testing.assert_allclose(A, axis_angle([0, 0, 1], 3.0 * s), rtol=0, atol=1e-11)
