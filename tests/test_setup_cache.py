"""Disk cache of setup results (flexmvm.setup_cache): hits (FE models, bases, body parts) equal
fresh builds, keys follow every input, bad entries are rebuilt, `cache clear`/`info` and
FLEXMVM_NO_CACHE work, a warm scenario build computes nothing."""

from __future__ import annotations

import dataclasses
import os
import re
import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm import setup_cache
from flexmvm.assembly import build_cache as scenario_setup
from flexmvm.assembly.build_cache import SetupCache
from flexmvm.bodies.build import body_from_fe, body_from_parts, body_parts
from flexmvm.errors import StaleDataWarning
from flexmvm.fe.assembly import assemble
from flexmvm.materials import ALUMINIUM, Material
from flexmvm.mesh.rod import RodSpec, rod_mesh
from flexmvm.reduction.basis import BasisKind, build_basis
from flexmvm.reduction.reference_condition import three_two_one
from flexmvm.reduction.rod_reference import rod_reference

SPEC = RodSpec(length_m=0.04, radius_m=0.005, n_rings=2, first_element_m=1e-3, max_element_m=0.01)
SOURCE = setup_cache.rod_source(SPEC)


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    """A fresh, enabled cache directory per test."""
    monkeypatch.setenv(setup_cache.ENV_DIR, str(tmp_path / "cache"))
    monkeypatch.delenv(setup_cache.ENV_OFF, raising=False)
    return tmp_path / "cache"


@pytest.fixture(scope="module")
def rod():
    return rod_mesh(SPEC)


@pytest.fixture(scope="module")
def fe(rod):
    return assemble(rod.mesh, ALUMINIUM)


class Counter:
    """A builder that counts its calls."""

    def __init__(self, build):
        self.build, self.calls = build, 0

    def __call__(self, *args):
        self.calls += 1
        return self.build(*args)


def _same_csr(a, b) -> bool:
    a, b = sp.csr_matrix(a), sp.csr_matrix(b)
    return (
        a.shape == b.shape
        and np.array_equal(a.data, b.data)
        and np.array_equal(a.indices, b.indices)
        and np.array_equal(a.indptr, b.indptr)
    )


def _cb(fe, rod, n_modes=5, selection=(1, 2)):
    ref = rod_reference(rod)
    nodes = rod.selection(*selection)
    builder = Counter(lambda: build_basis(fe, BasisKind.CRAIG_BAMPTON, ref, nodes, n_modes))
    basis = setup_cache.cached_basis(
        SOURCE, ALUMINIUM, BasisKind.CRAIG_BAMPTON, "end_b", ref, nodes, n_modes, builder
    )
    return basis, builder


def test_fe_hit_equals_fresh_build(rod, fe):
    builder = Counter(assemble)
    first = setup_cache.cached_fe(SOURCE, rod.mesh, ALUMINIUM, builder)
    second = setup_cache.cached_fe(SOURCE, rod.mesh, ALUMINIUM, builder)
    assert builder.calls == 1
    for name in ("M", "K", "M_scalar"):
        assert _same_csr(getattr(second, name), getattr(fe, name))
        assert _same_csr(getattr(first, name), getattr(fe, name))
    assert (second.mass, second.volume) == (fe.mass, fe.volume)
    assert second.mesh is rod.mesh and second.material == ALUMINIUM


def test_basis_hit_equals_fresh_build(rod, fe):
    fresh, builder = _cb(fe, rod)
    hit, again = _cb(fe, rod)
    assert builder.calls == 1 and again.calls == 0
    assert np.array_equal(hit.psi, fresh.psi)
    assert np.array_equal(hit.mode_freqs_hz, fresh.mode_freqs_hz)
    assert np.array_equal(hit.retained_nodes, fresh.retained_nodes)
    assert hit.kind is fresh.kind and hit.n_modes == fresh.n_modes
    assert np.array_equal(hit.reference.fixed_dofs, fresh.reference.fixed_dofs)


