"""The cost guard (issue 49 item 4, assembly/cost.py): full FE estimated from its factor's fill
(the symbolic analysis of its iteration matrix), memory and time a step compared, a warning
only beyond MARGIN.

Measured (2-core AMD EPYC, `flexmvm run --model full` against `--model mvm`, one after the
other; docs/notes/2026-11-29-warm-command.md): sphere_beam peak RSS 564 MB full against 449 MB
reduced, simulation 2.0 x faster reduced: the estimate (65 MB against 57 MB, 42 MB against
16 MB streamed a Newton iteration) has the reduced body smaller and faster, as measured;
before, full FE was taken as 6 nnz(K) (34 MB against 52 MB) and the run warned.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import flexmvm as fm
from flexmvm.assembly import cost
from flexmvm.assembly.body_reference import reference_label
from flexmvm.assembly.build import build_scenario
from flexmvm.assembly.build_cache import SetupCache
from flexmvm.assembly.cache_keys import mesh_key, mesh_source
from flexmvm.assembly.cost import (
    BodyCost,
    FullFactor,
    ReducedCostWarning,
    cached_full_factor,
    check_cost,
    full_factor,
    reduced_cost,
    step_sizes,
)
from flexmvm.assembly.mesh_lookup import contact_surfaces, retained_nodes
from flexmvm.assembly.supports import bedded_key
from flexmvm.integrate.moreau_jean.body_solver import MAX_CACHED, BodySolver
from flexmvm.integrate.run_result import TimeGrid

ROOT = Path(__file__).resolve().parents[1]
TINY = Path(__file__).parent / "data" / "tiny_impact.toml"


def test_the_fill_is_the_factor_the_integrator_makes():
    """full_factor's stored entries of L are those of the factor the integrator makes for the
    full-FE body (BodySolver, at a step size): the same pattern and elimination order. The
    tiny rod (full FE, 1,000-odd DOF): equal, not estimated. ~1 s."""
    setup = SetupCache()
    sc = fm.load_scenario(TINY).with_overrides(model="full").with_time(t_end_s=1e-6)
    built = build_scenario(sc, setup)
    cfg = sc.bodies[1]
    fe = setup.fe_model(mesh_key(cfg), cfg.material_obj())
    solver = BodySolver(built.system.bodies[1])
    solver.elastic_solve(sc.time.dt_s)
    ref = setup.reference_condition(mesh_key(cfg), fe.mesh, cfg.model.reference)
    counts = full_factor(fe, ref.fixed_dofs)
    assert counts.l_nnz == solver._symbolic.nnz
    assert built.system.bodies[1].nq == fe.K.shape[0] - ref.fixed_dofs.size


def test_sphere_beam_reduced_is_not_warned_and_is_estimated_as_measured():
    """The shipped sphere_beam's beam as kind mvm (465 columns on 10,269 DOF): estimated
    smaller (57 MB against 65 MB, within 15 % of each other) and ~2.7 x cheaper a Newton
    iteration than full FE (measured: 115 MB less peak RSS, 2.0 x faster simulation); no
    ReducedCostWarning (it warned before: ~52 MB against ~34 MB). ~3 s (FE assembly)."""
    sc = fm.load_scenario(ROOT / "scenarios" / "sphere_beam.toml").with_overrides(model="mvm")
    setup = SetupCache()
    (cfg,) = [b for b in sc.bodies if b.name == "beam"]
    key = bedded_key(mesh_key(cfg), cfg, sc.supports)
    mesh = setup.mesh(mesh_key(cfg))
    n_ret = len(retained_nodes(cfg.model, mesh, None, "beam"))
    label = reference_label(cfg.model.reference, mesh, contact_surfaces(sc, "beam"), "beam")
    ref = setup.reference_condition(key, mesh, label)
    load_fe = lambda: setup.fe_model(key, cfg.material_obj())
    full = cached_full_factor(mesh_source(key), ref.fixed_dofs, load_fe)
    assert 2.4 < full.l_nnz / full.k_nnz < 2.8  # measured 2.61: the fill, not FILL_PER_NNZ
    sizes = step_sizes(sc.time.dt_s, sc.time.dt_max_s)
    c = reduced_cost("beam", mesh.n_nodes, 3 * n_ret + 30, full.k_nnz, full=full, sizes=sizes)
    assert c.bytes < c.full_bytes and c.step_bytes < 0.5 * c.full_step_bytes
    with warnings.catch_warnings():
        warnings.simplefilter("error", ReducedCostWarning)
        check_cost(c, False, "bodies[beam].model")


def test_smaller_but_slower_a_step_is_warned():
    """A body within full FE's memory whose dense matrices stream more than MARGIN x what
    full FE's factor and M, K do a Newton iteration: warned, naming the time (before, memory
    alone was compared and it passed)."""
    c = BodyCost("b", 906, 40e6, 30_000, 60e6, step_bytes=50e6, full_step_bytes=20e6)
    with pytest.warns(ReducedCostWarning, match="its time a step more than 1.5 x"):
        check_cost(c, False, "bodies[b].model")


def test_within_the_margin_is_not_warned():
    """Estimated up to MARGIN x full FE in memory and time: no warning (the estimates leave
    out what both models hold; within that they are not told apart)."""
    full = FullFactor(k_nnz=1_000_000, m_nnz=300_000, l_nnz=4_000_000)
    # full FE: 27.6 MB of M and K, 64 MB of factor and fronts; reduced: 93.8 MB dense
    c = reduced_cost("b", 20_000, 190, full.k_nnz, full=full)
    assert c.full_bytes < c.bytes <= cost.MARGIN * c.full_bytes
    with warnings.catch_warnings():
        warnings.simplefilter("error", ReducedCostWarning)
        check_cost(c, False, "bodies[b].model")


@pytest.mark.parametrize(
    ("dt", "dt_max"), [(0.5e-6, None), (0.5e-6, 0.5e-6), (0.5e-6, 2e-6), (0.5e-6, 3e-6), (1e-6, 1)]
)
def test_step_sizes_are_the_grids_levels(dt, dt_max):
    """One factor per step level of the time grid (TimeGrid.ticks: dt 2^k up to dt_max), at
    most the solver's MAX_CACHED."""
    k_max = TimeGrid(1e-3, dt, dt_max).ticks()[2]
    assert step_sizes(dt, dt_max) == min(k_max + 1, MAX_CACHED)
    assert cost.MAX_FACTORS == MAX_CACHED


