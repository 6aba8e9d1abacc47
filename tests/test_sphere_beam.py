"""A rigid sphere striking a free tet10 beam at mid-span (Timoshenko's problem, coarse): the
case that stopped a new user's run mid-impact (issue "Your own geometry").

- Start check: a node far from a convex master (the sphere) projects inside facets on the
  sphere's far side, behind it; the closest-point rule (contact.geometry.closest_facets) must
  take the near facet, else the bodies "overlap by 7.7 cm" at t = 0.
- Convergence: a full-FE body's floating-frame Schur complement is the inertia near its 3-2-1
  nodes only, so the iteration matrix needs its exact J (moreau_jean._prepare_body): with the
  first-order J the beam's steps stalled with a factor ~ -1 in the frame rows once it rang.
- MVM against full FE on the same case: the contact force history agrees (NCC)."""

from __future__ import annotations

import numpy as np
import pytest

import flexmvm as fm
from flexmvm.metrics.ncc import compare_force

pytest.importorskip("gmsh")

import _gmsh_meshes

V0 = 0.5  # impact speed [m/s]
R = 0.01  # sphere radius [m]


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    d = tmp_path_factory.mktemp("sphere_beam")
    ball = _gmsh_meshes.sphere(d / "ball.msh", R, 2.5e-3, order=1)
    beam = _gmsh_meshes.box(d / "beam.msh", 0.2, 0.01, 0.01, fine=1.0e-3, coarse=5e-3, order=2)
    return ball, beam


def _scenario(meshes, model: dict, t_end: float):
    ball, beam = meshes
    return fm.scenario_from_dict(
        {
            "name": "sphere_beam_coarse",
            "time": {
                "t_end_s": t_end,
                "dt_s": 0.5e-6,
                "dt_max_s": 2e-6,
                "output_dt_s": 1e-6,
                "hf_damping_time_s": 12.5e-6,
            },
            "bodies": [
                {
                    "name": "ball",
                    "mesh_file": str(ball),
                    "model": {"kind": "rigid", "reference": "skin"},
                    "material": {"E_pa": 210e9, "nu": 0.3, "rho_kg_m3": 7850.0},
                    # touching the top face (z = 5 mm) with its lowest node
                    "placement": {"position_m": [0.0, 0.0, 0.005 + R], "velocity_mps": [0, 0, -V0]},
                },
                {
                    "name": "beam",
                    "mesh_file": str(beam),
                    "model": {"reference": "ends", **model},
                    "material": {"E_pa": 70e9, "nu": 0.33, "rho_kg_m3": 2700.0},
                },
            ],
            "contacts": [{"slave": "beam.top", "master": "ball.skin", "law": "position"}],
            "probes": [{"name": "mid_bottom", "body": "beam", "point_m": [0.0, 0.0, -0.005]}],
        }
    )


def test_start_check_takes_the_near_side_of_a_convex_master(meshes):
    """Before the closest-point rule, a beam node 6.6 cm from the sphere projected inside a
    facet on the sphere's far side and was read as 7.7 cm inside it: InputError at t = 0."""
    from flexmvm.assembly.build import build_scenario

    built = build_scenario(_scenario(meshes, {"kind": "full"}, 1e-6))
    pens = built.system.contacts[0].penetration(built.system.bodies, built.states, deep=True)
    # the sphere's lowest node sits on the top face: depths of round-off and faceting only
    assert max(p.depth_m for p in pens) < 1e-6


@pytest.fixture(scope="module")
def runs(meshes):
    """Full FE and MVM through the first impact and the separation (200 us)."""
    full = fm.run(_scenario(meshes, {"kind": "full"}, 2e-4))
    mvm = fm.run(
        _scenario(
            meshes,
            {
                "kind": "mvm",
                "modes": 30,
                "region": {"ball": {"centre_m": [0, 0, 0.005], "radius_m": 1.5e-3}},
            },
            2e-4,
        )
    )
    return full, mvm


def test_full_fe_beam_converges_through_the_impact(runs):
    """Every step converged to the Newton tolerance (none accepted on the round-off floor),
    no step cut, the contact closed and opened again: the whole first impact."""
    full, _ = runs
    s = full.summary
    assert s["status"] == "completed" and s["steps_on_roundoff_floor"] == 0
    assert s["newton_residual_max"] <= 1e-10
    assert s["contact_intervals_s"] and s["contact_intervals_s"][0][1] < 2e-4 - 1e-6
    # the rigid ball and the free beam: momentum is exchanged, not made. As the steps
    # converged (before their translational balance) it moved by 3.9e-7 over 322 steps, of
    # which the solves' residuals 8.4e-10: the rest is not the Newton tolerance's, so the
    # bound is 2.5 x the measured value, not a round-off one
    assert s["momentum_rel_error_converged"] < 1e-6


def test_mvm_beam_against_full_fe(runs):
    """Force history NCC over the contact windows (metrics.ncc.compare_force: from the first
    contact to the last, not the free flight's zeros) >= 0.996 and peak within 3 % (the
    issue's acceptance for the beam's showcase), with a reduced beam of at most 600 DOF.
    Measured: 1 - NCC 4.4e-4 over the two contacts (45.5-106 us, 164.5-183 us; 3.7e-4 over the
    whole 200 us), so the bound is 9 x it; peak +0.21 %."""
    full, mvm = runs
    assert mvm.summary["dof"]["beam"] <= 600
    assert mvm.summary["steps_on_roundoff_floor"] == 0
    assert compare_force(full.t, full.contact_force, mvm.t, mvm.contact_force).ncc >= 0.996
    peak_f, peak_m = full.contact_force.max(), mvm.contact_force.max()
    assert abs(peak_m - peak_f) <= 0.03 * peak_f
    np.testing.assert_allclose(mvm.t, full.t)
