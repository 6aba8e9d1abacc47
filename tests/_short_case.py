"""The short seed case (scenarios/rod_impact_short.toml: b1 full FE, b2 Craig-Bampton 1-3 + 37,
0.25 ms) run once per test process for each scheme and step, with what the tests that look
inside the step record of it: test_contact_ringing, test_contact_convergence, test_contact_law
and test_validation_live measure the same runs (each run costs seconds: share, do not repeat).

Schemes: "scenario" (as shipped: theta = 1/2 + h / (4 tau), position law, massless contact
nodes), "midpoint" (the same at theta = 1/2) and "damped" (studies.grid.seed_scheme for b2:
velocity law, contact nodes with mass, theta = 0.55)."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from _recording import simulate_recording

from flexmvm.assembly.build import build_scenario
from flexmvm.contact.nodes import ContactNodes
from flexmvm.runs.run import ScenarioRun, summarize
from flexmvm.scenarios import load_scenario
from flexmvm.studies.grid import seed_scheme

SHORT = Path(__file__).parents[1] / "scenarios" / "rod_impact_short.toml"


@dataclass(frozen=True)
class SlaveNodeTrace:
    """Per accepted step: the x positions and x velocities [m, m/s] of the slave (b2 face)
    nodes that carried an impulse at some step (columns in node order), the contact force
    (normal impulse / h) [N] and the step h [s]."""

    x: np.ndarray
    v: np.ndarray
    force: np.ndarray
    h: np.ndarray


def scenario(scheme: str = "scenario", dt_s: float | None = None):
    """rod_impact_short.toml on ``scheme``, at the step dt_s [s] (the file's 0.5 us if None)."""
    sc = load_scenario(SHORT)
    if dt_s is not None:
        sc = sc.with_time(dt_s=dt_s)
    if scheme == "midpoint":
        sc = sc.with_time(theta=0.5)
    elif scheme == "damped":
        sc = seed_scheme(sc, "b2")
    elif scheme != "scenario":
        raise ValueError(f"scheme {scheme!r}: expected scenario, midpoint or damped")
    return sc


@functools.cache
def short_run(
    scheme: str = "scenario", dt_s: float | None = None
) -> tuple[ScenarioRun, SlaveNodeTrace]:
    """The run (as run_scenario returns it, without its guard and energy warnings, which no
    reader of these runs checks) and its slave-node trace, once per process."""
    built = build_scenario(scenario(scheme, dt_s))
    prov = built.system.contacts[0]
    nodes = ContactNodes(built.system.bodies[prov.slave], prov.slave_nodes)
    x, v, force, hs, touched = [], [], [], [], set()

    def record(t, states, h, res):
        nodes.update(res.states[prov.slave])
        x.append(nodes.x[:, 0].copy())
        v.append(nodes.xd[:, 0].copy())
        lam = res.contact_impulses
        force.append(float(res.contact.normal_impulse(lam)) / h)
        hs.append(h)
        last = prov._last[0]  # (slave index, master facet nodes, weights, normal)
        if last is not None and lam.size:
            touched.update(int(p) for p in last[0][np.nonzero(lam[: len(last[0])] > 0)[0]])

    res = simulate_recording(built, record)
    cols = sorted(touched)
    trace = SlaveNodeTrace(
        np.array(x)[:, cols], np.array(v)[:, cols], np.array(force), np.array(hs)
    )
    return ScenarioRun("run", built, res, summarize(res, built)), trace
