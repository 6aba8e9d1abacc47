"""The reference condition of mesh bodies: "auto" (assembly/body_reference.py,
reduction.reference_condition.far_reference) when a mesh_file body names none, none for rigid bodies,
end_b for rods; on the shipped sphere_beam scenario (its meshes are stored, no gmsh needed)."""

import tomllib
from pathlib import Path

import numpy as np
import pytest

from flexmvm.assembly.build import build_scenario
from flexmvm.errors import InputError
from flexmvm.scenarios import load_scenario, scenario_from_dict

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


def _reference_nodes(body) -> np.ndarray:
    """The nodes of a full-FE body's reference condition: its basis has zero rows there."""
    psi = body.psi.tocsr() if hasattr(body.psi, "tocsr") else np.asarray(body.psi)
    rows = (
        np.flatnonzero(np.diff(psi.indptr) == 0)
        if hasattr(psi, "indptr")
        else np.flatnonzero(~np.any(psi, axis=1))
    )
    assert len(rows) == 6
    return np.unique(rows // 3)


def _beam_scenario(surface: str) -> dict:
    """The shipped sphere_beam scenario with the contact on beam facet set ``surface`` (the
    beam is the contact's slave side)."""
    data = tomllib.loads((SCENARIOS / "sphere_beam.toml").read_text())
    data["contacts"][0]["slave"] = f"beam.{surface}"
    return data


@pytest.mark.parametrize("surface", ["mid_top", "end_a"])
def test_auto_reference_far_from_contact(surface):
    """A mesh body without ``reference`` gets "auto": a 3-2-1 support among the nodes
    farthest from its contact surface. On the shipped 200 mm beam with the contact on
    ``mid_top`` the three nodes are near the two ends (>= 0.9 of the largest distance from
    the patch, i.e. |x - 0.1| >= 0.08 m); with the contact on ``end_a`` (x = 0) all three are
    at the far end, x >= 0.17 m. The rigid sphere, whose mesh has no ``end_b``, builds (it
    needs no reference)."""
    sc = scenario_from_dict(_beam_scenario(surface), source="sphere_beam", base_dir=SCENARIOS)
    assert sc.body("beam").model.reference == "auto"
    built = build_scenario(sc)
    beam_info = built.info[1]
    x = beam_info.mesh.nodes[_reference_nodes(built.system.bodies[1]), 0]
    if surface == "mid_top":
        assert np.all(np.abs(x - 0.1) >= 0.08)
    else:
        assert np.all(x >= 0.17)
    assert built.system.bodies[0].nq == 0


def test_reference_defaults_by_geometry(tmp_path):
    """``reference`` left out: "auto" for a mesh_file body (also given through a model
    constructor), "end_b" for a rod, and a named set stays as given."""
    from flexmvm import full

    data = _beam_scenario("mid_top")
    data["bodies"][1]["model"].update(reference="end_a", modes=5)
    sc = scenario_from_dict(data, source="s", base_dir=SCENARIOS)
    assert sc.body("beam").model.reference == "end_a"
    assert sc.with_model("beam", full()).body("beam").model.reference == "auto"
    assert sc.with_kind("modal").body("beam").model.reference == "end_a"
    rods = load_scenario(SCENARIOS / "rod_impact_short.toml")
    assert rods.body("b2").model.reference == "end_b"
    assert rods.with_model("b2", full()).body("b2").model.reference == "end_b"


def test_unknown_contact_surface_of_auto_reference_is_one_line():
    """An automatic reference needs its body's contact surfaces: a contact on a surface the
    mesh lacks is one InputError line naming the contact's key and the known surfaces."""
    sc = scenario_from_dict(_beam_scenario("nowhere"), source="s", base_dir=SCENARIOS)
    with pytest.raises(
        InputError,
        match=r"contacts\[0\]\.slave = 'beam\.nowhere': body 'beam': unknown surface "
        r"'nowhere'; known: .*mid_top",
    ) as info:
        build_scenario(sc)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(("name", "model"), [("sphere_block", "full"), ("sphere_beam", "mvm")])
def test_sphere_scenarios_start(name, model):
    """The shipped sphere scenarios build and run their first 10 us (20 steps): the contact
    closes (force > 0), linear momentum of the free pair, as the steps converged, is
    conserved through the impact to 1e-7 (momentum_rel_error_converged: measured 8.3e-11 on
    the block, 1.8e-8 on the MVM beam, whose solves' residuals account for 3.5e-13 of it:
    the rest is not the Newton tolerance's) and no node
    penetrates more than 1 um (the velocity law pushes back 0.2 of a penetration per step).
    The MVM beam (471 DOF, ~57 MB of dense matrices against full FE's ~65 MB with its
    factors, and faster a step: assembly.cost) builds without a ReducedCostWarning."""
    import warnings

    from flexmvm.assembly.cost import ReducedCostWarning
    from flexmvm.runs.run import run_scenario

    sc = load_scenario(SCENARIOS / f"{name}.toml").with_overrides(model=model, t_end_s=10e-6)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ReducedCostWarning)
        run = run_scenario(sc, warn=False)
    assert run.contact_force.max() > 0
    assert run.summary["momentum_rel_error_converged"] < 1e-7
    assert run.summary["max_penetration_m"] < 1e-6


def test_flexible_sphere_reference_at_its_back():
    """A flexible sphere (the shipped rigid one made full FE) whose contact surface is its
    ``front`` cap (within 30 degrees of the -z pole) gets its automatic support at the
    opposite side: all three nodes at z >= 0.8 R in its own frame."""
    from flexmvm import full

    sc = load_scenario(SCENARIOS / "sphere_block.toml").with_model("ball", full())
    assert sc.body("ball").model.reference == "auto"
    built = build_scenario(sc)
    z = built.info[0].mesh.nodes[_reference_nodes(built.system.bodies[0]), 2]
    assert np.all(z >= 0.8 * 0.010)
