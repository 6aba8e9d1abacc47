"""The contact nodes' step-to-step ringing on the short seed case (issue 14 part 3), measured
as docs/contact_law.md does (benchmarks/contact_law_study.py): over the steps k of the contact
interval and the slave (b2 face) nodes that carried an impulse, the mean of
|u(k+1) - 2 u(k) + u(k-1)| / v0, u a node's x velocity; v_m, the step's mean velocity
(x(k) - x(k-1)) / h, what moves a massless node, and v+, its velocity at the step's end (an
alternation of amplitude a reads 4 a / v0).

Three schemes of the same models (b1 full FE, b2 Craig-Bampton 1-3 + 37), h = 0.5 us:
- the scenario's: theta = 1/2 + h / (4 tau) = 0.51, position law, massless contact nodes;
  measured v_m 0.0229, v+ 0.0231;
- the same at theta = 1/2 (no damping at all): v_m 0.0391, v+ 0.048;
- the damped scheme the seed scenarios ran before (velocity law, contact nodes with mass,
  theta = 0.55: studies.grid.seed_scheme): v_m 0.0237, v+ 0.104.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
from _recording import simulate_recording

from flexmvm.contact.nodes import ContactNodes
from flexmvm.scenarios import load_scenario
from flexmvm.scenarios.build import build_scenario
from flexmvm.studies.grid import seed_scheme

SHORT = Path(__file__).parents[1] / "scenarios" / "rod_impact_short.toml"
V0 = 0.21


@functools.cache
def _ring(scheme: str) -> tuple[float, float, float]:
    """(v_m ring, v+ ring, theta) of the short case on ``scheme``."""
    sc = load_scenario(SHORT)
    if scheme == "midpoint":
        sc = sc.with_time(theta=0.5)
    elif scheme == "damped":
        sc = seed_scheme(sc, "b2")
    built = build_scenario(sc)
    prov = built.system.contacts[0]
    nodes = ContactNodes(built.system.bodies[prov.slave], prov.slave_nodes)
    x, v, force, touched = [], [], [], set()

    def record(t, states, h, res):
        nodes.update(res.states[prov.slave])
        x.append(nodes.x[:, 0].copy())
        v.append(nodes.xd[:, 0].copy())
        lam = res.contact_impulses
        force.append(float(res.contact.normal_impulse(lam)) / h)
        last = prov._last[0]  # (slave index, master facet nodes, weights, normal)
        if last is not None and lam.size:
            touched.update(int(p) for p in last[0][np.nonzero(lam[: len(last[0])] > 0)[0]])

    simulate_recording(built, record)
    h = built.grid.dt_s
    on = np.nonzero(np.array(force) > 0)[0]
    ks = np.arange(max(on[0], 1), on[-1])  # the contact interval's steps, all at dt_s
    cols = sorted(touched)
    X, U = np.array(x)[:, cols], np.array(v)[:, cols]
    Vm = np.vstack([np.full((1, len(cols)), np.nan), np.diff(X, axis=0) / h])

    def ring(W):
        return float(np.nanmean(np.abs(W[ks + 1] - 2 * W[ks] + W[ks - 1])) / V0)

    return ring(Vm), ring(U), built.grid.theta


def test_contact_nodes_ring_no_more_than_on_the_damped_scheme():
    """The scenario's scheme against the damped one: v_m ring within 10 % of it (measured
    0.0229 against 0.0237: the rings are equal to the measure's run-to-run precision) and v+
    ring below half of it (measured 0.0231 against 0.104: the damped scheme's contact nodes
    carry mass and alternate in their end velocity); and the measure sees the ringing the
    scenario's theta removes: at theta = 1/2 v_m rings 1.7 x more (0.0391; required 1.4 x)."""
    vm, vp, theta = _ring("scenario")
    vm_d, vp_d, theta_d = _ring("damped")
    vm_0, _, theta_0 = _ring("midpoint")
    assert (theta, theta_d, theta_0) == (0.51, 0.55, 0.5)
    assert vm <= 1.1 * vm_d and vp <= 0.5 * vp_d, (vm, vm_d, vp, vp_d)
    assert vm_0 >= 1.4 * vm, (vm_0, vm)
