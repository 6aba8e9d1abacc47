"""The seed case with yielding rods (scenarios/rod_impact_plastic.toml and
rod_impact_short_plastic.toml, docs/plasticity.md "The seed case with yielding rods"): each is
its elastic seed scenario with the handbook yield strengths added and nothing else changed but
what plasticity requires (both rods full FE, no contact mass redistribution), and the whole
cells of the struck rod's selections are the ones the page's MVM table counts; the same for
sphere_block_plastic.toml against sphere_block.toml. Builds no
system: about 3 s of CPU (rod meshes; 9 s of wall time at load 9 on 2 cores)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flexmvm.materials import PRESETS
from flexmvm.mesh.rod import RodSpec, rod_mesh
from flexmvm.scenarios import load_scenario

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
# handbook values the scenario headers cite [Pa]: (Y, H_iso) of 6061-T6 and C36000 H02
YIELD = {"b1": (310.0e6, 0.30e9), "b2": (276.0e6, 0.29e9)}


@pytest.mark.parametrize(
    "plastic, elastic",
    [
        ("rod_impact_plastic.toml", "rod_impact.toml"),
        ("rod_impact_short_plastic.toml", "rod_impact_short.toml"),
    ],
)
def test_plastic_seed_scenario_is_the_seed_case_with_yield_added(plastic, elastic):
    p, e = load_scenario(SCENARIOS / plastic), load_scenario(SCENARIOS / elastic)
    assert p.time == e.time and p.probes == e.probes  # exact: copied, not re-derived
    for name in ("b1", "b2"):
        bp, be = p.body(name), e.body(name)
        assert bp.rod == be.rod and bp.placement == be.placement
        preset = PRESETS[be.material]
        m = bp.material  # the seed's E, nu, rho (table 1), exactly the preset's
        assert (m.E_pa, m.nu, m.rho_kg_m3) == (preset.E, preset.nu, preset.rho)
        assert (m.plasticity.yield_pa, m.plasticity.hardening_pa) == YIELD[name]
        assert m.plasticity.kinematic_hardening_pa == 0.0
        assert bp.model.kind.value == "full"  # the reference: both rods full FE
    (cp,), (ce,) = p.contacts, e.contacts
    assert (cp.slave, cp.master, cp.law) == (ce.slave, ce.master, ce.law)
    assert ce.redistribute_mass and not cp.redistribute_mass  # refused with plastic bodies


@pytest.mark.parametrize("length_m", [0.1, 1.0])
def test_whole_cells_of_the_struck_rods_selections(length_m):
    """The counts of docs/plasticity.md's MVM table (exact integers): HEX27 cells span three
    node layers, so the elastic seed model's 1-3 holds none."""
    rod = rod_mesh(RodSpec(length_m=length_m, radius_m=0.01))
    (block,) = rod.mesh.cells
    counts = {}
    for layers, laps in ((1, 3), (2, 5), (3, 5), (3, 7), (5, 5)):
        kept = np.zeros(len(rod.mesh.nodes), bool)
        kept[rod.selection(layers, laps)] = True
        counts[f"{layers}-{laps}"] = int(kept[block.connectivity].all(axis=1).sum())
    assert counts == {"1-3": 0, "2-5": 0, "3-5": 12, "3-7": 20, "5-5": 24}


def test_plastic_block_scenario_is_sphere_block_with_yield_added():
    """scenarios/sphere_block_plastic.toml (docs/plasticity.md "Sphere on block: the region
    for the plastic zone") is sphere_block.toml with 6061-T6's yield (header: 276 MPa, H_iso 1 %
    of E as the full-FE run of the plastic dynamics note), 130 us, and its MVM form the select
    study's answer: the nodes within 1.1 mm of (0, 0, -0.2) mm, 713 nodes holding 309 whole
    tet10 cells (exact integers of the page's table). Builds no system: ~1 s (one mesh read)."""
    from flexmvm.assembly.mesh_lookup import retained_nodes
    from flexmvm.mesh.io import read_mesh

    p = load_scenario(SCENARIOS / "sphere_block_plastic.toml")
    e = load_scenario(SCENARIOS / "sphere_block.toml")
    assert p.time.t_end_s == 0.13e-3 and p.time.dt_s == e.time.dt_s
    assert p.probes == e.probes and p.contacts == e.contacts and p.body("ball") == e.body("ball")
    bp, be = p.body("block"), e.body("block")
    assert bp.mesh_file == be.mesh_file and bp.placement == be.placement
    preset, m = PRESETS[be.material], bp.material
    assert (m.E_pa, m.nu, m.rho_kg_m3) == (preset.E, preset.nu, preset.rho)
    assert (m.plasticity.yield_pa, m.plasticity.hardening_pa) == (276.0e6, 0.69e9)
    assert bp.model.kind.value == "full" and bp.model.modes == 10
    mesh = read_mesh(bp.mesh_file)
    kept = np.zeros(mesh.n_nodes, bool)
    kept[retained_nodes(bp.model, mesh, None, "block")] = True
    (cells,) = mesh.cells
    assert (int(kept.sum()), int(kept[cells.connectivity].all(axis=1).sum())) == (713, 309)
