"""A flexible arm on a motor-driven revolute joint swung into a rigid stop
(scenarios/arm_stop.toml on a coarse tet4 mesh): spin-up, coast, impact and rebound, full FE
and MVM (issue 35, the arm-into-a-stop showcase).

The arm (aluminium, 300 x 20 x 10 mm, hub R 15 mm with a pivot hole R 5 mm; 10 mm elements,
1 mm at the struck point) starts at rest on a revolute joint on the centroid of the hole face's
nodes; a motor torque TAU0 sin^2(pi t / T_SPIN) on the joint spins it up and is zero from
T_SPIN on, so it coasts into a grounded steel sphere R 10 mm placed where the struck point
(0.27 m from the pivot) arrives T_COAST later (the rigid arm's angle).

Physics checked:
- the angular momentum about the pivot equals the motor's angular impulse TAU0 T_SPIN / 2: the
  joint's force acts at the pivot and its two orientation rows give torques about x and y
  only; after the motor is off it is conserved until the impact;
- through the impact it changes by the moment of the contact impulse, -0.27 m x I_c (the
  contact normal is along -y at x = 0.27 m);
- rebound: the contact opens and the arm's angular momentum reverses;
- energy: the run's ledger closes, E(t) - works + dissipations = 0 against the motor's work,
  the joint does no work (scleronomic), the contact none that is positive.
The meshes and both runs (module fixtures): 106 s at load 10 on the shared 2-core machine
(full FE 70 s, 237 steps; MVM 36 s: the 2 ms spin-up at 16 us steps and the ~65 us contact at
1 us ones), the tests themselves < 0.1 s each."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import flexmvm as fm
from flexmvm.metrics.ncc import ncc

pytest.importorskip("gmsh")

from flexmvm.mesh import parts

# the coarse test arm's full-FE body (1,194 DOF) is as small as its reduced one: the
# reduced-cost guard's warning is expected here
pytestmark = pytest.mark.filterwarnings("ignore::flexmvm.assembly.cost.ReducedCostWarning")

ARM_X = 0.270  # struck point's distance from the pivot [m]
T_SPIN = 2.0e-3  # the motor's pulse [s]
TAU0 = 5.0  # its peak torque [N m]: angular impulse TAU0 T_SPIN / 2 = 5e-3 N m s
J_PIVOT = 4.86e-3  # the coarse arm's moment of inertia about the pivot [kg m^2] (measured)
OMEGA = TAU0 * T_SPIN / 2 / J_PIVOT  # the rigid arm's speed after the spin-up [rad/s]
T_COAST = 0.1e-3  # [s]: from the motor's end to the impact (rigid arm)
# the stop's gap: the struck point's path over the rigid arm's angle OMEGA (T_SPIN/2 + T_COAST)
GAP = ARM_X * OMEGA * (T_SPIN / 2 + T_COAST)
T_END = 2.2e-3  # [s]: past the separation (~65 us after the impact)


def _motor() -> dict:
    """TAU0 sin^2(pi t / T_SPIN) sampled at 17 times (its trapezoid integral is exactly
    TAU0 T_SPIN / 2), zero after."""
    ts = np.linspace(0.0, T_SPIN, 17)
    tau = TAU0 * np.sin(np.pi * ts / T_SPIN) ** 2
    return {
        "type": "motor",
        "name": "motor",
        "joint": 0,
        "times_s": ts.tolist(),
        "torque_nm": tau.tolist(),
    }


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    d = tmp_path_factory.mktemp("arm_stop")
    arm = parts.arm(
        d / "arm.msh",
        0.300,
        0.020,
        0.010,
        0.015,
        0.005,
        0.010,
        refine=parts.Refinement((ARM_X, 0.010, 0.005), 1.0e-3, 2.0e-3, 10.0e-3),
    )
    stop = parts.sphere(
        d / "stop.msh",
        0.010,
        0.004,
        refine=parts.Refinement((0.0, 0.0, -0.010), 0.5e-3, 1.0e-3, 5.0e-3),
    )
    return arm, stop


def _data(meshes, model: dict) -> dict:
    arm, stop = meshes
    return {
        "name": "arm_stop_coarse",
        "time": {
            "t_end_s": T_END,
            "dt_s": 1e-6,
            "dt_max_s": 16e-6,
            "output_dt_s": 16e-6,
            "output_contact_dt_s": 1e-6,
            "hf_damping_time_s": 12.5e-6,
        },
        "bodies": [
            {
                "name": "arm",
                "mesh_file": str(arm),
                "material": "aluminium",
                "model": {"reference": "hub", **model},
            },
            {
                "name": "stop",
                "mesh_file": str(stop),
                "model": {"kind": "rigid"},
                "material": {"E_pa": 210e9, "nu": 0.3, "rho_kg_m3": 7850.0},
                # its refined -z pole turned to face -y, GAP beyond the arm's +y side
                "placement": {
                    "position_m": [ARM_X, 0.020 + GAP, 0.005],
                    "rotation": {"axis": [1.0, 0.0, 0.0], "angle_deg": -90.0},
                },
            },
        ],
        "joints": [
            {"type": "revolute", "body": "arm", "node_set": "hub", "axis": [0, 0, 1]},
            {"type": "ground", "body": "stop"},
        ],
        "loads": [_motor()],
        "contacts": [{"slave": "stop.front", "master": "arm.surface", "law": "position"}],
        "probes": [{"name": "tip", "body": "arm", "point_m": [0.300, -0.010, 0.0]}],
    }


def _scenario(meshes, model: dict):
    return fm.scenario_from_dict(_data(meshes, model))


MVM = {
    "kind": "mvm",
    "modes": 30,
    "region": {"ball": {"centre_m": [ARM_X, 0.010, 0.005], "radius_m": 2.5e-3}},
}


@pytest.fixture(scope="module")
def runs(meshes):
    return fm.run(_scenario(meshes, {"kind": "full"})), fm.run(_scenario(meshes, MVM))


def _pivot_angular_momentum(run) -> np.ndarray:
    """L_z about the joint's ground point (the hub centroid at t = 0) [kg m^2/s]."""
    p0 = run.built.system.joints[0].p2
    res = run.result
    return (res.angular_momentum - np.cross(p0, res.momentum))[:, 2]


