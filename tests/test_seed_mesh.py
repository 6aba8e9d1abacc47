"""The seed case at the seed's mesh resolution (scenarios/rod_impact_seed_mesh.toml, issue 15)
and the two readings of the seed's eq. (4) (reduction.basis SEED_BLOCK and SEED_FIXED).

Measured values (docs/seed_reproduction.md) are quoted at each check with its tolerance.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm.assembly.build import build_scenario
from flexmvm.assembly.build_cache import default_setup
from flexmvm.fe.assembly import assemble
from flexmvm.fe.modes import constrained_modes, factor
from flexmvm.reduction.basis import BasisKind, build_basis
from flexmvm.reduction.rod_reference import rod_reference
from flexmvm.runs.main_job import run_main_job
from flexmvm.scenarios import load_scenario

ROOT = Path(__file__).resolve().parents[1]
SEED_MESH = ROOT / "scenarios" / "rod_impact_seed_mesh.toml"
SEED_NODES = 798  # seed section 3.2: B2 has 798 nodes, 2,394 DOF


@pytest.fixture(scope="module")
def b2():
    """(rod mesh, FE model, reference condition, material) of b2 on the seed mesh."""
    cfg = load_scenario(SEED_MESH).body("b2")
    rod = default_setup().rod_mesh(cfg.rod.spec())
    return rod, assemble(rod.mesh, cfg.material_obj()), rod_reference(rod), cfg


def test_node_counts_are_the_seeds_within_one_section():
    """Both rods: 779 nodes (2,337 DOF), 19 node layers, 6 laps. The mesher's node counts come
    in whole sections (41 nodes here), so the seed's 798 can only be met to -2.4 % (next: 861);
    tolerance 5 % of 798, i.e. less than one section either way."""
    sc = load_scenario(SEED_MESH)
    for name in ("b1", "b2"):
        rod = default_setup().rod_mesh(sc.body(name).rod.spec())
        n = rod.mesh.n_nodes
        assert n == 779, (name, n)
        assert abs(n - SEED_NODES) <= 0.05 * SEED_NODES
        assert 3 * n == 2337
        assert (rod.n_layers, rod.n_laps) == (19, 6)
    rod = default_setup().rod_mesh(sc.body("b2").rod.spec())
    # the seed's i-j grid (i <= 4, j <= 5) exists; 2-2 has fewer nodes than 1-5 (seed fig. 7)
    sizes = {(i, j): len(rod.selection(i, j)) for i in range(1, 5) for j in range(1, 6)}
    assert sizes[(1, 1)] == 1 and sizes[(2, 2)] == 18 and sizes[(1, 5)] == 33
    face = set(rod.mesh.node_set("end_a").tolist())
    assert set(rod.selection(1, 5).tolist()) < face


def test_b2_is_the_seeds_40_dof_model_46_with_the_frame():
    """b2 = eq. (4) 1-1 + 37 modes: 3 + 37 = 40 elastic coordinates + 6 frame = 46 (exact)."""
    built = build_scenario(load_scenario(SEED_MESH))
    info = {i.name: i for i in built.info}
    assert info["b2"].model == "mvm-seed"
    assert (info["b2"].dof, info["b2"].n_retained_nodes, info["b2"].n_modes) == (46, 1, 37)
    assert info["b1"].model == "full" and info["b1"].dof == 3 * 779 - 6 + 6


def test_seed_fixed_is_craig_bampton_without_constraint_modes(b2):
    """SEED_FIXED's modal columns are CB's fixed-interface modes (same solve: equal to 1e-9 of
    their largest entry, round-off of the shared Lanczos run), zero on region II and the
    reference; its nodal columns are the identity on region II and zero elsewhere."""
    rod, fe, ref, _ = b2
    nodes = rod.selection(1, 3)
    fixed = build_basis(fe, BasisKind.SEED_FIXED, ref, retained_nodes=nodes, n_modes=12)
    cb = build_basis(fe, BasisKind.CRAIG_BAMPTON, ref, retained_nodes=nodes, n_modes=12)
    nb = 3 * len(nodes)
    modes = fixed.psi[:, :12]
    assert np.abs(modes - cb.psi[:, nb:]).max() <= 1e-9 * np.abs(modes).max()
    np.testing.assert_allclose(fixed.mode_freqs_hz, cb.mode_freqs_hz, rtol=1e-10)
    b = (3 * nodes[:, None] + np.arange(3)).ravel()
    assert not modes[b].any() and not fixed.psi[ref.fixed_dofs].any()
    nodal = fixed.psi[:, 12:]
    np.testing.assert_array_equal(nodal[b], np.eye(nb))
    assert not np.delete(nodal, b, axis=0).any()
    np.testing.assert_array_equal(fixed.retained_columns().ravel(), 12 + np.arange(nb))


def test_seed_block_is_whole_body_modes_zeroed_on_region_ii(b2):
    """SEED_BLOCK (the code's first reading): the first n modes of the reference-supported body
    with their region-II rows set to zero (equal to the direct eigen solve to 1e-9 relative),
    identity on region II. The rod's bending modes come in near-degenerate pairs (the first
    two 2.6e-9 apart in frequency), within which round-off (here: one BLAS thread in the build
    against several in the direct solve) turns the vectors by ~eps / gap (1.5e-9 measured):
    modes are compared as the spans of such clusters (relative gap < 1e-6)."""
    rod, fe, ref, _ = b2
    nodes = rod.selection(1, 1)
    basis = build_basis(fe, BasisKind.SEED_BLOCK, ref, retained_nodes=nodes, n_modes=10)
    freqs, phi = constrained_modes(fe.M, fe.K, ref.fixed_dofs, 10)
    b = (3 * nodes[:, None] + np.arange(3)).ravel()
    phi[b] = 0.0
    psi = basis.psi[:, :10]
    cluster = np.concatenate([[0], np.cumsum(np.diff(freqs) > 1e-6 * freqs[1:])])
    for c in np.unique(cluster):
        cols = np.flatnonzero(cluster == c)
        turn = np.linalg.lstsq(phi[:, cols], psi[:, cols], rcond=None)[0]
        assert np.abs(psi[:, cols] - phi[:, cols] @ turn).max() <= 1e-9 * np.abs(phi).max()
        np.testing.assert_allclose(np.abs(np.linalg.svd(turn, compute_uv=False)), 1.0, atol=1e-6)
    np.testing.assert_allclose(basis.mode_freqs_hz, freqs, rtol=1e-10)
    np.testing.assert_array_equal(basis.psi[b, 10:], np.eye(3))


def _compliance(fe, psi, f) -> float:
    """f . u [m/N per N^2] of the static response u = Psi (Psi^T K Psi)^-1 Psi^T f."""
    if sp.issparse(psi):
        k_hat = (psi.T @ fe.K @ psi).tocsc()
        return float(f @ (psi @ factor(k_hat)(psi.T @ f)))
    k_hat = psi.T @ (fe.K @ psi)
    return float(f @ (psi @ np.linalg.solve(0.5 * (k_hat + k_hat.T), psi.T @ f)))


def test_static_stiffness_of_the_contact_node(b2):
    """1 N axial on b2's face centre, b2 held by its frame reference (end B). Theorems: CB
    1-1 reproduces the full-FE compliance at its retained node exactly (its constraint modes
    are the static response; rtol 1e-8, round-off of two solves), and every subspace is
    stiffer than full FE. Measured (benchmarks/seed_stiffness.py): full 4.839e-8 m/N (L/(EA)
    = 4.378e-8 of it is the rod's compression), eq. (4) whole-body modes 1.056x stiffer,
    eq. (4) fixed-interface modes 13.6x stiffer (its modes vanish at the node, so the load
    cannot compress the rod); tolerance +-0.01 on the first ratio, +-0.5 on the second
    (regression checks of the numbers the docs quote)."""
    rod, fe, ref, cfg = b2
    centre = int(rod.mesh.node_set("end_a_centre")[0])
    f = np.zeros(fe.n_dof)
    f[3 * centre] = 1.0
    full = _compliance(fe, build_basis(fe, BasisKind.FULL, ref).psi, f)
    rod_1d = cfg.rod.length_m / (cfg.material_obj().E * math.pi * cfg.rod.radius_m**2)
    assert rod_1d < full < 1.2 * rod_1d
    nodes = rod.selection(1, 1)
    c = {
        kind: _compliance(fe, build_basis(fe, kind, ref, retained_nodes=nodes, n_modes=37).psi, f)
        for kind in (BasisKind.CRAIG_BAMPTON, BasisKind.SEED_BLOCK, BasisKind.SEED_FIXED)
    }
    assert c[BasisKind.CRAIG_BAMPTON] == pytest.approx(full, rel=1e-8)
    assert all(v <= full * (1 + 1e-12) for v in c.values())
    assert full / c[BasisKind.SEED_BLOCK] == pytest.approx(1.056, abs=0.01)
    assert full / c[BasisKind.SEED_FIXED] == pytest.approx(13.6, abs=0.5)


def test_seed_mesh_case_runs_against_its_full_fe(tmp_path):
    """The main job on the first 0.5 ms (the whole first contact: 0..435 us in full FE), in one
    process: b2 eq. (4) 1-1 + 37 against b2 full FE on the same mesh. Measured: force NCC
    over the contact window 0.9243 (over the whole 0.5 ms 0.9675, over the default 2 ms
    0.9914: the zero tails raise it), peak +7.1 %, duration -2.7 %, max penetration 4.7e-8 m
    = h (1 - theta) v0 (the first step closes at the impact speed). Tolerances: NCC >= 0.90
    (1 - r may grow 1.3 x), the whole-window NCC above it, peak within 10 %, duration within
    5 %, penetration below 1e-7 m (twice the first-step bound). Its speed is measured by
    benchmarks/, not here."""
    lines: list[str] = []
    s = run_main_job(
        SEED_MESH,
        tmp_path / "out",
        t_end=5e-4,
        fields=False,
        progress=False,
        echo=lines.append,
        jobs=1,
    )
    assert s["dof"] == {"b1": 2337, "b2": 46}
    assert s["model"] == {"b1": "full", "b2": "mvm-seed"}
    assert s["reference_full"]["dof"] == {"b1": 2337, "b2": 2337}
    c = s["comparison_vs_full"]
    assert c["ncc_force"] >= 0.90, c
    assert c["ncc_force_whole"] > c["ncc_force"], c
    assert abs(c["peak_err"]) <= 0.10, c
    assert abs(c["duration_err"]) <= 0.05, c
    theta, h, v0 = 0.55, 0.5e-6, 0.21
    assert s["max_penetration_m"] <= 2 * h * (1 - theta) * v0
    assert s["reference_full"]["max_penetration_m"] <= 2 * h * (1 - theta) * v0
    assert s["failures"] == [] or all("theory" in f["item"] for f in s["failures"])
    assert (tmp_path / "out" / "summary.json").is_file()


@pytest.mark.parametrize(
    "kind, sel, rtol",
    [
        (BasisKind.SEED_FIXED, (1, 1), 1e-10),
        (BasisKind.SEED_FIXED, (2, 2), 1e-10),
        (BasisKind.SEED_BLOCK, (1, 1), 1e-6),
    ],
)
def test_both_eq4_readings_reproduce_statics_with_every_mode(kind, sel, rtol):
    """Loads on region II (random forces on the retained nodes), b2 held by its frame
    reference, a 6 mm rod (1,539 DOF): with every mode of region I (SEED_FIXED, n_I modes:
    LAPACK's dense solve) or as many whole-body modes (SEED_BLOCK: ARPACK, k close to m)
    the basis spans the whole space, so its static compliance f.u equals full FE's.
    Tolerances: round-off of a complete dense eigenbasis (measured 2.6e-14, 7.7e-14), and
    1e-6 for ARPACK's near-complete one (measured 9.6e-14 at 1-1, 1.1e-8 at 2-2: its last
    eigenvectors are less accurate). With fewer modes neither does (37 modes: 60 % and 9 %
    off on the 50 mm tiny rod)."""
    import dataclasses

    from flexmvm.materials import ALUMINIUM
    from flexmvm.mesh.rod import rod_mesh

    spec = load_scenario(ROOT / "tests" / "data" / "tiny_impact.toml").body("b2").rod.spec()
    rod = rod_mesh(dataclasses.replace(spec, length_m=0.006))
    fe = assemble(rod.mesh, ALUMINIUM)
    ref = rod_reference(rod)
    nodes = rod.selection(*sel)
    b = (3 * nodes[:, None] + np.arange(3)).ravel()
    n_i = fe.n_dof - len(ref.fixed_dofs) - b.size
    f = np.zeros(fe.n_dof)
    f[b] = np.random.default_rng(0).standard_normal(b.size)
    full = _compliance(fe, build_basis(fe, BasisKind.FULL, ref).psi, f)
    reduced = _compliance(fe, build_basis(fe, kind, ref, retained_nodes=nodes, n_modes=n_i).psi, f)
    assert reduced == pytest.approx(full, rel=rtol)
