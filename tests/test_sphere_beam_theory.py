"""The beam theory of the shipped sphere_beam scenario (flexmvm.theory.sphere_beam): what it
reads off the scenario's meshes and placements, the histories it lays over a run, and the
one line where it does not apply, and the resolution of its contact. About 5 s of CPU
(reading the beam's mesh: 3,423 nodes)."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from flexmvm.errors import InputError
from flexmvm.runs.main_job import _theory
from flexmvm.scenarios.load import load_scenario, scenario_from_dict
from flexmvm.theory.scenario import theory_histories
from flexmvm.theory.sphere_beam import LAW, sphere_beam_case

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


@pytest.fixture(scope="module")
def scenario():
    return load_scenario(SCENARIOS / "sphere_beam.toml").with_overrides(t_end_s=2e-4)


def test_the_case_read_off_the_scenario(scenario):
    """The toml's beam (200 x 10 x 10 mm aluminium, struck at mid-span along its local z)
    and sphere (R 10 mm). Geometry to 1e-9 m (mesh coordinates), E* of a rigid sphere on
    aluminium exactly, the sphere's mass within 3 % of 4/3 pi R^3 rho (its skin is faceted:
    the mesh holds 2.0 % less volume) and below it; the pole node touches at t = 0."""
    case = sphere_beam_case(scenario)
    imp, beam = case.impact, case.impact.beam
    assert (case.sphere, case.beam) == ("ball", "beam")
    for got, want in (
        (beam.length_m, 0.2),
        (beam.width_m, 0.01),
        (beam.depth_m, 0.01),
        (imp.contact_x_m, 0.1),
        (imp.sphere_radius_m, 0.01),
    ):
        assert got == pytest.approx(want, abs=1e-9)
    assert imp.e_star_pa == pytest.approx(72.71e9 / (1.0 - 0.33**2), rel=1e-12)
    ideal = 7850.0 * 4.0 / 3.0 * math.pi * 0.01**3
    assert 0.97 * ideal < imp.sphere_mass_kg < ideal
    assert imp.speed_mps == pytest.approx(0.5, rel=1e-12)
    assert case.t_first_touch_s == pytest.approx(0.0, abs=1e-12)
    # the probes: 95 mm and 0 mm along the axis, 5 mm beyond the mid-plane (bottom face);
    # w along the impact (global -x), so their global x velocity is -w_t
    probes = {p[0]: p[1:] for p in case.probes}
    assert probes["beam_mid_bottom"][:3] == pytest.approx(("beam", 0.095, 0.005))
    assert probes["beam_end_a"][:3] == pytest.approx(("beam", 0.0, 0.005))
    assert probes["beam_end_a"][3] == pytest.approx(-1.0)


def test_histories_laid_over_the_run(scenario):
    """theory_histories picks the beam theory for two mesh bodies: a force that starts at
    the touch, is never tensile, rises to its first peak (~250 N; Hertz's half-space impact
    would give 655 N: the free beam gives way) and opens within 0.1 ms; the beam's end moves
    against the impact (global +x) first, as a free beam's end swings back."""
    t, force, probes, info = theory_histories(scenario)
    assert info["law"] == LAW
    assert t[0] == 0.0 and t[-1] == pytest.approx(2e-4)
    assert np.all(force >= 0.0) and 200.0 < force.max() < 300.0
    assert len(info["contacts_s"]) >= 1 and info["contacts_s"][0][1] < 1e-4
    assert set(probes) == {"beam_mid_bottom", "beam_end_a"}
    assert probes["beam_mid_bottom"][np.argmax(force)] < 0.0
    first = np.flatnonzero(np.abs(probes["beam_end_a"]) > 1e-4)[0]
    assert probes["beam_end_a"][first] > 0.0


def test_where_no_theory_applies_the_run_says_so_in_one_line(scenario, tmp_path):
    """The same scenario with the sphere moving obliquely: the main job lists
    comparison_vs_theory under its failures with a one-line reason."""
    data = tomllib.loads((SCENARIOS / "sphere_beam.toml").read_text())
    for body in data["bodies"]:
        body["mesh_file"] = str(SCENARIOS / body["mesh_file"])
    data["bodies"][0]["placement"]["velocity_mps"] = [-0.5, 0.1, 0.0]
    sc = scenario_from_dict(data, source="oblique")
    failures: list[dict] = []
    assert _theory(sc, failures) is None
    assert failures[0]["item"] == "comparison_vs_theory"
    assert failures[0]["reason"].startswith("no theory applies: theory: the sphere's velocity")
    assert "\n" not in failures[0]["reason"]
    with pytest.raises(InputError, match="not normal to a long face"):
        sphere_beam_case(sc)


def test_the_shipped_contact_is_resolved_at_the_hertz_scale(scenario):
    """The theory's Hertz law is what the 3D run computes only if the contact is resolved
    (docs/notes/2026-11-27-hertz-block.md): the beam (slave) has >= 2.5 face nodes per contact
    radius a and the sphere's facets (master) are no longer than a / 2 near the pole. a =
    (3 F R / 4 E*)^(1/3) at F = 245 N, the theory's first peak (Johnson eq. 4.22): 0.28 mm.
    Bounds: 2.5 is the ratio at which sphere_block meets Hertz within 1.4 % (coarser node
    spacing made the contact stiffer); facets of a / 2 lie within 0.25 um of the sphere
    (s^2 / 8 R), 3 % of the approach at that force, where 0.4 mm facets made contacts last 5 %
    longer. The slave spacing needs the tet10 mid-side nodes (the corners are 0.2 mm apart).
    ~1 s (two meshes read)."""
    from scipy.spatial import cKDTree

    from flexmvm.mesh.io import read_mesh

    contact = scenario.contacts[0]
    assert (contact.slave, contact.master) == ("beam.mid_top", "ball.front")
    case = sphere_beam_case(scenario)
    imp = case.impact
    a = (3.0 * 245.0 * imp.sphere_radius_m / (4.0 * imp.e_star_pa)) ** (1.0 / 3.0)
    beam = read_mesh(scenario.body("beam").mesh_file)
    x = beam.nodes[beam.facet_set("mid_top").nodes]
    inside = x[np.linalg.norm(x - [imp.contact_x_m, 0.0, 0.0], axis=1) < a]
    spacing, _ = cKDTree(x).query(inside, k=2)
    assert len(inside) >= math.pi * 2.5**2 and spacing[:, 1].max() <= a / 2.5
    ball = read_mesh(scenario.body("ball").mesh_file)
    tris = ball.facet_set("front").tris
    y = ball.nodes
    near = np.linalg.norm(y[tris].mean(axis=1) - [0.0, 0.0, -imp.sphere_radius_m], axis=1) < a
    edges = np.linalg.norm(y[tris[near]] - y[np.roll(tris[near], 1, axis=1)], axis=2)
    assert near.sum() > 0 and edges.max() <= a / 2.0
