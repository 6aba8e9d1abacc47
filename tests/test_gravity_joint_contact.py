"""Contact, gravity and a joint in one cheap default-run case (issue 51 item 10): a rigid
pendulum (the shipped aluminium arm, 300 x 20 x 10 mm, on a revolute joint at its pivot
hole) falling under gravity onto a grounded rigid steel sphere near its tip, checked
against the rigid-body answer. 99 steps, about 3 s of CPU (the pendulum's whole event is in
the validation tier: tests/test_validation.py).

The arm lies along -y from the pin, gravity g along +x, the sphere's pole 0.1 mm from the
arm's face at 0.27 m from the pin; the arm starts turning at 2 rad/s about the pin
(rigid_motion). Its mass properties (mass m, centre of mass d from the pin, inertia I_p about
the pin's axis) come from the body's inertia invariants and the pin's point on it. The
rigid-body answers:

- free flight: I_p dw/dt = m g d (the arm turns by 0.4 mrad: cos of it is 1 to 1e-7), so
  w(t) = w0 + (m g d / I_p) t, and K + P constant (no work but gravity's, the pin does none);
- the impact (one step h, the contact impulse J_c at r_c from the pin, r_c the sphere's pole):
  the angular momentum about the pin, I_p (w+ - w-) = -r_c J_c + m g d h, and the pin's
  reaction impulse J_pin = (r_c m d / I_p - 1) J_c (zero at the centre of percussion
  I_p / (m d) = 0.200 m; the pole lies beyond it, so the pin pulls back);
- the scheme's restitution: the position law holds the gap at the step's end,
  g0 + h (theta u+ + (1 - theta) u-) = 0, so e = (1 - theta)/theta - g0 / (theta U h) lies
  in (0, (1 - theta)/theta] for a contact that closes within the step (g0 < (1 - theta) U h);
- the energy ledger closes: what the arm loses at the impact is the contact's work plus the
  scheme's numerical dissipation, the joints do no work.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import flexmvm as fm

MESHES = Path(__file__).resolve().parents[1] / "scenarios" / "meshes"
G = 9.81  # [m/s^2], along +x
W0 = 2.0  # [rad/s] about the pin (z)
R_POLE_Y = 0.270  # the sphere's pole: its centre's y [m] (negated)


def _scenario(gap_m: float = 0.1e-3, t_end_s: float = 0.5e-3):
    steel = {"name": "steel", "E_pa": 210e9, "nu": 0.3, "rho_kg_m3": 7850.0}
    return fm.scenario_from_dict(
        {
            "name": "gravity_pin_stop",
            "gravity_mps2": [G, 0.0, 0.0],
            "time": {
                "t_end_s": t_end_s,
                "dt_s": 0.5e-6,
                "dt_max_s": 16e-6,
                "output_dt_s": 8e-6,
                "output_contact_dt_s": 0.5e-6,
                "hf_damping_time_s": 12.5e-6,
            },
            "bodies": [
                {
                    "name": "arm",
                    "material": "aluminium",
                    "mesh_file": str(MESHES / "arm_300x20x10.msh"),
                    "model": {"kind": "rigid", "reference": "hub"},
                    "placement": {
                        "rotation": {"axis": [0, 0, 1], "angle_deg": -90.0},
                        "rigid_motion": {
                            "angular_velocity_radps": [0, 0, W0],
                            "about_joint": "pin",
                        },
                    },
                },
                {
                    "name": "stop",
                    "material": steel,
                    "mesh_file": str(MESHES / "sphere_r10.msh"),
                    "model": {"kind": "rigid"},
                    "placement": {
                        "position_m": [0.020 + gap_m, -R_POLE_Y, 0.005],
                        "rotation": {"axis": [0, 1, 0], "angle_deg": 90.0},
                    },
                },
            ],
            "joints": [
                {
                    "type": "revolute",
                    "name": "pin",
                    "body": "arm",
                    "node_set": "hub",
                    "axis": [0, 0, 1],
                },
                {"type": "ground", "body": "stop"},
            ],
            "contacts": [{"slave": "stop.front", "master": "arm.surface", "law": "position"}],
        }
    )


@pytest.fixture(scope="module")
def pendulum():
    """The run and the arm's rigid-body data: (run, m, d, I_p, pin's global point)."""
    run = fm.run(_scenario())
    arm, pin = run.built.system.bodies[0], run.built.system.joints[0]
    m, S0, G0 = arm.inv.mass, arm.inv.S0, arm.inv.G0
    xp = np.asarray(pin.p1.X_bar)  # the pin's point in the arm's frame
    I_p = (
        G0[0, 0] + G0[1, 1] - 2.0 * (xp[0] * S0[0] + xp[1] * S0[1]) + m * (xp[0] ** 2 + xp[1] ** 2)
    )
    d = float(np.hypot(*(S0 / m - xp)[:2]))
    return run, m, d, float(I_p), np.asarray(pin.p2)


def test_free_flight_is_the_rigid_pendulum_under_gravity(pendulum):
    """w(t) = w0 + (m g d / I_p) t before the contact to 2e-10 of w0 (measured 2.1e-11: the
    Newton tolerance; alpha = 48.93 rad/s^2), the same rate after it (to 1e-6), and K + P
    constant in both free flights to 1e-6 of K(0) (measured 2.4e-7 and 4.5e-7: the scheme's
    theta = 0.51 on the turning body)."""
    run, m, d, I_p, _ = pendulum
    res = run.result
    assert run.summary["status"] == "completed" and run.summary["steps_on_roundoff_floor"] == 0
    alpha = m * G * d / I_p
    w, t = res.frame_v[:, 0, 5], res.t
    (t_on, t_off), *rest = run.summary["contact_intervals_s"]
    assert not rest  # one impact
    before, after = t < t_on - 1e-9, t > t_off + 1e-9
    assert np.abs(w[before] - (W0 + alpha * t[before])).max() < 2e-10 * W0
    assert abs(np.polyfit(t[after], w[after], 1)[0] / alpha - 1.0) < 1e-6
    E = res.kinetic + res.potential
    assert np.ptp(E[before]) < 1e-6 * res.kinetic[0]
    assert np.ptp(E[after]) < 1e-6 * res.kinetic[0]


def test_impact_is_the_rigid_body_answer(pendulum):
    """Over the contact step: the angular momentum about the pin to 1e-4 of r_c J_c (measured
    1.4e-5: the contact node sits 3.7 um from the pole's lever 0.2696 m), the pin's reaction
    impulse (r_c m d / I_p - 1) J_c = 0.3448 J_c to 5e-4 (measured 6.7e-5), and the scheme's
    restitution between 0 and (1 - theta)/theta = 0.961 (measured 0.822: the contact closed
    7 % of a step's travel into the step)."""
    run, m, d, I_p, pin = pendulum
    res = run.result
    w = res.frame_v[:, 0, 5]
    k = int(np.argmax(res.contact_force))
    h = float(res.t[k] - res.t[k - 1])
    J_c = float(np.sum(res.steps.contact_impulse_Ns))
    assert abs(res.contact_force[k] * h / J_c - 1.0) < 1e-12  # the impulse is that one step's
    r_c = R_POLE_Y + float(pin[1])
    dw = float(w[k] - w[k - 1])
    assert abs(I_p * dw - (-r_c * J_c + m * G * d * h)) < 1e-4 * r_c * J_c
    J_pin = np.abs(res.joint_force[k, :3]) * h  # the pin's force: its first three rows
    assert abs(J_pin[0] / J_c / (r_c * m * d / I_p - 1.0) - 1.0) < 5e-4, J_pin[0] / J_c
    assert J_pin[1] < 1e-3 * J_pin[0]
    theta = run.built.grid.theta
    assert 0.0 < -w[k] / w[k - 1] <= (1.0 - theta) / theta


def test_energy_ledger_closes_through_the_impact(pendulum):
    """The ledger's balance (start = end + contact work lost + numerical dissipation, gravity
    in the potential) to 3e-10 of the start (measured 3.8e-11), the pin's work below 1e-12 J
    (measured 4e-14 J), and the arm's loss over the contact step, 1/2 I_p (w-^2 - w+^2) less
    gravity's work, equal to the contact's work plus the run's numerical dissipation to 1e-5
    of it (measured 2.1e-6: the free flights' K + P drift, above, which the run's dissipation
    also holds)."""
    run, _, _, I_p, _ = pendulum
    res, ledger = run.result, run.summary["energy_ledger"]
    assert ledger["balance_residual_rel_max"] < 3e-10
    assert all(abs(v) < 1e-12 for v in ledger["work_joints_J"].values())
    w = res.frame_v[:, 0, 5]
    k = int(np.argmax(res.contact_force))
    loss = 0.5 * I_p * (w[k - 1] ** 2 - w[k] ** 2) - (res.potential[k] - res.potential[k - 1])
    lost = -ledger["work_contact_J"] + ledger["dissipation_numerical_J"]
    assert abs(lost / loss - 1.0) < 1e-5, (lost, loss)
