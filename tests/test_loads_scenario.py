"""[[loads]] and [[springs]] in a scenario file (scenarios/load_schema.py, load_build.py):
the tables validate with one-line errors, build into the run, and summary.json reports the
energy ledger and why the momentum error is not defined (issue 35).

The run: the short flat test rod (tests/data/short_flat_impact.toml's b2, 50 mm, r = 5 mm,
725 nodes) as a full-FE body pinned at the centre of its end A by a revolute joint about z,
driven by a motor torque table, held by a rotational spring on the joint and a linear
spring-damper from its end B to the ground, and pushed by a force following it. ~60 steps.
"""

from __future__ import annotations

import copy
import functools
import tomllib
from pathlib import Path

import numpy as np
import pytest

from flexmvm.runs.run import run_scenario
from flexmvm.scenarios import ScenarioError, scenario_from_dict

CASE = Path(__file__).parent / "data" / "short_flat_impact.toml"


def _data() -> dict:
    base = tomllib.loads(CASE.read_text())
    rod = base["bodies"][1]
    rod.pop("placement", None)
    return {
        "name": "driven_rod",
        "time": {"t_end_s": 30e-6, "dt_s": 0.5e-6, "output_dt_s": 0.5e-6, "theta": 0.5},
        "bodies": [{**rod, "name": "rod"}],
        "joints": [
            {"type": "revolute", "body": "rod", "node_set": "end_a_centre", "axis": [0, 0, 1]}
        ],
        "loads": [
            {"type": "motor", "joint": 0, "times_s": [0.0, 10e-6], "torque_nm": [0.0, 5.0]},
            {
                "type": "force",
                "body": "rod",
                "node_set": "end_b_centre",
                "frame": "body",
                "force_n": [0.0, 2.0, 0.0],
                "name": "push",
            },
        ],
        "springs": [
            {"type": "rotational", "joint": 0, "stiffness_nm_per_rad": 50.0},
            {
                "body": "rod",
                "node_set": "end_b_centre",
                "ground_m": [0.05, -0.01, 0.0],
                "stiffness_n_per_m": 1.0e4,
                "damping_n_s_per_m": 5.0,
            },
        ],
    }


@functools.cache
def _run():
    return run_scenario(scenario_from_dict(_data(), "driven_rod"))


def test_driven_rod_converges_and_its_ledger_closes():
    """Newton with these loads in the residual only converges in the default iteration limit
    at every step (no step cut, none on the round-off floor): the springs are far softer than
    the rod (1e4 N/m against EA/L = 1.1e8 N/m; theta^2 h^2 k / m ~ 1e-9). Every load has its
    work in summary.json, the revolute joint none to speak of (an ideal joint, 1e-6 of the
    input), and the balance closes to 1e-6 of the input work (measured 9e-10: the frame turns
    ~1e-4 rad in 30 us, so the rotating frame's O(h^2) energy error is tiny). The momentum
    error says why it is undefined: the pin and the external loads, not the internal torques.
    ~15 s on the loaded 2-core machine (60 steps of a 2,175-DOF full-FE body)."""
    s = _run().summary
    assert s["status"] == "completed"
    assert s["steps_on_roundoff_floor"] == 0 and s["step_cuts"] == 0
    led = s["energy_ledger"]
    assert set(led["work_loads_J"]) == {
        "loads[0] motor",
        "push",
        "springs[0] rotational",
        "springs[1] linear",
    }
    assert led["balance_reference"] == "input work"
    assert led["balance_residual_rel_max"] < 1e-6
    w_in = led["balance_reference_J"]
    assert abs(sum(led["work_joints_J"].values())) < 1e-6 * w_in
    assert led["load_damper_dissipation_J"]["springs[1] linear"] > 0
    # the energy guard counts the loads' work as input: no rise beyond it (runs.run
    # energy_gain; the run's energy rises from 0 by the motor's work)
    assert s["energy_gain_rel_max"] is not None and s["energy_gain_rel_max"] < 1e-6
    assert s["momentum_rel_error"] is None
    why = s["momentum_error_undefined_because"]
    assert "joints[0] (SphericalJoint) holds 'rod' to the ground" in why
    assert "push pushes 'rod' from outside" in why and "springs[1] linear" in why
    assert "motor" not in why and "springs[0]" not in why  # internal torques


