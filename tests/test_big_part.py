"""A small version of scenarios/plate_impact.toml (a clamped plate struck by a rigid ball,
the plate kind mvm-sparse): what the warm run (setup cache filled) holds. It reads the ring
body's parts and the truncation guard back (no exterior rows of psi gathered, no K_EE
factored), keeps psi's exterior rows on disk (memory-mapped: a run makes resident only the
rows it reads), and gives the cold run's body and contact force exactly."""

from __future__ import annotations

import mmap
import shutil
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

pytest.importorskip("gmsh")

import flexmvm as fm
from flexmvm.assembly import build_cache as scenario_setup
from flexmvm.assembly.build import build_scenario
from flexmvm.assembly.build_cache import SetupCache
from flexmvm.bodies import ring_body
from flexmvm.integrate.driver import simulate

ROOT = Path(__file__).resolve().parents[1]

SCENARIO = """name = "small_plate"
gravity_mps2 = [0.0, 0.0, 0.0]
[time]
t_end_s = 4.0e-6
dt_s = 0.5e-6
dt_max_s = 0.5e-6
output_dt_s = 0.5e-6
[[bodies]]
name = "ball"
material = { name = "steel", E_pa = 210.0e9, nu = 0.3, rho_kg_m3 = 7850.0 }
mesh_file = "sphere_r5.msh"
[bodies.model]
kind = "rigid"
[bodies.placement]
position_m = [0.0, 0.0, 0.005]
velocity_mps = [0.0, 0.0, -1.0]
[[bodies]]
name = "plate"
material = "aluminium"
mesh_file = "plate.msh"
[bodies.model]
kind = "mvm-sparse"
region = { ball = { centre_m = [0.0, 0.0, 0.0], radius_m = 1.0e-3 } }
modes = 8
[[supports]]
type = "clamp"
body = "plate"
node_set = "side"
[[contacts]]
slave = "plate.top"
master = "ball.front"
law = "position"
"""


@pytest.fixture(scope="module")
def scenario(tmp_path_factory):
    from flexmvm.mesh.gmsh_session import Refinement
    from flexmvm.mesh.parts import block

    d = tmp_path_factory.mktemp("plate")
    refine = Refinement((0.0, 0.0, 0.0), 0.5e-3, 1.0e-3, 3.0e-3)
    block(d / "plate.msh", 0.020, 0.020, 0.002, 2.5e-3, order=1, refine=refine)
    shutil.copy(ROOT / "scenarios" / "meshes" / "sphere_r5.msh", d / "sphere_r5.msh")
    (d / "plate.toml").write_text(SCENARIO)
    return fm.load_scenario(d / "plate.toml")


def _mapped(a) -> bool:
    """Whether array ``a`` is a view of a memory map (a file's pages, not the process's)."""
    while a is not None:
        if isinstance(a, np.memmap | mmap.mmap):
            return True
        a = getattr(a, "base", None)
    return False


def _run(sc):
    built = build_scenario(sc, SetupCache())  # a new process's caches: only the disk's
    res = simulate(built.system, built.states, built.grid, built.probes)
    return built.system.bodies[1], np.asarray(res.contact_force)


def _refuse(what):
    def refuse(*args, **kwargs):
        raise AssertionError(f"the warm run computed {what}")

    return refuse


@pytest.fixture(scope="module")
def runs(scenario, tmp_path_factory):
    """(cold body, its force, warm body, its force): the scenario run on an empty setup
    cache, then again on the cache the first run filled, where it must compute neither psi's
    corner rows, nor the ring parts, nor the truncation guard (which factors K_EE)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("FLEXMVM_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))
        mp.delenv("FLEXMVM_NO_CACHE", raising=False)
        cold, f_cold = _run(scenario)
        mp.setattr(ring_body, "split_ring_psi", _refuse("psi's corner rows"))
        mp.setattr(ring_body, "ring_parts", _refuse("the ring parts"))
        mp.setattr(scenario_setup, "modal_residual", _refuse("the truncation guard"))
        warm, f_warm = _run(scenario)
    return cold, f_cold, warm, f_warm


def test_warm_run_reads_its_parts_and_maps_psi(runs):
    cold, f_cold, warm, f_warm = runs
    assert isinstance(cold, ring_body.RingBody) and cold.corner.size < cold.nq
    # psi: its entries on disk (the data and column indices of every row), equal to cold's
    assert sp.issparse(warm.psi)
    assert _mapped(warm.psi.data) and _mapped(warm.psi.indices)
    assert not _mapped(cold.psi.data)
    assert (warm.psi != cold.psi).nnz == 0
    # the parts read back bit for bit (the same arrays stored), so is the run
    np.testing.assert_array_equal(warm.corner, cold.corner)
    for a in range(3):
        for b in range(3):
            assert (warm.inv.G2[a][b] != cold.inv.G2[a][b]).nnz == 0
            np.testing.assert_array_equal(warm.inv.G1[a][b], cold.inv.G1[a][b])
    assert (warm.k_hat != cold.k_hat).nnz == 0 and (warm.inv.M_qq != cold.inv.M_qq).nnz == 0
    np.testing.assert_array_equal(warm.inv.S1, cold.inv.S1)
    assert f_cold.max() > 1.0  # the ball strikes within the window
    np.testing.assert_array_equal(f_warm, f_cold)


def test_warm_body_holds_no_dense_exterior_rows(runs):
    """No array of the warm body's own memory has a row per exterior DOF: psi's exterior
    rows (n_E x n_c: the dense part of the basis) stay mapped."""
    warm = runs[2]
    n_dof = warm.psi.shape[0]
    held = [warm.X, warm.inv.S1, *(np.asarray(g) for row in warm.inv.G1 for g in row)]
    for m in (warm.k_hat, warm.inv.M_qq, *(g for row in warm.inv.G2 for g in row)):
        held += [m.data, m.indices]
    held += [warm.psi.data, warm.psi.indices]
    resident = [a.size for a in held if not _mapped(a)]
    # the largest resident array: G2's corner blocks (n_c^2) or X (n x 3), far below the
    # n_E x n_c entries of psi's exterior rows (a half: the exterior is most of the DOFs)
    assert max(resident) < 0.5 * n_dof * warm.corner.size