@pytest.mark.parametrize("which", [0, 1], ids=["full", "mvm"])
def test_arm_is_spun_up_coasts_into_the_stop_and_rebounds(runs, which):
    """Zero steps not converged and no step cut; one contact, after the motor is off, that
    opens again. L_z about the pivot at the motor's end equals its angular impulse
    TAU0 T_SPIN / 2 to 1e-4 (the scheme takes the table at t + theta h, a quadrature of
    O(h^2) on the free-flight steps; measured -2.7e-5 on both arms); conserved to 1e-7 over
    the coast (the Newton tolerance's floor on the 16 us steps, measured 2.1e-8; the joint's
    rows give no moment about z); changed through the impact by the contact impulse's moment
    -0.27 m x I_c to 0.5 % (measured 0.10 %: the struck point is 0.27 m from the pivot to the
    width of the contact patch, and the normal turns with the arm by ~1e-3 rad), reversed
    after it (-8 % of its value in the coast), and the tip moving back. The impact comes
    within 40 us of the rigid arm's T_SPIN + T_COAST (measured 17 us early on both: the struck
    point ~5 um ahead of the rigid arm's, the arm's bending after the spin-up)."""
    run = runs[which]
    s = run.summary
    assert s["status"] == "completed"
    assert s["steps_on_roundoff_floor"] == 0 and s["step_cuts"] == 0
    ((t_on, t_off),) = s["contact_intervals_s"]
    assert T_SPIN < t_on and abs(t_on - (T_SPIN + T_COAST)) <= 40e-6
    assert t_off < T_END - 5e-6
    L, t = _pivot_angular_momentum(run), run.t
    assert L[0] == 0.0
    coast = (t >= T_SPIN) & (t < t_on - 1e-6)
    assert L[coast][0] == pytest.approx(TAU0 * T_SPIN / 2, rel=1e-4)
    assert np.abs(L[coast] - L[coast][0]).max() <= 1e-7 * L[coast][0]
    impulse = float(run.steps.contact_impulse_Ns.sum())
    assert L[-1] - L[coast][0] == pytest.approx(-ARM_X * impulse, rel=5e-3)
    assert L[-1] < 0.0
    v = run.probe("tip").v[:, 1]
    assert v[-1] < 0.0 < v[coast][-1]


@pytest.mark.parametrize("which", [0, 1], ids=["full", "mvm"])
def test_energy_ledger_closes_on_the_motor_work(runs, which):
    """The run's ledger (integrate.energy_ledger): E(t) - E(0) - works + dissipations within
    1e-5 of the input work at every output (the issue's bound is 1e-3; what is left is the
    scheme's O(h^2) kinetic-energy identity for a turning frame: measured 2.4e-7 full FE,
    1.1e-6 MVM).
    The motor is the only input: the pin's rows, scleronomic, do work within 1e-5 of it (the
    same O(h^2)), the contact none that is positive (compressive impulses on a closing or
    resting gap), and the theta scheme's numerical dissipation is what the energy misses
    (to 1e-3 of it: the residual's share; measured 1.6e-6 and 1.6e-5; the dissipation is
    9.5 % and 7.4 % of the motor's work, mostly the 16 us steps' theta = 0.82)."""
    led = runs[which].summary["energy_ledger"]
    w_motor = led["work_loads_J"]["motor"]
    assert led["balance_reference"] == "input work"
    assert led["balance_residual_rel_max"] <= 1e-5
    assert abs(sum(led["work_joints_J"].values())) <= 1e-5 * w_motor
    assert led["work_contact_J"] <= 1e-9 * w_motor
    missing = w_motor + led["work_contact_J"] - led["total_end_J"]
    assert missing == pytest.approx(led["dissipation_numerical_J"], rel=1e-3)


