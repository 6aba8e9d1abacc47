"""The impact `flexmvm region` expects (issue 49, item 6; studies/impact_estimate.py), each
against a value computed by hand, on small meshes: a rigid steel sphere R 5 mm (tet4, 2 mm)
above a 40 x 40 x 4 mm aluminium plate (tet4, 2 mm; ``top`` struck, ``side`` clamped).

- E* with a rigid ball: the plate's E / (1 - nu^2) alone (before: both materials, 26 % low).
- The clamped plate: no recoil, its point impedance 8 sqrt(D rho h) at its 4 mm thickness in
  series with Hertz (Zener 1941): the peak force against an independent integration of
  Zener's ODE (before: the plate's whole mass recoiled and its impedance was left out); the
  free plate: its whole mass, the same impedance.
- The closing speed from the scenario: a ball given a rigid_motion about a point, and a ball
  on a revolute joint with a constant-rate drive, against |w x r . n| (before: InputError,
  "give the closing speed").
- A link swung by a motor on its revolute joint (no drive): its speed from the motor's
  angular impulse and its moment of inertia, its mass J / l^2.
- The region centred on the body at an edge: the struck point of a block's edge lies on the
  block (before: the projection on the averaged normal's plane, 1 mm off it).
- The mode count from 3 / contact duration, and `flexmvm select --allow-costly`.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import flexmvm as fm
from flexmvm.errors import InputError
from flexmvm.theory.hertz import hertz_impact
from flexmvm.theory.plate_impact import plate_impact, plate_impedance

pytest.importorskip("gmsh")

R, V0 = 5e-3, 1.0  # the ball's radius [m] and speed [m/s]
STEEL = {"E_pa": 210e9, "nu": 0.3, "rho_kg_m3": 7850.0}
AL = {"E_pa": 70e9, "nu": 0.33, "rho_kg_m3": 2700.0}
H = 4e-3  # the plate's thickness [m]

SCENARIO = """
name = "region_estimates"
[time]
t_end_s = 1.0e-4
dt_s = 0.5e-6
output_dt_s = 1.0e-6

[[bodies]]
name = "ball"
mesh_file = "ball.msh"
material = { E_pa = 210.0e9, nu = 0.3, rho_kg_m3 = 7850.0 }
model = { kind = "rigid" }
[bodies.placement]
position_m = [0.0, 0.0, 0.005]
MOTION

[[bodies]]
name = "plate"
mesh_file = "plate.msh"
material = { E_pa = 70.0e9, nu = 0.33, rho_kg_m3 = 2700.0 }
model = { kind = "full" }

[[contacts]]
slave = "plate.top"
master = "ball.front"
law = "position"
"""
CLAMP = """
[[supports]]
type = "clamp"
body = "plate"
node_set = "side"
"""


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    from flexmvm.mesh.parts import block, sphere

    d = tmp_path_factory.mktemp("region_estimates")
    sphere(d / "ball.msh", R, 2e-3)
    block(d / "plate.msh", 0.04, 0.04, H, 2e-3)
    return d


def _scenario(folder, motion: str = "velocity_mps = [0.0, 0.0, -1.0]", extra: str = CLAMP):
    path = folder / "case.toml"
    path.write_text(SCENARIO.replace("MOTION", motion) + extra)
    return fm.load_scenario(path)


def _ball_mass(sc) -> float:
    from flexmvm.assembly.build_cache import default_setup

    return float(default_setup().free_modes_source(sc.body("ball"))[0].M_scalar.sum())


def test_rigid_ball_takes_the_plates_modulus_alone(folder):
    """E* of a rigid ball on aluminium is E / (1 - nu^2) = 78.57 GPa exactly (a rigid body's
    modulus is infinite); the former estimate took steel's too (58.6 GPa)."""
    est = fm.estimate_region(_scenario(folder), "plate", modes=10)
    assert est.hertz.e_star_pa == pytest.approx(AL["E_pa"] / (1 - AL["nu"] ** 2), rel=1e-12)


