"""A moving region's run reports the work of all its integrators (issue 53): at a window
switch the driver makes a new integrator for the new system (integrate/driver.py, _rebound);
summary.json's ``n_factorizations`` counted only the last one's, so a run with switches said it
factored its iteration matrix once or twice where every window had its own."""

from __future__ import annotations

from test_moving_region import _scenario

import flexmvm as fm


def test_factorizations_of_every_window_are_counted():
    """1 ms of the shipped moving load (60 m/s, spacing 12.5 mm: 4 switches in 20 steps): each
    window that takes a step factors its W once, so the run's count is at least the number of
    switches (the last switch may fall on the last step: measured 4, one a window); the last
    window's integrator alone had 0."""
    run = fm.run(_scenario(1e-3, "mvm-moving"))
    n_switches = len(run.built.switches.switches)
    assert n_switches >= 3
    assert run.summary["n_factorizations"] >= n_switches
    assert run.result.n_factorizations == run.summary["n_factorizations"]
