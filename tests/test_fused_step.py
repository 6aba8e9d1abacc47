"""The fused step (issue 49 item 3): a body's Moreau-Jean residual in one compiled call per
Newton iterate (integrate.moreau_jean.fused_newton) against the reference path of moreau_jean._residual.

The same arithmetic in the same order, so every comparison is bit for bit (tolerance 0): the
residual, its momentum scale, the midpoint and end configurations, the carried midpoint terms
a step advances with, and whole runs (contact force, energy, probe velocities).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm.assembly.build import build_scenario
from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.rotation import expm_so3
from flexmvm.errors import SolverError
from flexmvm.integrate.driver import simulate
from flexmvm.integrate.moreau_jean import MoreauJeanIntegrator, fused_newton
from flexmvm.integrate.state import BodyState
from flexmvm.integrate.system import System
from flexmvm.scenarios import load_scenario

DATA = Path(__file__).parent / "data"


def _body(rng, nq: int) -> FlexibleBody:
    """A free body of 12 nodes with nq random dense modes (nq = 0: rigid)."""
    n = 12
    X = rng.standard_normal((n, 3)) * [0.03, 0.01, 0.02]
    psi = rng.standard_normal((3 * n, nq)) * 1e-2
    a = rng.standard_normal((nq, nq))
    return FlexibleBody.build(
        "b", X, sp.diags(rng.uniform(0.1, 1.0, n)), psi, a @ a.T + nq * np.eye(nq) * 1e3
    )


def _both(integ, b, st, vp, h, th, applied):
    """(fused, reference) results of _residual, with the carried midpoint terms each left."""
    out = []
    for fused in (True, False):
        integ.fused[b] = fused
        R, mid, end, scale = integ._residual(b, 0.0, st, vp, h, th, applied)
        terms = integ.carried_state._midpoint[b]
        out.append((R, mid, end, scale, terms))
    return out


@pytest.mark.parametrize("nq", [0, 7])
def test_fused_residual_equals_the_reference_bit_for_bit(nq):
    """A spinning body under gravity and a point load, dq_dot = 0 (a step's first iterate)
    and dq_dot != 0: R, scale, both configurations and the carried terms identical."""
    rng = np.random.default_rng(11 + nq)
    body = _body(rng, nq)
    integ = MoreauJeanIntegrator(System((body,), gravity=np.array([0.0, -9.81, 1.0])))
    assert integ.fused == [True]
    st = BodyState(
        rng.standard_normal(3),
        expm_so3(rng.standard_normal(3)),
        rng.standard_normal(nq) * 1e-3,
        rng.standard_normal(6 + nq) * 30,
    )
    h, th = 1e-4, 0.55
    applied = rng.standard_normal(6 + nq)
    for vp in (
        st.v + np.r_[rng.standard_normal(6), np.zeros(nq)],
        st.v + rng.standard_normal(6 + nq),
    ):
        (Rf, mf, ef, sf, tf), (Rr, mr, er, sr, tr) = _both(integ, 0, st, vp, h, th, applied)
        assert np.array_equal(Rf, Rr) and sf == sr
        for a, b in ((mf, mr), (ef, er)):
            for name in ("r", "A", "q", "v"):
                assert np.array_equal(getattr(a, name), getattr(b, name)), name
        if nq:
            for name in ("L_dqd", "L_qd_mid", "K_dqd", "K_qd_mid", "M_dqd"):
                x, y = getattr(tf, name), getattr(tr, name)
                assert (x is None) == (y is None) and (x is None or np.array_equal(x, y)), name


def test_fused_residual_raises_as_the_reference_on_an_overflowed_spin():
    """A non-finite angular velocity: expm_so3's SolverError, the same message."""
    rng = np.random.default_rng(3)
    integ = MoreauJeanIntegrator(System((_body(rng, 4),)))
    v = np.zeros(10)
    v[4] = np.inf
    st = BodyState(np.zeros(3), np.eye(3), np.zeros(4), v)
    with pytest.raises(SolverError, match="not finite"):
        integ._residual(0, 0.0, st, v.copy(), 1e-4, 0.5)


def _tiny(tmp: Path, model: str):
    return build_scenario(
        load_scenario(DATA / "tiny_impact.toml").with_overrides(model=model, t_end_s=10e-6)
    )


@pytest.mark.parametrize("model", ["mvm"])
def test_run_with_the_fused_residual_equals_the_reference_run(model, tmp_path, monkeypatch):
    """The tiny seed case, both rods reduced, through contact: the run with the fused
    residual and the run with the reference path give the same contact force, energy and
    probe velocities, bit for bit."""
    calls = []
    fused = fused_newton.fused_residual
    monkeypatch.setattr(fused_newton, "fused_residual", lambda *a: calls.append(a[1]) or fused(*a))
    built = _tiny(tmp_path, model)
    fast = simulate(built.system, built.states, built.grid, built.probes)
    assert fast.n_steps >= 20 and fast.contact_force.max() > 0.0
    assert set(calls) == {0, 1}  # both rods took the fused residual
    monkeypatch.setattr(fused_newton, "applies", lambda integ, b: False)
    built = _tiny(tmp_path, model)
    ref = simulate(built.system, built.states, built.grid, built.probes)
    assert np.array_equal(fast.contact_force, ref.contact_force)
    assert np.array_equal(fast.total_energy, ref.total_energy)
    assert np.array_equal(fast.probe_v, ref.probe_v)


def test_node_velocities_without_np_cross_equal_it_bit_for_bit(monkeypatch):
    """The recorder's probe velocities (FlexibleBody.node_velocities) take w x s from
    rotation.cross_rows, not np.cross (~30 us of axis handling a call, twice per output):
    the same products and differences, so np.cross's values bit for bit."""
    from flexmvm.bodies.rotation import cross_rows

    rng = np.random.default_rng(7)
    body = _body(rng, 5)
    nodes = np.array([0, 3, 7])
    A = expm_so3(rng.standard_normal(3))
    q, v = rng.standard_normal(5) * 1e-3, rng.standard_normal(11) * 20
    s = body.X[nodes] + body.local_displacements(nodes, q)
    ref = v[:3] + (np.cross(v[3:6], s) + body.local_displacements(nodes, v[6:])) @ A.T
    for _ in range(200):
        w, x = rng.standard_normal(3) * 50, rng.standard_normal((4, 3))
        assert np.array_equal(cross_rows(w, x), np.cross(w, x))

    def refused(*args, **kwargs):
        raise AssertionError("np.cross called")

    monkeypatch.setattr(np, "cross", refused)
    assert np.array_equal(body.node_velocities(nodes, A, q, v), ref)
