"""Drives, paths and initial motion in scenario files (issue 35): their keys' one-line errors,
the initial motion about a point or a joint's pivot, the error for initial velocities that
violate a joint, and a driven spin-up of a flexible (full FE) arm on a coarse tet4 mesh.

The schema tests take < 0.1 s each; the arm's mesh (gmsh, module fixture) ~1 s; the builds
~1 s each; the flexible spin-up ~7 s on the shared 2-core machine (100 steps of 0.2 ms)."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import h5py
import numpy as np
import pytest

import flexmvm as fm
from flexmvm.assembly.build import build_scenario
from flexmvm.errors import InputError
from flexmvm.results.writers import write_results_h5
from flexmvm.scenarios import ScenarioError, scenario_from_dict

pytest.importorskip("gmsh")

from flexmvm.mesh import parts

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
ROD_IMPACT = tomllib.loads((SCENARIOS / "rod_impact.toml").read_text())
SPIN = {"spin_up": {"final": 20.0, "duration_s": 0.02}}  # [rad/s], [s]
SPIN_DRIVE = {"angular_velocity_radps": SPIN}


def _with_joint(joint: dict, **placement) -> dict:
    """rod_impact with one joint on b2 (and b2's placement replaced by ``placement``)."""
    data = {**ROD_IMPACT, "joints": [joint]}
    bodies = [dict(b) for b in data["bodies"]]
    if placement:
        bodies[1]["placement"] = placement
    return {**data, "bodies": bodies}


def _error(data: dict) -> str:
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(data, "dict")
    assert "\n" not in str(info.value)
    return str(info.value)


REV = {"type": "revolute", "body": "b2", "point_m": [0, 0, 0], "ground_m": [0, 0, 0]}
REV_AXIS = {**REV, "axis": [0, 0, 1]}


@pytest.mark.parametrize(
    ("joint", "placement", "expected"),
    [
        (
            {"type": "ground", "body": "b2", "drive": {"angle_rad": {"constant": 0.0}}},
            {},
            "dict: joints[0].drive: not used by a 'ground' joint",
        ),
        (
            {**REV_AXIS, "drive": {"angle_rad": {"constant": 0.1}}},
            {},
            (
                "dict: joints[0].drive.angle_rad: must be 0 rad at t = 0 (the joint's placement), "
                "got 0.1"
            ),
        ),
        (
            {**REV_AXIS, "drive": {"angular_velocity_radps": {"table": [[0.0, 1.0], [0.0, 2.0]]}}},
            {},
            (
                "dict: joints[0].drive.angular_velocity_radps.table: times must increase strictly, "
                "got t = 0.0 then 0.0"
            ),
        ),
        (
            {**REV_AXIS, "drive": {"angle_rad": {"constant": 0.0}, "angular_velocity_radps": SPIN}},
            {},
            (
                "dict: joints[0].drive: give exactly one of angle_rad, angular_velocity_radps, got "
                "['angle_rad', 'angular_velocity_radps']"
            ),
        ),
        (
            {
                "type": "prescribed",
                "body": "b2",
                "point_m": [0, 0, 0],
                "velocity_mps": [1, 0, 0],
                "path": {"velocity_mps": [[0, 0, 0, 0], [1, 1, 0, 0]]},
            },
            {},
            "dict: joints[0].path: give one of velocity_mps (constant) and path (a table), not both",
        ),
        (
            {
                "type": "prescribed",
                "body": "b2",
                "point_m": [0, 0, 0],
                "path": {"displacement_m": [[0, 0, 0, 1e-3], [1, 1, 0, 0]]},
            },
            {},
            (
                "dict: joints[0].path.displacement_m: must be [0, 0, 0] at t = 0 (the point's "
                "placement), got [0.0, 0.0, 0.001]"
            ),
        ),
        (
            {
                "type": "prescribed",
                "body": "b2",
                "point_m": [0, 0, 0],
                "velocity_mps": [1, 0, 0],
                "drive": {"angular_velocity_radps": SPIN},
            },
            {},
            "dict: joints[0].axis: required by a 'prescribed' joint",
        ),
        (
            {**REV_AXIS, "name": "pin"},
            {"rigid_motion": {"about_joint": "pin"}, "angular_velocity_radps": [0, 0, 1]},
            (
                "dict: bodies[1].placement: give the motion by rigid_motion or by "
                "angular_velocity_radps, not both"
            ),
        ),
        (
            {**REV_AXIS, "name": "pin"},
            {"rigid_motion": {"about_joint": "hinge"}},
            (
                "dict: bodies[1].placement.rigid_motion.about_joint: unknown joint 'hinge' (named "
                "joints: pin)"
            ),
        ),
    ],
)
def test_drive_and_motion_keys_errors(joint, placement, expected):
    assert _error(_with_joint(joint, **placement)) == expected


def test_duplicate_joint_names():
    data = {**ROD_IMPACT, "joints": [{**REV_AXIS, "name": "pin"}, {**REV_AXIS, "name": "pin"}]}
    assert _error(data) == "dict: joints[1].name: duplicate joint name 'pin' (also joints[0])"


@pytest.fixture(scope="module")
def arm_mesh(tmp_path_factory) -> Path:
    """A coarse tet4 arm (aluminium 300 x 20 x 10 mm on a hub R 15 mm, pivot hole R 5 mm,
    10 mm elements): its hole face is the node set ``hub``."""
    d = tmp_path_factory.mktemp("drives")
    return parts.arm(d / "arm.msh", 0.300, 0.020, 0.010, 0.015, 0.005, 0.010)


def _arm(mesh: Path, model: dict, placement: dict, joints: list, t_end=1e-3, dt=1e-4) -> dict:
    return {
        "name": "arm_drive",
        "time": {"t_end_s": t_end, "dt_s": dt, "output_dt_s": dt, "theta": 0.5},
        "bodies": [
            {
                "name": "arm",
                "mesh_file": str(mesh),
                "material": "aluminium",
                "model": {"reference": "hub", **model},
                "placement": placement,
            }
        ],
        "joints": joints,
    }


TIP_PIN = {
    "type": "revolute",
    "name": "pin",
    "body": "arm",
    "point_m": [0.29, 0.0, 0.005],
    "axis": [0, 0, 1],
}


def test_initial_motion_about_a_joint_pivot_and_a_point(arm_mesh):
    """A rigid arm placed at r_O = (1, 2, 0) m turned 90 deg about z, pinned at a point 0.29 m
    along it: its initial motion about the pin (w = 3 rad/s about z) gives the frame
    v_O = w x (r_O - r_P) and omega = A^T w exactly (round-off, 1e-15); about a global point
    with a velocity of that point, v_O = v_P + w x (r_O - r_P)."""
    turned = {"position_m": [1.0, 2.0, 0.0], "rotation": {"axis": [0, 0, 1], "angle_deg": 90.0}}
    A = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    pin_global = np.array([1.0, 2.0, 0.0]) + A @ TIP_PIN["point_m"]
    w = np.array([0.0, 0.0, 3.0])
    motion = {"angular_velocity_radps": list(w), "about_joint": "pin"}
    joint = {**TIP_PIN, "ground_m": list(pin_global)}
    data = _arm(arm_mesh, {"kind": "rigid"}, {**turned, "rigid_motion": motion}, [joint])
    st = build_scenario(scenario_from_dict(data)).states[0]
    np.testing.assert_allclose(st.v[:3], np.cross(w, [1.0, 2.0, 0.0] - pin_global), atol=1e-15)
    np.testing.assert_allclose(st.v[3:6], A.T @ w, atol=1e-15)

    motion = {
        "angular_velocity_radps": list(w),
        "about_m": [0.5, 0.0, 0.0],
        "velocity_mps": [0, 0, 1],
    }
    data = _arm(arm_mesh, {"kind": "rigid"}, {**turned, "rigid_motion": motion}, [])
    st = build_scenario(scenario_from_dict(data)).states[0]
    expected = np.array([0, 0, 1.0]) + np.cross(w, [0.5, 2.0, 0.0])
    np.testing.assert_allclose(st.v[:3], expected, atol=1e-15)


def test_initial_velocities_that_violate_a_joint_are_an_error(arm_mesh):
    """The arm turning about its frame origin (the hub) while pinned 0.29 m away: the pin's
    point moves at 0.87 m/s, its whole speed (0.97 of the arm's speed scale |omega| R, R = 0.3 m
    the farthest node; > 1e-2): one InputError line naming the joint; so is a drive whose speed at t = 0 (2 rad/s) the arm at rest does not have."""
    spin = {"angular_velocity_radps": [0.0, 0.0, 3.0]}
    data = _arm(arm_mesh, {"kind": "rigid"}, spin, [{**TIP_PIN, "ground_m": [0.29, 0.0, 0.005]}])
    with pytest.raises(InputError) as info:
        build_scenario(scenario_from_dict(data))
    msg = str(info.value)
    assert msg.startswith("joints[0] (pin): the initial velocities violate the joint: ")
    assert "0.97 of the bodies' speed (tolerance 0.01)" in msg and "\n" not in msg
    drive = {"angular_velocity_radps": {"constant": 2.0}}
    hub = {"type": "revolute", "body": "arm", "node_set": "hub", "axis": [0, 0, 1], "drive": drive}
    data = _arm(arm_mesh, {"kind": "rigid"}, {}, [hub])
    with pytest.raises(InputError, match=r"^joints\[0\]: the initial velocities violate"):
        build_scenario(scenario_from_dict(data))


def test_flexible_arm_spin_up_follows_the_drive(arm_mesh, tmp_path):
    """The full-FE arm (coarse tet4) spun up about its hub by the drive's spin-up profile to
    20 rad/s over T = 20 ms (Kane et al. 1987), no gravity, theta = 1/2, h = 0.2 ms. Checked:
    - the frame turns by the prescribed angle to round-off (the step closes phi to 1e-12);
    - angular momentum about the pivot axis: H_z(t) - H_z(0) = int tau dt (the revolute's
      other rows give no z torque about the pivot), and energy: (kinetic + strain)(t) - E(0) =
      sum tau_k (theta_k - theta_k-1), the drive's work. The midpoint rule keeps both balances
      step by step up to the Newton tolerance (1e-10 per step, 100 steps): bound 1e-8
      relative (measured 2e-10 and 3.4e-9);
    - the largest torque is I_O alpha_max (alpha_max = 2 w_s / T, I_O = H_z(end) / w_s) to
      10 %: the arm's elastic lag behind a ramp of T = 20 ms adds a share of order (P / T)^2
      = 8 % (P ~ 5.5 ms, its first in-plane bending period clamped at the hub); measured
      +7 %."""
    drive = {"angular_velocity_radps": SPIN}
    hub = {
        "type": "revolute",
        "name": "motor",
        "body": "arm",
        "node_set": "hub",
        "axis": [0, 0, 1],
        "drive": drive,
    }
    data = _arm(arm_mesh, {"kind": "full"}, {}, [hub], t_end=0.02, dt=2e-4)
    run = fm.run(scenario_from_dict(data))
    res = run.result
    t = res.t
    T, ws = 0.02, 20.0
    angle = np.array(
        [
            ws / T * (s * s / 2 + (T / (2 * math.pi)) ** 2 * (math.cos(2 * math.pi * s / T) - 1))
            for s in t
        ]
    )
    turned = np.unwrap([math.atan2(A[1, 0], A[0, 0]) for A in res.frame_A[:, 0]])
    np.testing.assert_allclose(turned, angle, rtol=0, atol=1e-10)
    tau = res.drive_torque["motor"]
    assert run.summary["drive_torque_max_abs_Nm"]["motor"] == pytest.approx(np.abs(tau).max())
    write_results_h5(tmp_path / "r.h5", res, run.built.system.bodies)
    with h5py.File(tmp_path / "r.h5") as f:  # the torque in the archive, with its unit
        np.testing.assert_array_equal(f["drive_torque/motor"][()], tau)
        assert f["drive_torque/motor"].attrs["units"] == "N m"
    pivot = run.built.system.joints[0].p2
    Hz = (res.angular_momentum - np.cross(pivot, res.momentum))[:, 2]
    impulse = np.concatenate([[0.0], np.cumsum(tau[1:] * np.diff(t))])
    E = res.kinetic + res.strain
    work = np.concatenate([[0.0], np.cumsum(tau[1:] * np.diff(angle))])
    inertia = Hz[-1] / ws
    assert np.abs(Hz - Hz[0] - impulse).max() < 1e-8 * abs(Hz[-1])
    assert np.abs(E - E[0] - work).max() < 1e-8 * E[-1]
    assert np.abs(tau).max() == pytest.approx(inertia * 2 * ws / T, rel=0.1)


def test_prescribed_frame_from_a_scenario(arm_mesh):
    """A rigid arm's frame prescribed from the scenario file: its hub point on a path given
    by a table of velocities (0 to 1 m/s along x over 10 ms: d = 50 t^2 m) and turned about z
    by a table of angular velocities (0 to 5 rad/s: angle = 250 t^2 rad). The point p, 0.1 m
    along the arm, follows x_0 + d(t), the frame turns by R_z(angle), so the frame origin is
    x_0 + d(t) - R p: both to round-off (1e-12) at every output."""
    p = np.array([0.1, 0.0, 0.005])
    joint = {
        "type": "prescribed",
        "name": "carriage",
        "body": "arm",
        "point_m": list(p),
        "path": {"velocity_mps": [[0.0, 0.0, 0.0, 0.0], [0.01, 1.0, 0.0, 0.0]]},
        "axis": [0, 0, 1],
        "drive": {"angular_velocity_radps": {"table": [[0.0, 0.0], [0.01, 5.0]]}},
    }
    res = fm.run(scenario_from_dict(_arm(arm_mesh, {"kind": "rigid"}, {}, [joint], 0.01))).result
    for t, r, A in zip(res.t, res.frame_r[:, 0], res.frame_A[:, 0], strict=True):
        c, s = math.cos(250.0 * t * t), math.sin(250.0 * t * t)
        R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
        np.testing.assert_allclose(A, R, rtol=0, atol=1e-12)
        np.testing.assert_allclose(r, p + [50.0 * t * t, 0.0, 0.0] - R @ p, rtol=0, atol=1e-12)
    assert (
        set(res.drive_torque) == {"carriage"}
        and res.torque("carriage") is res.drive_torque["carriage"]
    )
    with pytest.raises(InputError, match=r"^no drive 'motor' in this run \(drives: carriage\)$"):
        res.torque("motor")


def test_dumps_without_the_new_keys_are_as_before_and_round_trip():
    """Study keys and cache identities hash scenario dumps: a scenario without drives, paths,
    joint names or rigid_motion dumps without those keys; one with them reads back from its
    dump to the same dump."""
    plain = fm.load_scenario(SCENARIOS / "pendulum_release.toml").model_dump(mode="json")
    assert all(not {"name", "drive", "path"} & set(j) for j in plain["joints"])
    assert all("rigid_motion" not in b["placement"] for b in plain["bodies"])
    motion = {"angular_velocity_radps": [0, 0, 1.0], "about_joint": "pin"}
    data = _with_joint({**REV_AXIS, "name": "pin", "drive": SPIN_DRIVE}, rigid_motion=motion)
    dump = scenario_from_dict(data).model_dump(mode="json")
    assert scenario_from_dict(dump).model_dump(mode="json") == dump