def test_full_basis_round_trip(rod, fe):
    ref = rod_reference(rod)
    make = Counter(lambda: build_basis(fe, BasisKind.FULL, ref))
    args = (SOURCE, ALUMINIUM, BasisKind.FULL, "end_b", ref, np.zeros(0, np.int64), 0, make)
    fresh, hit = setup_cache.cached_basis(*args), setup_cache.cached_basis(*args)
    assert make.calls == 1 and sp.issparse(hit.psi) and _same_csr(hit.psi, fresh.psi)
    assert np.array_equal(hit.retained_nodes, fresh.retained_nodes)


def test_key_follows_every_input(rod):
    ref = rod_reference(rod)
    other_ref = three_two_one(rod.mesh, rod.mesh.node_set("end_b"))
    nodes = rod.selection(1, 2)
    base = {
        "source": SOURCE,
        "material": ALUMINIUM,
        "kind": BasisKind.CRAIG_BAMPTON,
        "reference_set": "end_b",
        "reference": ref,
        "retained": nodes,
        "n_modes": 5,
    }
    key = setup_cache.basis_key(**base)
    assert setup_cache.basis_key(**base) == key
    stiffer = Material(ALUMINIUM.E * 1.01, ALUMINIUM.nu, ALUMINIUM.rho)
    longer = setup_cache.rod_source(dataclasses.replace(SPEC, length_m=0.05))
    changes = [
        {"material": stiffer},
        {"retained": rod.selection(1, 1)},
        {"n_modes": 6},
        {"reference_set": "side"},
        {"reference": other_ref},
        {"source": longer},
        {"kind": BasisKind.SEED_BLOCK},
        {"version": "0" * 16},
    ]
    keys = {setup_cache.basis_key(**{**base, **change}) for change in changes}
    assert key not in keys and len(keys) == len(changes)
    renamed = dataclasses.replace(ALUMINIUM, name="another name")
    assert setup_cache.basis_key(**{**base, "material": renamed}) == key
    assert setup_cache.fe_key(SOURCE, stiffer) != setup_cache.fe_key(SOURCE, ALUMINIUM)


def test_code_version_and_file_source(tmp_path):
    version = setup_cache.code_version()
    assert len(version) == 16 and version == setup_cache.code_version()
    assert setup_cache.make_key("fe", {"a": 1}) != setup_cache.make_key("fe", {"a": 1}, "x")
    a, b = tmp_path / "a.msh", tmp_path / "b.msh"
    a.write_bytes(b"mesh one")
    b.write_bytes(b"mesh two")
    assert setup_cache.file_source(a) != setup_cache.file_source(b)
    assert setup_cache.file_source(tmp_path / "missing.msh") is None


def _evicted(entry, why: str) -> str:
    """The pattern of the one line (errors.StaleDataWarning) that says ``entry`` was
    evicted and rebuilt for the reason ``why`` (a regular expression)."""
    return rf"setup cache {re.escape(entry.name)}: {why}: evicted and rebuilt"


@pytest.mark.parametrize("damage", [b"not a zip file", b"PK\x03\x04 truncated", b""])
def test_corrupt_entry_is_rebuilt(rod, fe, cache, damage):
    fresh, _ = _cb(fe, rod)
    (entry,) = cache.glob("basis-*.npz")
    entry.write_bytes(damage)
    with pytest.warns(StaleDataWarning, match=_evicted(entry, r"unreadable \(\w+\)")):
        rebuilt, builder = _cb(fe, rod)
    assert builder.calls == 1 and np.array_equal(rebuilt.psi, fresh.psi)
    hit, again = _cb(fe, rod)
    assert again.calls == 0 and np.array_equal(hit.psi, fresh.psi)


def test_malformed_entry_is_rebuilt(rod, fe, cache):
    fresh, _ = _cb(fe, rod)
    (entry,) = cache.glob("basis-*.npz")
    np.savez(entry, psi=np.zeros(3))
    with pytest.warns(StaleDataWarning, match=_evicted(entry, r"no checksum .*")):
        rebuilt, builder = _cb(fe, rod)
    assert builder.calls == 1 and np.array_equal(rebuilt.psi, fresh.psi)


