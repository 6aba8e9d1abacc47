"""Runs through driver.simulate with a hook called after every accepted step (simulate's
on_step): the tests that look inside the step (rows, impulses, node motion) share this one
way of doing it."""

from __future__ import annotations

from collections.abc import Callable

from flexmvm.integrate import driver


def simulate_recording(built, hook: Callable) -> object:
    """driver.simulate of a built scenario, calling hook(t, states, h, result) after each
    accepted step (states: those at t, result: the StepResult)."""
    return driver.simulate(
        built.system,
        built.states,
        built.grid,
        built.probes,
        on_step=lambda step: hook(step.t_s, step.start, step.h_s, step.result),
    )