def test_springs_work_equals_their_energy_change():
    """The rotational spring's work is minus its energy change (it starts unstressed; its
    damper is off): exact at theta = 1/2 for a rotation about a fixed axis (the midpoint
    angle is the mean angle), here to round-off on the flexible rod (measured 4e-16
    relative; bound 1e-9). The linear spring's elastic work (its work plus its damper's
    dissipation) is minus its energy change to the scheme's O(h^2) for a point that does not
    move along the spring (bound 1e-3)."""
    s = _run().summary["energy_ledger"]
    stored = s["spring_energy_J"]["springs[0] rotational"]
    assert stored > 0
    assert abs(s["work_loads_J"]["springs[0] rotational"] + stored) < 1e-9 * stored
    key = "springs[1] linear"
    elastic = s["work_loads_J"][key] + s["load_damper_dissipation_J"][key]
    assert abs(elastic + s["spring_energy_J"][key]) < 1e-3 * s["spring_energy_J"][key]


def test_empty_tables_are_left_out_of_dumps():
    """A scenario without loads dumps as before the keys existed (cache identities)."""
    data = _data()
    data.pop("loads")
    data.pop("springs")
    dump = scenario_from_dict(data).model_dump(mode="json")
    assert "loads" not in dump and "springs" not in dump
    assert "loads" in scenario_from_dict(_data()).model_dump(mode="json")


@pytest.mark.parametrize(
    ("path", "value", "expected"),
    [
        (("loads", 0, "times_s"), [0.0, 0.0], "loads[0].times_s: times must increase strictly"),
        (("loads", 0, "torque_nm"), [0.0, 5.0, 1.0], "values must have shape (2,)"),
        (("loads", 1, "force_n"), [1.0, 2.0], "loads[1].force_n: must be 3 numbers"),
        (("loads", 0, "joint"), 3, "loads[0].joint: no joints[3] (1 joint(s))"),
        (("springs", 1, "stiffness_n_per_m"), -1.0, "stiffness_n_per_m: must be >= 0"),
        (("springs", 1, "body2"), "rod", "springs[1].point2_m: required by a 'linear' spring"),
        (("loads", 1, "torque_nm"), [1.0, 0, 0], "loads[1].torque_nm: not used by a 'force'"),
    ],
)
def test_bad_tables_give_one_line(path, value, expected):
    data = copy.deepcopy(_data())
    target = data
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(data, "driven_rod")
    message = str(info.value)
    assert expected in message and "\n" not in message, message


def test_rod_swings_the_way_the_motor_turns():
    """The motor's torque is about +z (5 N m after 10 us): the rod turns positively."""
    res = _run().result
    A = res.frame_A[-1, 0]
    assert np.arctan2(A[1, 0], A[0, 0]) > 0


def test_energy_gain_counts_inputs_and_catches_the_rest():
    """runs.run.energy_gain: a rise of the energy equal to the loads' and joints' work is
    no gain; 1 J more than they did is (relative to the largest input work when E(0) = 0)."""
    from types import SimpleNamespace

    from flexmvm.integrate.energy_ledger import EnergyLedgerHistory
    from flexmvm.runs.run import energy_gain

    t = np.linspace(0.0, 1.0, 5)
    zero = np.zeros(5)
    works = EnergyLedgerHistory(
        ["load"], ["joint"], np.c_[4.0 * t], np.c_[zero], np.c_[zero], np.c_[6.0 * t],
        contact=zero, damping=zero, numerical=zero,
    )  # fmt: skip
    fed = SimpleNamespace(total_energy=10.0 * t, energy_ledger=works)
    assert energy_gain(fed) == pytest.approx(0.0, abs=1e-15)
    extra = SimpleNamespace(total_energy=10.0 * t + np.r_[0, 0, 1.0, 0, 0], energy_ledger=works)
    assert energy_gain(extra) == pytest.approx(0.1)
    alone = SimpleNamespace(total_energy=np.r_[2.0, 2.5, 2.0, 2.0, 2.0], energy_ledger=None)
    assert energy_gain(alone) == pytest.approx(0.25)
