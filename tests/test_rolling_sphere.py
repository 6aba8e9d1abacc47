"""A sphere rolling with friction along a plate (issue 53 item 3, second check): a rigid
steel sphere (R 10 mm, gmsh tet4 from flexmvm.mesh.part_shapes.sphere) set down on an
aluminium plate (40 x 20 x 5 mm; full FE clamped on its bottom, or rigid on a ground joint)
under gravity, given a sliding start v0 = 0.05 m/s along x with omega0 = 0, Coulomb friction
mu = 0.3, h = 100 us.

Both plates hold their frame by 6 equality rows. Before the equality rows were scaled to a
unit diagonal in coulomb.solve_coulomb, the rigid plate's run stopped at 4.8 ms, as the
sphere starts to roll ("Coulomb residual 1.60e-08 exceeds 1e-08", the regularisation of the
rows' elimination), and the clamped plate's took every rolling step in 6.25 us pieces (761
step cuts, 9.2 x the CPU): docs/notes/2026-11-29-rolling-sphere.md.

Rigid-body answer (sphere of mass m and inertia I about its centre, contact at distance R
below it; k = m R^2 / I, 5/2 for a solid sphere): slides with a = -mu g, alpha = mu g m R / I
(5 mu g / 2 R), rolls from t_r = (v0 - v_r) / (mu g) (2 v0 / 7 mu g) at v_r = v0 k / (1 + k)
(5/7 v0), normal force m g; friction dissipates (1/2) m v0^2 - (1/2)(m + I / R^2) v_r^2
((1/2) m v0^2 - (7/10) m v_r^2). The meshed sphere's own m and I (its FE mass matrix:
I / m R^2 = 0.3967, 0.8 % below 2/5: its facets cut the skin) give the tight forms; 5/7 v0
is checked with the inertia's offset in the tolerance. Measured values and the reasons of
each tolerance: docs/notes/2026-11-29-rolling-sphere.md.

The sphere's nodes are the slave side, the plate's flat top the master facets: the sphere
rolls on the vertices of its mesh (0.2 mm near the pole it rolls on), pivoting about one
node between vertex changes, so while it pivots the normal force is m (g - v^2 / R) (the
centre's circular path about the node), not m g.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from flexmvm.assembly.build import build_scenario
from flexmvm.integrate.driver import simulate
from flexmvm.scenarios import scenario_from_dict

G, R, MU, V0 = 9.81, 0.010, 0.3, 0.05
STEEL = {"name": "steel", "E_pa": 210.0e9, "nu": 0.3, "rho_kg_m3": 7850.0}


def _meshes(folder):
    """The sphere (2 mm, 0.2 mm within 2 mm of its -z pole) and the plate (5 mm) meshes."""
    pytest.importorskip("gmsh")
    from flexmvm.mesh.gmsh_session import Refinement
    from flexmvm.mesh.part_shapes import block, sphere

    ball = sphere(folder / "ball.msh", R, 2.0e-3, refine=Refinement((0, 0, -R), 2e-4, 2e-3, 4e-3))
    return ball, block(folder / "plate.msh", 0.04, 0.02, 0.005, 5.0e-3)


def _scenario(folder, plate_kind: str, t_end_s: float):
    """The sphere touching the plate's top at the origin at t = 0, moving at V0 along x. A
    full plate is clamped on its bottom; a rigid one is held by a ground joint."""
    ball, plate = _meshes(folder)
    held = (
        {"supports": [{"type": "clamp", "body": "plate", "node_set": "bottom"}]}
        if plate_kind == "full"
        else {"joints": [{"type": "ground", "body": "plate"}]}
    )
    return scenario_from_dict(
        {
            "name": "rolling_sphere",
            "gravity_mps2": [0.0, 0.0, -G],
            "time": {"t_end_s": t_end_s, "dt_s": 1e-4, "output_dt_s": 1e-4},
            "bodies": [
                {
                    "name": "plate",
                    "material": "aluminium",
                    "mesh_file": str(plate),
                    "model": {"kind": plate_kind},
                    "placement": {"position_m": [-0.01, 0.0, 0.0]},
                },
                {
                    "name": "ball",
                    "material": STEEL,
                    "mesh_file": str(ball),
                    "model": {"kind": "rigid"},
                    "placement": {"position_m": [0.0, 0.0, R], "velocity_mps": [V0, 0.0, 0.0]},
                },
            ],
            "contacts": [
                {"slave": "ball.front", "master": "plate.top", "friction_coefficient": MU}
            ],
            **held,
        }
    )


@functools.cache
def _run(folder, plate_kind: str):
    """The run (10 ms) and the sphere's mass and inertia about y from its mesh."""
    built = build_scenario(_scenario(folder, plate_kind, 0.010))
    res = simulate(built.system, built.states, built.grid)
    inv = built.system.bodies[1].inv
    m = inv.mass
    c = inv.S0 / m
    return res, m, inv.G0[0, 0] + inv.G0[2, 2] - m * (c[0] ** 2 + c[2] ** 2)


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("rolling")