def _nan_copy(entry, checksum: bool) -> None:
    """Rewrite ``entry`` as a valid .npz with its arrays but every float NaN (with a checksum
    of that content when ``checksum``, as setup_cache.save would write it)."""
    with np.load(entry) as z:
        arrays = {
            k: (np.full_like(z[k], np.nan) if z[k].dtype.kind == "f" else z[k])
            for k in z.files
            if k != "__sha256__"
        }  # setup_cache.CHECKSUM
    if checksum:
        arrays[setup_cache.CHECKSUM] = np.array(setup_cache.checksum(arrays))
    np.savez(entry, **arrays)


@pytest.mark.parametrize("checksum", [False, True])
def test_nan_entry_is_evicted_rebuilt_and_announced(rod, fe, cache, checksum):
    """A valid .npz holding NaN (with or without a matching checksum) fails the entry's
    check: evicted, rebuilt (the fresh basis) and said in one line naming the entry."""
    fresh, _ = _cb(fe, rod)
    (entry,) = cache.glob("basis-*.npz")
    _nan_copy(entry, checksum)
    with pytest.warns(
        StaleDataWarning,
        match=rf"setup cache {entry.name}: holds NaN or inf "
        r"in \w+: evicted and rebuilt",
    ):
        rebuilt, builder = _cb(fe, rod)
    assert builder.calls == 1 and np.array_equal(rebuilt.psi, fresh.psi)
    hit, again = _cb(fe, rod)
    assert again.calls == 0 and np.array_equal(hit.psi, fresh.psi)


def test_edited_entry_fails_its_checksum(rod, fe, cache):
    """One value of a stored basis changed (finite, the file still valid): the checksum
    written with it differs, so it is evicted and rebuilt."""
    fresh, _ = _cb(fe, rod)
    (entry,) = cache.glob("basis-*.npz")
    with np.load(entry) as z:
        arrays = {k: z[k].copy() for k in z.files}
    arrays["psi"].flat[7] += 1e-3
    np.savez(entry, **arrays)
    with pytest.warns(StaleDataWarning, match="content differs from its checksum"):
        rebuilt, builder = _cb(fe, rod)
    assert builder.calls == 1 and np.array_equal(rebuilt.psi, fresh.psi)


def test_run_after_nan_entries_succeeds_and_names_them(cache):
    """Every setup-cache entry of a run rewritten as a valid .npz of NaN: the next process
    (a new SetupCache: empty per-process caches) evicts each, says so, and gives the first run's history
    (before: every later run failed on the iteration matrix, never naming the cache)."""
    from pathlib import Path

    from flexmvm.runs.run import run_scenario
    from flexmvm.scenarios import load_scenario

    sc = load_scenario(Path(__file__).parent / "data" / "tiny_impact.toml").with_overrides(
        t_end_s=2e-6
    )
    first = run_scenario(sc, warn=False, setup=SetupCache()).result
    entries = sorted(cache.glob("*.npz"))
    assert entries
    for entry in entries:
        _nan_copy(entry, checksum=False)
    with pytest.warns(StaleDataWarning) as notes:
        again = run_scenario(sc, warn=False, setup=SetupCache()).result
    named = {
        str(w.message).split(":")[0].removeprefix("setup cache ")
        for w in notes
        if issubclass(w.category, StaleDataWarning)
    }
    assert named and named <= {e.name for e in entries}
    assert np.array_equal(again.contact_force, first.contact_force)


def test_info_and_clear(rod, fe, cache):
    assert setup_cache.info().n_entries == 0
    setup_cache.cached_fe(SOURCE, rod.mesh, ALUMINIUM, assemble)
    _cb(fe, rod)
    found = setup_cache.info()
    assert found.path == cache and found.n_entries == 2 and found.size_mb > 0
    assert setup_cache.clear() == 2
    assert setup_cache.info().n_entries == 0 and list(cache.iterdir()) == []