def test_mvm_against_full_fe(runs):
    """Contact force over the contact window and tip velocity from the motor's end on, of the
    reduced arm (30 modes and the nodes within 2.5 mm of the struck point: 114 DOF) against
    full FE (1,194 DOF): bounds 0.995 and 0.99 (the issue's showcase acceptance; measured
    0.9964 and 0.9990); peak within 5 % (measured +3.0 %); the motor's work within 5e-5
    (measured 7.5e-6: the two arms bend alike under it; the issue's bound is 1 %)."""
    full, mvm = runs
    ((t_on, t_off),) = full.summary["contact_intervals_s"]

    def window(run, t0, t1):
        keep = (run.t >= t0) & (run.t <= t1)
        return run.t[keep], run.contact_force[keep], run.probe("tip").v[keep, 1]

    tf, ff, _ = window(full, t_on - 5e-6, t_off + 5e-6)
    tm, fm_, _ = window(mvm, t_on - 5e-6, t_off + 5e-6)
    assert ncc(tf, ff, tm, fm_) >= 0.995
    tf, _, vf = window(full, T_SPIN, T_END)
    tm, _, vm = window(mvm, T_SPIN, T_END)
    assert ncc(tf, vf, tm, vm) >= 0.99
    assert mvm.contact_force.max() == pytest.approx(full.contact_force.max(), rel=0.05)
    w = [r.summary["energy_ledger"]["work_loads_J"]["motor"] for r in runs]
    assert w[1] == pytest.approx(w[0], rel=5e-5)


def test_frame_block_is_the_mass_matrix_of_its_configuration(runs):
    """Where nothing is carried (the midpoint refresh of a slow iteration), the iteration
    matrix's J and M_wq must come from one contraction L(q): the reduced arm's modes hold
    the quasi-rigid rotations of its 3-2-1 support, so its rotational mass Schur complement
    J - M_wq M_qq^-1 M_wq^T is small, and a J without its quadratic part q^T G2 q beside an
    exact M_wq turned it (and the joint rows' D) indefinite on the fine arm after the impact.
    Checked at the arm's most deformed state of the run, q scaled up 10x to make the quadratic
    part count: J and M_wq equal to the exact ones (inertia_terms) to 1e-12 of J, and the
    Schur complement positive definite."""
    from flexmvm.integrate.moreau_jean.carried import CarriedState
    from flexmvm.integrate.moreau_jean.iteration_matrix import IterationMatrices
    from flexmvm.integrate.state import BodyState

    mvm = runs[1]
    arm = mvm.built.system.bodies[0]
    q_hist, _ = mvm.elastic("arm")
    q = 10 * q_hist[np.abs(q_hist).max(axis=1).argmax()]
    seen = {}

    class Solver:
        def refresh_coupling(self, h, M_wq, tol, defer=False):
            seen["M_wq"] = M_wq

        def prepare(self, h, A, Mff):
            seen["Mff"] = Mff

    st = BodyState(np.zeros(3), np.eye(3), q, np.zeros(arm.nv))
    threads = SimpleNamespace(each=lambda fn, items: {i: fn(i) for i in items})
    mats = IterationMatrices([arm], [Solver()], threads, CarriedState([arm], None), None)
    mats.prepare([st], 1e-6, refresh_tol=0.0)
    _, J, M_wq, _ = arm.inertia_terms(q)
    scale = np.abs(J).max()
    assert np.abs(seen["Mff"][3:, 3:] - J).max() <= 1e-12 * scale
    assert np.abs(seen["M_wq"] - M_wq).max() <= 1e-12 * scale
    schur = J - M_wq @ np.linalg.solve(np.asarray(arm.inv.M_qq), M_wq.T)
    assert np.linalg.eigvalsh(0.5 * (schur + schur.T)).min() > 0.0


@pytest.mark.parametrize(
    ("joint", "message"),
    [
        ({"type": "distance", "node_set": "hub", "ground_m": [0, 0, 0]}, "node_set: not used"),
        (
            {"type": "revolute", "node_set": "hub", "point_m": [0, 0, 0], "axis": [0, 0, 1]},
            "point_m: not used",
        ),
        ({"type": "revolute", "node_set": "nowhere", "axis": [0, 0, 1]}, "nowhere"),
    ],
)
def test_node_set_joint_errors_are_one_line(meshes, joint, message):
    """node_set stands for point_m on fixed, spherical and revolute joints only, never
    beside it, and names a set the body has: each a one-line error naming the key."""
    from flexmvm.assembly.build import build_scenario
    from flexmvm.errors import InputError

    data = _data(meshes, {"kind": "full"})
    data["joints"][0] = {"body": "arm", **joint}
    with pytest.raises(InputError) as info:
        build_scenario(fm.scenario_from_dict(data))
    assert message in str(info.value) and "\n" not in str(info.value)
