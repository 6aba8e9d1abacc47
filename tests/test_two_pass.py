"""One contact pair between two deformable bodies (issue "Numbers a user can trust, part
three", item 8): a point-to-surface pair holds the slave's nodes out of the master's facets,
not the master's nodes out of the slave's, so a master edge can go through the slave surface.

The case: a coarse steel link (40 x 6 x 6 mm, tet4, 4 mm elements) tilted 45 degrees about y,
its end face's lower edge at 5 m/s onto the top of a coarse aluminium cantilever (120 x 12 x
6 mm, tet4, 6 mm elements, clamped at x = 120 mm), both full FE (324 + 558 DOF), the edge 3 mm
from the nearest top nodes. With the one pair cantilever.top -> link.surface the edge goes
straight through: no contact force, and the penetration measure reads only its reach, the
pair's search radius 2e-4 m (3 % of the 6 mm thickness), so before runs.blowup's reach
bound the run "completed". ``two_pass = true`` adds the reverse pair (same law, options):
penetration 7.3e-9 m, peak 3.75 kN. About 1 s of CPU per run after the kernels compile."""

from __future__ import annotations

import math

import pytest

from flexmvm.errors import SimulationFailed
from flexmvm.mesh.link import connecting_rod
from flexmvm.mesh.part_shapes import beam
from flexmvm.runs.run import run_scenario
from flexmvm.scenarios.load import scenario_from_dict
from flexmvm.scenarios.problems import ScenarioError

STEEL = {"name": "steel", "E_pa": 210.0e9, "nu": 0.3, "rho_kg_m3": 7850.0}
ONE_PAIR = {"slave": "cant.top", "master": "link.surface", "law": "position"}
REVERSE = {"slave": "link.surface", "master": "cant.top", "law": "position"}


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    d = tmp_path_factory.mktemp("two_pass")
    beam(d / "cant.msh", 0.12, 0.012, 0.006, 6e-3)
    connecting_rod(d / "link.msh", 0.04, 0.006, 0.006, 4e-3, order=1)
    return d


def link_on_cantilever(d, contacts, t_end_s=150e-6):
    """The module doc's case: the link's end-face edge 0.05 mm above the cantilever's top at
    x = 90 mm (3 mm from the top nodes at x = 87 and 93 mm), moving at 5 m/s down."""
    tilt, half, gap, x0 = 45.0, 0.003, 0.05e-3, 0.090
    c, s = math.cos(math.radians(tilt)), math.sin(math.radians(tilt))
    link = {
        "name": "link",
        "material": STEEL,
        "mesh_file": str(d / "link.msh"),
        "model": {"kind": "full"},
        "placement": {
            "position_m": [x0 - half * s, 0.0, gap + half * c],
            "rotation": {"axis": [0.0, 1.0, 0.0], "angle_deg": -tilt},
            "velocity_mps": [0.0, 0.0, -5.0],
        },
    }
    cant = {
        "name": "cant",
        "material": "aluminium",
        "mesh_file": str(d / "cant.msh"),
        "model": {"kind": "full"},
    }
    data = {
        "name": "link_on_cantilever",
        "time": {
            "t_end_s": t_end_s,
            "dt_s": 1e-6,
            "output_dt_s": 1e-6,
            "hf_damping_time_s": 12.5e-6,
        },
        "bodies": [cant, link],
        "supports": [{"type": "clamp", "body": "cant", "node_set": "end_b"}],
        "contacts": contacts,
    }
    return scenario_from_dict(data)


def test_one_pair_lets_the_edge_through_and_the_run_fails_naming_the_reverse_pair(meshes):
    """The edge passes through (no contact force) and the measure reads its reach, 2e-4 m:
    deeper than half the search radius, the run fails and the line names the pair to add."""
    with pytest.raises(SimulationFailed) as info:
        run_scenario(link_on_cantilever(meshes, [ONE_PAIR]), warn=False)
    summary = info.value.partial.summary
    line = summary["failure"]
    assert summary["status"] == "failed" and "\n" not in line
    assert summary["max_contact_force_interval_mean_N"] == 0.0  # went through: no force at all
    at = summary["max_penetration_at"]
    assert at["body"] == "link" and at["against"] == "cant"
    assert f"node {at['node']} of body 'link'" in line and "may have gone through" in line
    assert "pair cant.top->link.surface" in line
    assert "add the reverse pair (slave 'link', master 'cant'), or set two_pass = true" in line


def test_two_pass_is_the_reverse_pair_and_holds_the_edge(meshes):
    """two_pass = true builds the reverse pair with the same law: the run equals the one with
    both pairs written out (same providers, same order: bit-identical numbers), the edge stays
    out to 7.3e-9 m (bound 1e-7 m: the position law's Newton tolerance on a 6 mm body) and
    the peak force is 3.75 kN."""
    two = run_scenario(link_on_cantilever(meshes, [{**ONE_PAIR, "two_pass": True}]), warn=False)
    both = run_scenario(link_on_cantilever(meshes, [ONE_PAIR, REVERSE]), warn=False)
    s = two.summary
    assert s["status"] == "completed"
    names = [c.name for c in two.built.system.contacts]
    assert names == ["cant.top->link.surface", "link.surface->cant.top"]
    assert s["max_penetration_m"] < 1e-7
    assert s["max_contact_force_interval_mean_N"] == pytest.approx(3749.0, rel=1e-3)
    for key in ("max_contact_force_interval_mean_N", "max_penetration_m", "energy_rel_change"):
        assert s[key] == both.summary[key]


def test_two_pass_with_its_reverse_written_out_is_refused(meshes):
    with pytest.raises(ScenarioError) as info:
        link_on_cantilever(meshes, [{**ONE_PAIR, "two_pass": True}, REVERSE])
    msg = str(info.value)
    assert "\n" not in msg and "contacts[1]" in msg
    assert "duplicate contact 'link.surface on cant.top' (also contacts[0] (its two_pass" in msg