def test_no_cache_bypasses(rod, fe, cache, monkeypatch):
    monkeypatch.setenv(setup_cache.ENV_OFF, "1")
    assert not setup_cache.enabled()
    _, first = _cb(fe, rod)
    _, second = _cb(fe, rod)
    assert first.calls == 1 and second.calls == 1 and not cache.exists()


def test_unwritable_cache_dir_is_ignored(rod, fe, tmp_path, monkeypatch):
    blocker = tmp_path / "a file"
    blocker.write_text("not a directory")
    monkeypatch.setenv(setup_cache.ENV_DIR, str(blocker / "cache"))
    basis, builder = _cb(fe, rod)
    assert builder.calls == 1 and basis.n_modes == 5


def test_a_full_disk_is_said_in_one_line_and_the_run_goes_on(rod, fe, monkeypatch):
    """An entry that cannot be written for want of space (ENOSPC) is announced in one line
    (the next run would make it again unawares); the run has its basis all the same, and no
    partial entry is left. A read-only directory stays silent (the test above)."""
    import errno

    from flexmvm.setup_cache import store

    def full(*_args, **_kw):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(store.np, "savez", full)
    with pytest.warns(StaleDataWarning, match="no space left") as seen:
        basis, builder = _cb(fe, rod)
    assert builder.calls == 1 and basis.n_modes == 5
    assert all("\n" not in str(w.message) for w in seen)
    assert setup_cache.info().n_entries == 0


def test_scenario_builder_reads_the_disk_cache(cache, monkeypatch):
    """A second process (here: a new SetupCache, empty per-process caches) builds nothing,
    mode floor included."""
    args = (SPEC, ALUMINIUM, BasisKind.CRAIG_BAMPTON, tuple(rod_mesh(SPEC).selection(1, 2)))
    fresh = SetupCache().with_mode_floor(6).basis(*args, 4, "end_b")
    assert setup_cache.info().n_entries == 2

    def refuse(*_args, **_kw):
        raise AssertionError("rebuilt although cached")

    monkeypatch.setattr(scenario_setup, "build_basis", refuse)
    monkeypatch.setattr(scenario_setup, "assemble", refuse)
    hit = SetupCache().with_mode_floor(6).basis(*args, 4, "end_b")
    assert np.array_equal(hit.psi, fresh.psi) and hit.n_modes == 4


def _assert_same_parts(a, b):
    """Body parts equal array by array (bit for bit)."""
    assert a.inv.mass == b.inv.mass and a.inv.nq == b.inv.nq
    for name in ("S0", "S1", "G0", "M_qq"):
        assert np.array_equal(getattr(a.inv, name), getattr(b.inv, name)), name
    for i in range(3):
        for j in range(3):
            assert np.array_equal(a.inv.G1[i][j], b.inv.G1[i][j])
            assert np.array_equal(a.inv.G2[i][j], b.inv.G2[i][j])
    assert np.array_equal(a.k_hat, b.k_hat)


def _cached_parts(basis, rod, fe):
    builder = Counter(lambda: body_parts(fe, basis))
    parts = setup_cache.cached_body(
        SOURCE,
        ALUMINIUM,
        basis.kind,
        "end_b",
        basis.reference,
        basis.retained_nodes,
        basis.n_modes,
        basis.psi.shape[1],
        builder,
    )
    return parts, builder


