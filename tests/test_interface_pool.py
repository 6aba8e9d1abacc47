"""One mode pool per patch set of an interface grid (reduction/interface.py participation_pool,
studies/interface.py mode_pools, the setup cache's ``freemodes`` / ``patchstatic`` entries).

The cases of a patch set share an explicit ``mode_pool`` (the pool of the grid's largest mode
count), a case rebuilt standalone from its params has the study's basis, a second mode count
of a patch set solves no eigenproblem and factors no K, and the new cache keys follow their
inputs. The rod: tests/data/tiny_impact.toml's b2 (a few thousand DOFs).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import flexmvm as fm
from flexmvm import setup_cache
from flexmvm.assembly import build_cache as scenario_setup
from flexmvm.errors import InputError, StaleDataWarning
from flexmvm.materials import ALUMINIUM, BRASS
from flexmvm.reduction import interface as iface
from flexmvm.reduction.basis import BasisKind
from flexmvm.reduction.interface import InterfaceSpec, participation_pool
from flexmvm.reduction.reference_condition import three_two_one
from flexmvm.studies.interface import interface_cases, mode_pools, run_interface_case

SETUP = scenario_setup.default_setup()  # what fm.clear_caches empties

ROOT = Path(__file__).resolve().parents[1]
TINY = ROOT / "tests" / "data" / "tiny_impact.toml"
MM = 1e-3
PATCHES = [(0.2 * MM,), (0.2 * MM, 0.4 * MM)]
MODES = [0, 1, 3, 6]


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    """A fresh, enabled cache directory and empty per-process caches per test."""
    monkeypatch.setenv(setup_cache.ENV_DIR, str(tmp_path / "cache"))
    monkeypatch.delenv(setup_cache.ENV_OFF, raising=False)
    scenario_setup.clear_caches()
    yield tmp_path / "cache"
    scenario_setup.clear_caches()


@pytest.fixture(scope="module")
def tiny():
    return fm.load_scenario(TINY)


class Counter:
    """Wraps a function of module assembly.build_cache and counts its calls."""

    def __init__(self, fn):
        self.fn, self.calls = fn, 0

    def __call__(self, *args, **kw):
        self.calls += 1
        return self.fn(*args, **kw)


def _counted(monkeypatch, name: str) -> Counter:
    counter = Counter(getattr(scenario_setup, name))
    monkeypatch.setattr(scenario_setup, name, counter)
    return counter


def _args(sc, p: dict) -> tuple:
    """SetupCache.basis's arguments for the interface model of study case params ``p``, as
    run_interface_case builds it (the model written out: patch radii, modes, mode_pool)."""
    from flexmvm.studies.interface import _model

    cfg = sc.with_model("b2", _model(p, "end_b")).body("b2")
    return (
        cfg.rod.spec(),
        cfg.material_obj(),
        BasisKind.INTERFACE,
        (),
        cfg.model.modes,
        cfg.model.reference,
        cfg.model.interface_spec(),
    )


def test_cases_of_a_patch_set_share_the_pool_of_the_largest_count(tiny):
    cases = interface_cases(tiny, "b2", PATCHES, MODES)
    assert len(cases) == len(PATCHES) * len(MODES)
    fe = SETUP.fe_model(tiny.body("b2").rod.spec(), ALUMINIUM)
    for radii in PATCHES:
        own = {
            c.params["modes"]: c.params["mode_pool"]
            for c in cases
            if tuple(c.params["patch_radii_m"]) == radii
        }
        top = participation_pool(fe, InterfaceSpec(radii_m=radii), max(MODES))
        # the default pool of the largest count, grown past 4 m + 6 here (the tiny rod's
        # on-axis load excites few of its lowest modes)
        assert top > 4 * max(MODES) + 6
        assert own == {0: None, 1: top, 3: top, 6: top}
    # the frequency choice keeps its default
    freq = interface_cases(tiny, "b2", PATCHES[:1], [3], mode_choice="frequency")
    assert freq[0].params["mode_pool"] is None


def test_largest_count_is_the_default_model_and_a_case_is_reproducible(tiny, cache, monkeypatch):
    """The largest count's basis with the explicit pool is the default basis bit for bit; a
    smaller count built in the study (pool and statics from the cache) equals the same model
    built alone with no cache at all."""
    cases = {
        (len(c.params["patch_radii_m"]), c.params["modes"]): c
        for c in interface_cases(tiny, "b2", PATCHES, MODES)
    }
    top = cases[(2, 6)].params
    study = SETUP.basis(*_args(tiny, top))
    default = SETUP.basis(*_args(tiny, dict(top, mode_pool=None)))
    assert np.array_equal(study.psi, default.psi)
    small = cases[(2, 3)].params
    in_study = SETUP.basis(*_args(tiny, small))
    scenario_setup.clear_caches()
    monkeypatch.setenv(setup_cache.ENV_OFF, "1")
    alone = SETUP.basis(*_args(tiny, small))
    assert np.array_equal(in_study.psi, alone.psi)
    np.testing.assert_array_equal(in_study.mode_freqs_hz, alone.mode_freqs_hz)
    # the case's model is the standalone scenario's: the written-out model carries the pool
    model = (
        fm.scenario_from_dict(small["scenario"])
        .with_model("b2", fm.interface([0.2 * MM, 0.4 * MM], 3, mode_pool=small["mode_pool"]))
        .body("b2")
    )
    assert model.model.interface_spec() == _args(tiny, small)[-1]


def test_a_second_mode_count_solves_no_eigenproblem(tiny, monkeypatch):
    """Another process (cleared per-process caches) building another mode count of the patch
    set reads the mode pool and the patch statics from the setup cache."""
    cases = {c.params["modes"]: c for c in interface_cases(tiny, "b2", PATCHES[1:], MODES)}
    eig = _counted(monkeypatch, "free_modes")
    statics = _counted(monkeypatch, "relieved_statics")
    SETUP.basis(*_args(tiny, cases[6].params))
    # the pool was solved when the cases were made (interface_mode_pool): not again
    assert eig.calls == 0 and statics.calls == 1
    for m in (1, 3):
        scenario_setup.clear_caches()
        basis = SETUP.basis(*_args(tiny, cases[m].params))
        assert basis.n_modes == m and basis.psi.shape[1] == 2 + m
    assert eig.calls == 0 and statics.calls == 1
    # a pool of another size is a miss: the counters can fail
    scenario_setup.clear_caches()
    SETUP.basis(*_args(tiny, dict(cases[3].params, mode_pool=cases[3].params["mode_pool"] + 1)))
    assert eig.calls == 1 and statics.calls == 1


def test_run_interface_case_records_the_pool(tiny, tmp_path):
    from flexmvm.studies.reference_run import reference_history

    sc = tiny.with_time(t_end_s=5e-6)
    hist, _ = reference_history(sc, "b2", tmp_path)
    (case,) = [
        c
        for c in interface_cases(sc, "b2", PATCHES[:1], [1, 3], reference=hist)
        if c.params["modes"] == 1
    ]
    row = run_interface_case(case, reference=hist)
    assert row["mode_pool"] == case.params["mode_pool"] > 3 and "failed" not in row


def test_too_small_a_pool_is_one_line_and_the_grid_falls_back(tiny, monkeypatch):
    fe = SETUP.fe_model(tiny.body("b2").rod.spec(), ALUMINIUM)
    spec = InterfaceSpec(radii_m=(0.2 * MM,), pool=10)
    with pytest.raises(InputError, match="or a larger mode_pool") as err:
        participation_pool(fe, spec, 10)
    assert "\n" not in str(err.value)
    with pytest.raises(InputError, match="participation"):
        participation_pool(fe, InterfaceSpec(mode_choice=iface.ModeChoice.FREQUENCY), 3)
    # a largest count no pool within MAX_POOL can hold: the smaller counts share the pool of
    # the largest one that fits, the others keep their default (their runs fail alone)
    cfg = tiny.body("b2")
    ok = participation_pool(fe, InterfaceSpec(radii_m=(0.2 * MM,)), 3)
    monkeypatch.setattr(iface, "MAX_POOL", ok)
    pools = mode_pools(cfg, (0.2 * MM,), [1, 3, 40])
    assert pools == {1: ok, 3: ok, 40: None}


def test_pool_and_statics_keys_follow_their_inputs_not_the_mode_count(tiny):
    spec = tiny.body("b2").rod.spec()
    src = setup_cache.rod_source(spec)
    other = setup_cache.rod_source(tiny.body("b1").rod.spec())
    keys = {
        setup_cache.free_modes_key(s, m, k)
        for s in (src, other)
        for m in (ALUMINIUM, BRASS)
        for k in (30, 60)
    }
    assert len(keys) == 8 and all(k.startswith("freemodes-") for k in keys)
    assert setup_cache.free_modes_key(src, ALUMINIUM, 30, version="0" * 16) not in keys
    mesh = SETUP.rod_mesh(spec).mesh
    ref_b = SETUP.reference_condition(spec, mesh, "end_b")
    ref_3 = three_two_one(mesh, mesh.node_set("end_a"))
    base = {
        "source": src,
        "material": ALUMINIUM,
        "reference_set": "end_b",
        "reference": ref_b,
        "surface": "end_a",
        "node": 0,
        "radii_m": (0.2 * MM,),
    }
    variants = [
        {},
        {"source": other},
        {"material": BRASS},
        {"reference_set": "end_a", "reference": ref_3},
        {"surface": "end_b"},
        {"node": 1},
        {"radii_m": (0.3 * MM,)},
        {"radii_m": (0.2 * MM, 0.4 * MM)},
    ]
    keys = {setup_cache.patch_statics_key(**(base | v)) for v in variants}
    assert len(keys) == len(variants) and all(k.startswith("patchstatic-") for k in keys)
    # a malformed entry is a miss, rebuilt
    key = setup_cache.free_modes_key(src, ALUMINIUM, 7)
    setup_cache.save(key, {"freqs_hz": np.zeros(7), "modes": np.zeros((5, 7))})
    calls = []
    with pytest.warns(StaleDataWarning, match=rf"setup cache {key}\.npz: malformed .*rebuilt"):
        _f, m = setup_cache.cached_free_modes(
            src, ALUMINIUM, 7, 6, lambda: calls.append(1) or (np.ones(7), np.ones((6, 7)))
        )
    assert calls == [1] and m.shape == (6, 7)
    _f, m = setup_cache.cached_free_modes(src, ALUMINIUM, 7, 6, lambda: calls.append(1))
    assert calls == [1] and np.array_equal(m, np.ones((6, 7)))
