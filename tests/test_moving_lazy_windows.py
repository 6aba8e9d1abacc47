"""A moving region read from the setup cache makes a window's basis when the contact first
reaches it, not every window at the set-up (assembly/moving_region.py; the cam follower's
contact visits 14 of its 24 windows in a revolution). A run that makes them all (the entry
absent) and one that makes them as visited give the same history bit for bit: the same basis
from the same stored columns, in the same order of operations."""

from __future__ import annotations

import numpy as np
from test_moving_region import _scenario

import flexmvm as fm


def _run(tmp, monkeypatch):
    monkeypatch.setenv("FLEXMVM_CACHE_DIR", str(tmp))
    return fm.run(_scenario(1e-3, "mvm-moving"))


def test_a_warm_run_makes_only_the_windows_it_visits(tmp_path, monkeypatch):
    """1 ms of the shipped moving load (60 m/s: 4 switches in 20 steps) on an empty setup
    cache, then again on the entry it stored."""
    cold = _run(tmp_path, monkeypatch)
    warm = _run(tmp_path, monkeypatch)
    c, w = cold.built.switches, warm.built.switches
    n_windows = len(c.windows.centres)
    visited = {c.window} | {s.old for s in c.switches} | {s.new for s in c.switches}
    assert len(c._bodies) == n_windows > len(visited)  # made at the cold set-up: all
    assert set(w._bodies) == visited  # warm: the ones the contact reached (failed before)
    assert w.parts_remade == 0  # every basis made again has its stored parts' signature
    assert [(s.old, s.new) for s in w.switches] == [(s.old, s.new) for s in c.switches]
    assert np.array_equal(warm.result.contact_force, cold.result.contact_force)
    assert np.array_equal(warm.result.probe_v, cold.result.probe_v)


def test_a_window_made_otherwise_has_its_parts_made_again(tmp_path, monkeypatch):
    """A window whose basis, made again on a warm run, is not the one its stored parts came
    from (here: eigh returning its first held-mode vector with the other sign, as a threaded
    product once did) has its parts made again from the new basis, not the stored ones used
    with it: the stored M_qq's coupling of that column with the window's nodes would have the
    wrong sign."""
    import scipy.linalg as sla
    from test_moving_region_tools import _moving_load

    import flexmvm.reduction.kinds.mvm_moving as kind
    from flexmvm.assembly.build_cache import default_setup
    from flexmvm.assembly.moving_region import moving_body
    from flexmvm.bodies.invariants import inertia_invariants

    monkeypatch.setenv("FLEXMVM_CACHE_DIR", str(tmp_path))
    sc, setup = _moving_load(half_width_m=0.025), default_setup()
    cold = moving_body(sc.bodies[0], sc.supports, setup, 0)[1]
    eigh = sla.eigh

    def flipped(*args, **kwargs):
        lam, vec = eigh(*args, **kwargs)
        vec[:, 0] *= -1.0
        return lam, vec

    monkeypatch.setattr(kind.sla, "eigh", flipped)
    warm = moving_body(sc.bodies[0], sc.supports, setup, 0)[1]
    k = 5  # not the first window (made at the set-up)
    warm.body(k)
    assert warm.parts_remade == 2  # the first window and this one
    psi = warm.windows.basis(k).psi
    n_b = psi.shape[1] - warm.windows.factor.phi.shape[1]
    assert np.array_equal(psi[:, n_b], -cold.windows.basis(k).psi[:, n_b])
    fe = warm.windows.factor.fe
    made = inertia_invariants(fe.mesh.nodes, fe.M_scalar, psi).M_qq
    assert np.allclose(warm.parts[k].inv.M_qq, made, rtol=0, atol=1e-12 * np.abs(made).max())
    assert not np.allclose(cold.parts[k].inv.M_qq, made, rtol=0, atol=1e-6 * np.abs(made).max())