def test_body_hit_equals_fresh_build(rod, fe, cache):
    basis, _ = _cb(fe, rod)
    first, builder = _cached_parts(basis, rod, fe)
    hit, again = _cached_parts(basis, rod, fe)
    assert builder.calls == 1 and again.calls == 0 and len(list(cache.glob("body-*.npz"))) == 1
    fresh = body_from_fe("b", fe, basis)
    _assert_same_parts(hit, first)
    _assert_same_parts(hit, body_parts(fe, basis))
    body = body_from_parts("b", rod.mesh, basis, hit)
    assert np.array_equal(body.X, fresh.X) and np.array_equal(body.psi, fresh.psi)
    assert body.label == fresh.label and body.nv == fresh.nv and body.mesh is fresh.mesh
    for name in ("S0", "S1", "G0", "M_qq"):
        assert np.array_equal(getattr(body.inv, name), getattr(fresh.inv, name))
    assert np.array_equal(body.k_hat, fresh.k_hat)
    assert np.array_equal(
        body.contractions(np.arange(body.nq) * 1e-6), fresh.contractions(np.arange(body.nq) * 1e-6)
    )


@pytest.mark.parametrize("damage", [b"not a zip file", b""])
def test_corrupt_or_malformed_body_entry_is_rebuilt(rod, fe, cache, damage):
    basis, _ = _cb(fe, rod)
    fresh, _ = _cached_parts(basis, rod, fe)
    (entry,) = cache.glob("body-*.npz")
    entry.write_bytes(damage)
    with pytest.warns(StaleDataWarning, match=_evicted(entry, r"unreadable \(\w+\)")):
        rebuilt, builder = _cached_parts(basis, rod, fe)
    assert builder.calls == 1
    _assert_same_parts(rebuilt, fresh)
    arrays = dict(np.load(entry))
    np.savez(entry, **{**arrays, "G2": arrays["G2"][:, :, :1]})
    with pytest.warns(StaleDataWarning, match=_evicted(entry, ".*")):
        rebuilt, builder = _cached_parts(basis, rod, fe)
    assert builder.calls == 1
    _assert_same_parts(rebuilt, fresh)


def test_body_key_and_full_bodies(rod, fe, cache):
    ref = rod_reference(rod)
    base = (SOURCE, ALUMINIUM, BasisKind.CRAIG_BAMPTON, "end_b", ref, rod.selection(1, 2), 5)
    assert "bodies/invariants.py" in setup_cache.BODY_SOURCES
    assert "bodies/build.py" in setup_cache.BODY_SOURCES
    assert setup_cache.code_version(setup_cache.BODY_SOURCES) != setup_cache.code_version()
    key = setup_cache.body_key(*base)
    assert key.startswith("body-") and key[5:] != setup_cache.basis_key(*base)[6:]
    assert setup_cache.body_key(*base, version="0" * 16) != key
    full = build_basis(fe, BasisKind.FULL, ref)
    builder = Counter(lambda: body_parts(fe, full))
    args = (
        SOURCE,
        ALUMINIUM,
        BasisKind.FULL,
        "end_b",
        ref,
        full.retained_nodes,
        0,
        full.psi.shape[1],
        builder,
    )
    parts = setup_cache.cached_body(*args)
    setup_cache.cached_body(*args)
    assert builder.calls == 2 and sp.issparse(parts.k_hat) and not cache.exists()


def test_warm_scenario_build_computes_nothing(cache, monkeypatch):
    """A second process (a new SetupCache: empty per-process caches) reads bases and body
    parts and neither assembles nor loads an FE model; under a mode floor the parts are cut
    like the basis."""
    nodes = tuple(rod_mesh(SPEC).selection(1, 2))
    args = (SPEC, ALUMINIUM, BasisKind.CRAIG_BAMPTON, nodes)
    cold = SetupCache()
    fresh = cold.body_parts(*args, 6, "end_b")
    floor = cold.with_mode_floor(6)
    cut_basis, cut = floor.basis(*args, 4, "end_b"), floor.body_parts(*args, 4, "end_b")

    def refuse(*_args, **_kw):
        raise AssertionError("computed although cached")

    warm = SetupCache()
    for name in ("build_basis", "assemble", "body_parts"):
        monkeypatch.setattr(scenario_setup, name, refuse)
    monkeypatch.setattr(warm.caches, "fe_model", refuse)
    hit = warm.body_parts(*args, 6, "end_b")
    _assert_same_parts(hit, fresh)
    cut_hit = warm.with_mode_floor(6).body_parts(*args, 4, "end_b")
    _assert_same_parts(cut_hit, cut)
    assert cut.inv.nq == cut_basis.psi.shape[1] == 3 * len(nodes) + 4
    monkeypatch.undo()
    own = body_parts(SetupCache().fe_model(SPEC, ALUMINIUM), cut_basis)
    np.testing.assert_allclose(cut.k_hat, own.k_hat, rtol=1e-12, atol=1e-9 * abs(own.k_hat).max())
    np.testing.assert_allclose(
        cut.inv.M_qq, own.inv.M_qq, rtol=1e-12, atol=1e-12 * abs(own.inv.M_qq).max()
    )