def _zener_by_hand(m: float, E: float, Rb: float, Z: float, v: float) -> float:
    """Peak force [N] of Zener's ODE (theory/plate_impact.py) by a fixed-step midpoint rule:
    x' = u - F / Z, u' = -F / m, F = 4/3 E sqrt(R) x^1.5."""
    K = 4.0 / 3.0 * E * math.sqrt(Rb)
    x, u, dt, peak = 0.0, v, 1e-9, 0.0
    while u > 0 or x > 0:
        f = K * max(x, 0.0) ** 1.5
        xm, um = x + 0.5 * dt * (u - f / Z), u - 0.5 * dt * f / m
        fm_ = K * max(xm, 0.0) ** 1.5
        x, u = x + dt * (um - fm_ / Z), u - dt * fm_ / m
        peak = max(peak, f)
        if x < 0:
            break
    return peak


def test_clamped_plate_answers_with_its_point_impedance(folder):
    """The clamped plate does not recoil (m* = the ball's mass, before: reduced with the
    plate's 17 g) and takes Z = 8 sqrt(D rho h) at its 4 mm thickness (the bottom nodes:
    exact); the peak force is Zener's, against a 1 ns midpoint integration to 1e-3 (its
    error ~ (dt / T_c)^2 with T_c ~ 50 us), and below rigid-target Hertz."""
    sc = _scenario(folder)
    est = fm.estimate_region(sc, "plate", modes=10)
    m = _ball_mass(sc)
    E = AL["E_pa"] / (1 - AL["nu"] ** 2)
    D = AL["E_pa"] * H**3 / (12 * (1 - AL["nu"] ** 2))
    Z = 8 * math.sqrt(D * AL["rho_kg_m3"] * H)
    assert est.impedance_body == "plate" and est.thickness_m == pytest.approx(H, rel=1e-9)
    assert est.impedance_nspm == pytest.approx(Z, rel=1e-9)
    assert est.hertz.m_star_kg == pytest.approx(m, rel=1e-12)
    Rb = est.curvature_radius_m
    assert est.hertz.force_max_n == pytest.approx(_zener_by_hand(m, E, Rb, Z, V0), rel=1e-3)
    assert est.hertz.force_max_n < 0.8 * hertz_impact(Rb, V0, E, m).force_max_n
    # free, the plate recoils with its whole mass, in series with the same impedance
    free = fm.estimate_region(_scenario(folder, extra=""), "plate", modes=10)
    m_plate = AL["rho_kg_m3"] * 0.04 * 0.04 * H
    assert free.hertz.m_star_kg == pytest.approx(m * m_plate / (m + m_plate), rel=1e-6)
    assert free.impedance_nspm == pytest.approx(Z, rel=1e-9)


def test_plate_impact_limits():
    """Z -> inf is Hertz's rigid target (theory/hertz.py) to 1e-6 (the ODE's rtol 1e-9 and the
    4001-point peak search); Z = plate_impedance is 8 sqrt(D rho h)."""
    a, b = plate_impact(R, V0, 80e9, 4e-3, math.inf, 1e15), hertz_impact(R, V0, 80e9, 4e-3)
    assert a.force_max_n == pytest.approx(b.force_max_n, rel=1e-6)
    assert a.duration_s == pytest.approx(b.duration_s, rel=1e-4)
    D = 70e9 * H**3 / (12 * (1 - 0.33**2))
    assert plate_impedance(70e9, 0.33, 2700.0, H) == pytest.approx(
        8 * math.sqrt(D * 2700 * H), rel=1e-12
    )


def test_speed_from_a_rigid_motion(folder):
    """A ball turning at w = 10 rad/s about y through (-0.1, 0, 0.005) m: its pole (0, 0, 0)
    moves at w x r = (0, 10, 0) x (0.1, 0, -0.005) along -z at 1.0 m/s; exactly that."""
    motion = (
        "rigid_motion = { angular_velocity_radps = [0.0, 10.0, 0.0], about_m = [-0.1, 0.0, 0.005] }"
    )
    est = fm.estimate_region(_scenario(folder, motion), "plate", modes=10)
    assert est.closing_speed_mps == pytest.approx(1.0, rel=1e-9) and not est.speed_given