def test_without_an_analysis_the_fill_is_estimated():
    """reduced_cost without ``full`` (the studies' quick estimates) takes FILL_PER_NNZ, and
    the fronts of the factorization as large as the factor (measured 0.7-1.0 x it)."""
    c = reduced_cost("b", 1000, 10, 100_000)
    e = FullFactor.estimated(100_000)
    assert e.l_nnz == int(cost.FILL_PER_NNZ * 100_000) and e.stored == e.fronts == e.l_nnz
    np.testing.assert_allclose(c.full_bytes, 12 * (2 * 100_000 + e.m_nnz) + 8 * 2 * e.l_nnz)


def test_an_analysis_counts_the_factor_as_stored_and_its_fronts():
    """With the symbolic analysis's counts, full FE holds its factor as stored (squares per
    supernode) per step size and, beside the last one made, the fronts."""
    full = FullFactor(1_000_000, 300_000, 4_000_000, factor_entries=5_000_000, front_entries=3e6)
    c = reduced_cost("b", 20_000, 10, full.k_nnz, full=full, sizes=2)
    np.testing.assert_allclose(c.full_bytes, 12 * 2_300_000 + 8 * (2 * 5_000_000 + 3_000_000))
    # a Newton iteration reads L's entries (not the squares' upper halves) twice
    np.testing.assert_allclose(c.full_step_bytes, 2 * 8 * 4_000_000 + 12 * 1_300_000)