def test_cli_info_and_clear(rod, cache):
    setup_cache.cached_fe(SOURCE, rod.mesh, ALUMINIUM, assemble)
    env = {**os.environ, setup_cache.ENV_DIR: str(cache)}

    def run(*args):
        return subprocess.run(
            [sys.executable, "-m", "flexmvm.cli.main", "cache", *args],
            capture_output=True,
            text=True,
            env=env,
            timeout=120,
            check=True,
        )

    out = run("info").stdout
    assert str(cache) in out and "entries: 1" in out and "MB" in out
    assert "removed 1 entries" in run("clear").stdout
    assert "entries: 0" in run("info").stdout


def test_elimination_order_round_trip(cache):
    """An elimination order is kept under the sparsity pattern alone: the same pattern with
    other values is a hit; a stored "no order" (None) is a hit too; an entry that is not a
    permutation of the right size is rebuilt. (A 10 x 200 grid: a strip, as a rod is.)"""
    from flexmvm.fe.solvers.ordering import dissection_order

    def lap(n):
        return sp.diags([-np.ones(n - 1), 2.0 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1])

    grid = sp.csr_matrix(sp.kron(lap(200), sp.eye(10)) + sp.kron(sp.eye(200), lap(10)))
    builder = Counter(dissection_order)
    first = setup_cache.cached_elimination_order(grid, builder)
    assert builder.calls == 1 and first is not None
    assert np.array_equal(np.sort(first), np.arange(grid.shape[0]))
    again = setup_cache.cached_elimination_order(3.0 * grid + sp.eye(2000), builder)
    assert builder.calls == 1 and np.array_equal(again, first)
    (entry,) = cache.glob("order-*.npz")
    np.savez(entry, order=first[:-1])
    with pytest.warns(StaleDataWarning, match=_evicted(entry, ".*")):
        rebuilt = setup_cache.cached_elimination_order(grid, builder)
    assert builder.calls == 2 and np.array_equal(rebuilt, first)
    none = Counter(lambda a: None)
    small = sp.eye(5, format="csr")
    assert setup_cache.cached_elimination_order(small, none) is None
    assert setup_cache.cached_elimination_order(small, none) is None and none.calls == 1


def test_the_checksum_reads_the_bytes_tobytes_gives():
    """store.checksum hashes an array's bytes in place (no copy of a basis of GBs) to the
    same digest as its C-order tobytes() did, 0-d, strided, Fortran-ordered and text arrays
    included: entries written before stay valid."""
    import hashlib

    from flexmvm.setup_cache import store

    arrays = {
        "a": np.arange(10.0).reshape(2, 5),
        "b": np.array("xyz"),
        "c": np.zeros((0, 3)),
        "d": np.array([True, False]),
        "e": np.asfortranarray(np.arange(6.0).reshape(2, 3)),
        "f": np.array(3.5),
        "g": np.arange(5, dtype=np.int32),
        "h": np.arange(12.0)[::2],
    }
    digest = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        digest.update(f"{name}\0{a.dtype.str}\0{a.shape}\0".encode())
        digest.update(a.tobytes())
    assert store.checksum(arrays) == digest.hexdigest()