@pytest.mark.parametrize("plate_kind", ["full", "rigid"])
def test_slides_then_rolls_at_the_rigid_body_speed(folder, plate_kind):
    """Sliding deceleration, time to roll and rolling speed against the closed forms, every
    step at h (no step cut). Measured full / rigid plate:

    - a (fit over 0.5 ms .. t_r - 0.5 ms) within 1 % of -mu g: -0.64 % / -0.63 %; the mean
      normal force while sliding is 0.5 % below m g (the pivots on the mesh's vertices,
      module doc), and the friction force is mu N.
    - the slip v - omega R first below 1e-3 v0 within 2 output steps (0.2 ms) of t_r (mesh
      inertia): 4.90 ms against 4.83 ms (0.03 ms from the slower a, the rest the 0.1 ms
      output step).
    - v_r (mean after t_r + 1 ms) within 0.3 % of the mesh's v0 k / (1 + k) (+0.084 % both,
      the vertex impacts while sliding) and within 0.6 % of 5/7 v0 (+0.32 %: the mesh's
      inertia 0.8 % below 2/5 m R^2 adds +0.23 %).
    - rolling holds: |slip| after t_r + 1 ms below 1e-3 v0 and its mean below 1e-4 v0 (a
      cone that let a sticking contact creep would show here): 2.0e-4 / 2.0e-5 v0 and
      -8.4e-6 / -6.8e-6 v0 (the full plate's ringing after a vertex impact at 6.7 ms)."""
    res, m, I = _run(folder, plate_kind)
    assert res.step_cuts == 0 and res.n_steps == 100
    t, v, w = res.t, res.frame_v[:, 1, 0], res.frame_v[:, 1, 4]
    k = m * R * R / I
    vr = V0 * k / (1 + k)
    tr = (V0 - vr) / (MU * G)
    sliding = (t > 0.5e-3) & (t < tr - 0.5e-3)
    a = np.polyfit(t[sliding], v[sliding], 1)[0]
    assert a == pytest.approx(-MU * G, rel=0.01)
    slip = v - w * R
    t_roll = t[np.argmax(np.abs(slip) < 1e-3 * V0)]
    assert abs(t_roll - tr) < 2.0e-4
    rolled = t > tr + 1e-3
    assert v[rolled].mean() == pytest.approx(vr, rel=0.003)
    assert v[rolled].mean() == pytest.approx(5.0 / 7.0 * V0, rel=0.006)
    assert np.abs(slip[rolled]).max() < 1e-3 * V0
    assert abs(slip[rolled].mean()) < 1e-4 * V0
    assert res.friction.max_sliding == 1 and res.friction.max_sticking == 1


@pytest.mark.parametrize("plate_kind", ["full", "rigid"])
def test_rolling_normal_force_and_friction_dissipation(folder, plate_kind):
    """Once rolling, the normal force is m (g - v_r^2 / R), the sphere pivoting about one
    node (module doc), 1.3 % below m g (v_r^2 / g R). Measured full / rigid plate: its
    median within 1e-3 (-3.2e-4 / +3e-6), its mean (vertex impacts and the plate's ringing
    after them included) within 0.5 % (-0.04 % / -0.000 %; std 0.23 m g: a vertex impact at
    6.7 ms, and on the full plate its step-to-step ringing after it, +-5 % decaying over ~15
    steps).
    The contact's work (integrate.energy_ledger) at the end, against the friction's
    dissipation (1/2) m v0^2 - (1/2)(m + I / R^2) v_r^2 with the mesh's inertia: within
    0.5 % (+0.010 % / +0.016 %; -0.12 % at t_r + 0.5 ms: the vertex impacts take energy, as
    they take speed above), and the ledger closes to 1e-6 of it (1e-7)."""
    res, m, I = _run(folder, plate_kind)
    t, v, F = res.t, res.frame_v[:, 1, 0], res.contact_force
    k = m * R * R / I
    vr = V0 * k / (1 + k)
    rolled = t > (V0 - vr) / (MU * G) + 1e-3
    pivot = m * (G - v[rolled].mean() ** 2 / R)
    assert np.median(F[rolled]) == pytest.approx(pivot, rel=1e-3)
    assert F[rolled].mean() == pytest.approx(pivot, rel=0.005)
    dissipated = 0.5 * m * V0**2 - 0.5 * (m + I / R**2) * vr**2
    ledger = res.energy_ledger
    assert -ledger.contact[-1] == pytest.approx(dissipated, rel=0.005)
    assert np.abs(ledger.residual(res.total_energy)).max() < 1e-6 * dissipated
