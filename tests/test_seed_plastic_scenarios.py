"""The seed case with yielding rods (scenarios/rod_impact_plastic.toml and
rod_impact_short_plastic.toml, docs/plasticity.md "The seed case with yielding rods"): each is
its elastic seed scenario with the handbook yield strengths added and nothing else changed but
what plasticity requires (both rods full FE, no contact mass redistribution), and the whole
cells of the struck rod's selections are the ones the page's MVM table counts. Builds no
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
