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
    assert [(s.old, s.new) for s in w.switches] == [(s.old, s.new) for s in c.switches]
    assert np.array_equal(warm.result.contact_force, cold.result.contact_force)
    assert np.array_equal(warm.result.probe_v, cold.result.probe_v)