def test_speed_from_a_driven_joint(folder):
    """A ball on a revolute joint to the ground at (-0.1, 0, 0.005) m about y, driven at a
    constant 10 rad/s, onto a free plate: 10 x 0.1 = 1.0 m/s at the pole, exactly; before, the
    estimate asked for --speed (the ball is at rest at its placement)."""
    joint = """
[[joints]]
type = "revolute"
body = "ball"
point_m = [-0.1, 0.0, 0.0]
ground_m = [-0.1, 0.0, 0.005]
axis = [0.0, 1.0, 0.0]
drive = { angular_velocity_radps = { constant = 10.0 } }
"""
    est = fm.estimate_region(_scenario(folder, "", joint), "plate", modes=10)
    assert est.closing_speed_mps == pytest.approx(1.0, rel=1e-9)


def test_swung_link_from_its_motor(folder):
    """The ball on an undriven revolute joint about y through (-0.1, 0, 0.005) m, turned by a
    motor of 0.05 N m over the run (100 us) onto the clamped plate: it strikes at
    w = 0.05 x 1e-4 / J, J = m (0.4 R^2 + 0.1^2) about the pivot, with the pole 0.1 m from the
    axis: closing speed 0.1 w and mass J / 0.1^2 (before: "give the closing speed", then both
    bodies held to the ground). Hand values with the mesh's mass m, to 2e-3: the lumped
    masses' J misses the sphere's own 0.4 m R^2 (0.1 % of J) by its faceting."""
    joint = """
[[joints]]
type = "revolute"
body = "ball"
point_m = [-0.1, 0.0, 0.0]
ground_m = [-0.1, 0.0, 0.005]
axis = [0.0, 1.0, 0.0]

[[loads]]
type = "motor"
joint = 0
torque_nm = 0.05
"""
    sc = _scenario(folder, "", CLAMP + joint)
    est = fm.estimate_region(sc, "plate", modes=10)
    m = _ball_mass(sc)
    J = m * (0.4 * R**2 + 0.1**2)
    assert est.closing_speed_mps == pytest.approx(0.1 * 0.05 * 1e-4 / J, rel=2e-3)
    assert est.hertz.m_star_kg == pytest.approx(J / 0.1**2, rel=2e-3)


def test_centre_on_the_body_at_an_edge(folder):
    """The ball's pole over the plate's edge x = 20 mm, 1 mm outside it: the region's centre
    is the nearest point of the plate's top, its edge (0.02, 0, 0) to 1e-12 m."""
    sc = _scenario(folder)
    data = sc.model_dump(mode="json")
    data["bodies"][0]["placement"]["position_m"] = [0.021, 0.0, 0.0049]
    est = fm.estimate_region(fm.scenario_from_dict(data), "plate", modes=10, radius_m=R)
    np.testing.assert_allclose(est.centre_m, [0.02, 0.0, 0.0], atol=1e-12)


def test_mode_count_from_the_contact_duration(folder):
    """Without --modes the count is the plate's elastic free-free modes below 3 / T_c, its
    f_max that; the modes below it counted by hand from the body's free-free spectrum."""
    from flexmvm.assembly.build_cache import default_setup

    sc = _scenario(folder)
    est = fm.estimate_region(sc, "plate")
    assert est.modes_from == "criterion"
    assert est.f_max_hz == pytest.approx(3.0 / est.hertz.duration_s, rel=1e-12)
    f = default_setup().free_modes_source(sc.body("plate"))[1](est.modes + 7)[0][6:]
    assert f[est.modes - 1] < est.f_max_hz <= f[est.modes]


def test_select_allow_costly_sets_the_bodys_model(folder, monkeypatch):
    """`flexmvm select --allow-costly` hands the study the scenario with the body's
    model.allow_costly set (the study itself replaced by a recorder)."""
    from flexmvm.cli.main import main
    from flexmvm.studies import selection

    seen = {}
    monkeypatch.setattr(
        selection, "run_selection_study", lambda sc, body, *a, **k: seen.update(sc=sc)
    )
    _scenario(folder)
    args = ["select", str(folder / "case.toml"), "--body", "plate", "--radii", "1"]
    main([*args, "--out", str(folder / "study"), "--allow-costly"])
    assert seen["sc"].body("plate").model.allow_costly


def test_both_rigid_is_an_input_error(folder):
    """Two rigid bodies have no E*: one line saying so."""
    sc = _scenario(folder, extra="")
    data = sc.model_dump(mode="json")
    data["bodies"][1]["model"] = {"kind": "rigid"}
    with pytest.raises(InputError, match="both rigid"):
        fm.estimate_region(fm.scenario_from_dict(data), "plate", modes=10)
