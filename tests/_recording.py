"""Runs through driver.simulate with a hook called after every accepted step: the tests that
look inside the step (rows, impulses, node motion) share this one way of doing it."""

from __future__ import annotations

from collections.abc import Callable

from flexmvm.integrate import driver
from flexmvm.integrate.moreau_jean import MoreauJeanIntegrator


def simulate_recording(built, hook: Callable) -> object:
    """driver.simulate of a built scenario, calling hook(t, states, h, result) after each step
    (states: those at t, result: the StepResult); the driver's integrator restored after."""

    class Recording(MoreauJeanIntegrator):
        def step(self, t, states, h):
            res = super().step(t, states, h)
            hook(t, states, h, res)
            return res

    original = driver.MoreauJeanIntegrator
    driver.MoreauJeanIntegrator = Recording
    try:
        return driver.simulate(built.system, built.states, built.grid, built.probes)
    finally:
        driver.MoreauJeanIntegrator = original
