"""The step's compiled path against its reference path (issue 49 item 3).

The Newton step of reduced bodies factors and solves small dense matrices (the 6 x 6 frame Schur
complements, the contact and massless-node Delassus blocks) and multiplies with the massless
coordinates' rows of k_hat on every step. Those go straight to LAPACK
(integrate.moreau_jean.dense_solve) and to compiled CSR/CSC products
(integrate.moreau_jean.massless) instead of scipy's wrappers, in the same arithmetic: the results
must be the reference path's bit for bit (tolerance 0), and a step must not go through
scipy.linalg's factor/solve wrappers at all (only the factorization of W per step size, once, may).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from flexmvm.assembly.build import build_scenario
from flexmvm.integrate.driver import simulate
from flexmvm.integrate.moreau_jean import dense_solve
from flexmvm.integrate.moreau_jean.massless import MasslessCoordinates, csr_times
from flexmvm.scenarios import load_scenario

DATA = Path(__file__).parent / "data"
WRAPPERS = ("cho_factor", "cho_solve", "lu_factor", "lu_solve")


def _spd(n: int, seed: int) -> np.ndarray:
    a = np.random.default_rng(seed).standard_normal((n, n))
    return a @ a.T + n * np.eye(n)


@pytest.mark.parametrize("n", [6, 40])
def test_factors_and_solves_equal_scipy_bit_for_bit(n):
    """cho_factor (both triangles), lu_factor and their solves give scipy's arrays exactly."""
    a = _spd(n, n)
    b = np.random.default_rng(1).standard_normal((n, 3))
    for lower in (False, True):
        c, low = dense_solve.cho_factor(a, lower=lower)
        c_ref, low_ref = sla.cho_factor(a, lower=lower)
        assert low == low_ref and np.array_equal(c, c_ref)
        assert np.array_equal(dense_solve.cho_solve((c, low), b), sla.cho_solve((c, low), b))
    g = a + np.random.default_rng(2).standard_normal((n, n))  # not symmetric
    lu, piv = dense_solve.lu_factor(g)
    lu_ref, piv_ref = sla.lu_factor(g)
    assert np.array_equal(lu, lu_ref) and np.array_equal(piv, piv_ref)
    assert np.array_equal(
        dense_solve.lu_solve((lu, piv), b[:, 0]), sla.lu_solve((lu, piv), b[:, 0])
    )


def test_factor_errors_as_scipy():
    """Not positive definite: LinAlgError; a NaN: ValueError (what the callers catch)."""
    with pytest.raises(np.linalg.LinAlgError):
        dense_solve.cho_factor(-np.eye(3))
    with pytest.raises(ValueError):
        dense_solve.lu_factor(np.full((3, 3), np.nan))


def test_massless_products_equal_scipy_bit_for_bit():
    """K_s q and K_cols dq of the massless coordinates: scipy's CSR/CSC products exactly."""
    rng = np.random.default_rng(3)
    k = sp.random(50, 50, density=0.3, random_state=4, format="csr")
    k = (k + k.T + 50 * sp.eye(50)).tocsr()
    s = np.array([3, 7, 20])
    ml = MasslessCoordinates(s, k[s], sp.csc_matrix(k[s].T), None)
    q, dq = rng.standard_normal(50), rng.standard_normal(3)
    assert np.array_equal(csr_times(ml.K_s, q), ml.K_s @ q)
    assert np.array_equal(ml.k_times(dq), ml.K_cols @ dq)


def _built(tmp: Path):
    """The tiny seed case, both rods reduced, under the seed's position law with the contact
    nodes' mass redistributed (massless retained nodes, as scenarios/rod_impact.toml)."""
    text = (DATA / "tiny_impact.toml").read_text()
    text = text.replace(
        'kind = "frictionless"\n',
        'kind = "frictionless"\nlaw = "position"\nredistribute_mass = true\n',
    )
    path = tmp / "tiny_position.toml"
    path.write_text(text)
    return build_scenario(load_scenario(path).with_overrides(model="mvm", t_end_s=10e-6))


def _counting(monkeypatch) -> dict:
    """Count the calls of scipy.linalg's factor/solve wrappers from here on."""
    calls = dict.fromkeys(WRAPPERS, 0)
    for name in WRAPPERS:
        orig = getattr(sla, name)

        def counted(*args, _orig=orig, _name=name, **kwargs):
            calls[_name] += 1
            return _orig(*args, **kwargs)

        monkeypatch.setattr(sla, name, counted)
    return calls


def test_reduced_step_makes_no_scipy_wrapper_call_and_equals_the_reference(monkeypatch, tmp_path):
    """The tiny seed case, both rods reduced (massless retained nodes, contact from t = 0),
    40 steps: no scipy.linalg factor/solve wrapper call beyond the factorizations made once per
    body (W_qq at the one step size, K_ss of the massless nodes); and the contact force, energy and probe velocities are bit for bit
    those of the reference path (dense_solve's functions replaced by scipy's, the compiled
    massless products by scipy's sparse products)."""
    built = _built(tmp_path)
    assert any(MasslessCoordinates.of(b) is not None for b in built.system.bodies)
    calls = _counting(monkeypatch)
    fast = simulate(built.system, built.states, built.grid, built.probes)
    n_bodies = sum(1 for b in built.system.bodies if b.nq)
    assert fast.n_steps >= 40
    # once per body and run: W_qq's factor (one step size) and the massless nodes' K_ss
    assert sum(calls.values()) <= 2 * n_bodies, calls

    from flexmvm.integrate.moreau_jean import body_solver, coulomb, lcp, massless

    for module in (body_solver, coulomb, lcp, massless):
        for name in WRAPPERS:
            if hasattr(module, name):
                monkeypatch.setattr(module, name, getattr(sla, name))
    monkeypatch.setattr(massless, "csr_times", lambda K, x: K @ x)
    monkeypatch.setattr(MasslessCoordinates, "k_times", lambda self, dq: self.K_cols @ dq)
    built = _built(tmp_path)
    ref = simulate(built.system, built.states, built.grid, built.probes)
    assert np.array_equal(fast.contact_force, ref.contact_force)
    assert np.array_equal(fast.total_energy, ref.total_energy)
    assert np.array_equal(fast.probe_v, ref.probe_v)


def test_rigid_residual_in_the_kernel_equals_the_numpy_terms(monkeypatch):
    """A rigid body's momentum residual M(x_m) dv - h F(x_m, v_m) (spinning, under gravity)
    comes from the compiled momentum_terms, no FlexibleBody.mass_times call, and equals the
    numpy terms (inertia_terms, mass_times, velocity_forces, gravity_forces) to 1e-14 of the
    momentum scale: the same sums in another order (measured ~1e-16)."""
    from flexmvm.bodies.body import FlexibleBody
    from flexmvm.bodies.rotation import expm_so3
    from flexmvm.integrate.moreau_jean import MoreauJeanIntegrator
    from flexmvm.integrate.state import BodyState
    from flexmvm.integrate.system import System

    rng = np.random.default_rng(5)
    n = 12
    X = rng.standard_normal((n, 3)) * [0.03, 0.01, 0.02]
    body = FlexibleBody.build(
        "rigid", X, sp.diags(rng.uniform(0.1, 1.0, n)), np.zeros((3 * n, 0)), np.zeros((0, 0))
    )
    g = np.array([0.0, -9.81, 1.0])
    integ = MoreauJeanIntegrator(System((body,), gravity=g))
    st = BodyState(
        rng.standard_normal(3),
        expm_so3(rng.standard_normal(3)),
        np.zeros(0),
        rng.standard_normal(6) * 50,
    )
    vp = st.v + rng.standard_normal(6)
    h, th = 1e-4, 0.55
    vm = th * vp + (1.0 - th) * st.v
    mid = st.advanced(vm, th * h)
    terms = body.inertia_terms(mid.q)
    inertia = body.mass_times(mid.A, mid.q, vp - st.v, terms)
    F = body.velocity_forces(mid.A, mid.q, vm, terms) + body.gravity_forces(
        mid.A, mid.q, g, terms[0]
    )
    momentum = body.mass_times(mid.A, mid.q, vm, terms)
    scale = max(np.abs(inertia).max(), h * np.abs(F).max(), np.abs(momentum).max())

    def refused(*args, **kwargs):
        raise AssertionError("mass_times called in the step")

    monkeypatch.setattr(FlexibleBody, "mass_times", refused)
    R, _, _, sc = integ._residual(0, 0.0, st, vp, h, th)
    assert abs(sc / scale - 1.0) < 1e-14
    assert np.abs(R - (inertia - h * F)).max() <= 1e-14 * scale


def _massless_case(seed: int):
    """Two bodies with dense massless coordinates (random SPD k_hat, the retained s), a
    contact group touching both and a joint group touching body 0 only, some impulses zero,
    and a point load on body 1: the arguments of equilibrate_step_end."""
    from types import SimpleNamespace

    from flexmvm.constraints.rows import Rows

    rng = np.random.default_rng(seed)
    nq = (30, 22)
    massless, states, new_states = [], [], []
    for n in nq:
        a = rng.standard_normal((n, n))
        k = sp.csr_matrix(a @ a.T + n * np.eye(n))
        s = np.sort(rng.choice(n, 7, replace=False))
        K_s = k[s]
        cho = sla.cho_factor(K_s[:, s].toarray())
        ml = MasslessCoordinates(s, K_s, sp.csc_matrix(K_s.T), lambda b, c=cho: sla.cho_solve(c, b))
        ml.cho = cho  # the dense factor (MasslessCoordinates.of)
        massless.append(ml)
        q0, q1 = rng.standard_normal(n), rng.standard_normal(n)
        states.append(SimpleNamespace(q=q0, v=rng.standard_normal(6 + n)))
        new_states.append(SimpleNamespace(q=q1, v=rng.standard_normal(6 + n)))
    contact, joints = Rows(4), Rows(2)
    for b, n in enumerate(nq):
        contact.blocks[b] = (rng.standard_normal((4, 6)), rng.standard_normal((4, n)))
    joints.blocks[0] = (rng.standard_normal((2, 6)), rng.standard_normal((2, nq[0])))
    contact.blocks[1][1][3, massless[1].s] = 0.0  # row 3: no massless column in body 1 ...
    contact.blocks[0][1][3, massless[0].s] = 0.0  # ... nor in body 0: not held
    h = 1e-6  # impulses of forces O(k q), as in a step
    held = [(contact, h * np.array([3.0, 0.0, -12.0, 7.0])), (joints, h * np.array([5.0, -2.0]))]
    f = rng.standard_normal(6 + nq[1])
    load = SimpleNamespace(name="p", forces=lambda bodies, sts, t: {1: f})
    return massless, (load,), states, new_states, held


def test_massless_step_end_compiled_equals_the_reference_path():
    """The massless nodes' equilibrium at a step's end through the compiled kernels
    (integrate.moreau_jean.massless_kernels) equals the numpy/scipy reference path (equilibrate) to
    1e-12 relative: the same sums, the triangular solves and Phi_s^T lambda in another order
    (measured ~1e-15). Ends q and q_dot in place, dq, dq_dot and K_cols dq, K_cols dq_dot."""
    from flexmvm.integrate.moreau_jean import massless as mod

    out = []
    for path in (mod._compiled_step_end, mod._reference_step_end):
        massless, loads, states, new_states, held = _massless_case(8)
        orig = mod._compiled_step_end
        mod._compiled_step_end = path
        try:
            changes = mod.equilibrate_step_end(
                massless, None, loads, 0.0, 1e-6, states, new_states, held
            )
        finally:
            mod._compiled_step_end = orig
        out.append((changes, new_states))
    (fast, fast_states), (ref, ref_states) = out
    assert len(fast) == len(ref) == 2
    for cf, cr in zip(fast, ref):
        assert cf[0] == cr[0]
        for a, b in zip(cf[1:], cr[1:]):
            assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max()
    for sf, sr in zip(fast_states, ref_states):
        assert np.abs(sf.q - sr.q).max() <= 1e-12 * np.abs(sr.q).max()
        assert np.abs(sf.v - sr.v).max() <= 1e-12 * np.abs(sr.v).max()


def test_massless_step_end_of_dense_bodies_makes_no_numpy_solve(monkeypatch):
    """The dense bodies' massless equilibrium goes through the kernels: no K_ss solve through
    MasslessCoordinates.solve, no csr_times, no k_times (the ~60 small calls of 5-30 us a
    step that were 1.4 ms of the seed all-MVM step)."""
    from flexmvm.integrate.moreau_jean import massless as mod

    massless, loads, states, new_states, held = _massless_case(9)

    def refused(*args, **kwargs):
        raise AssertionError("numpy/scipy path called")

    for ml in massless:
        ml.solve = refused
    monkeypatch.setattr(mod, "csr_times", refused)
    monkeypatch.setattr(MasslessCoordinates, "k_times", refused)
    changes = mod.equilibrate_step_end(massless, None, loads, 0.0, 1e-6, states, new_states, held)
    assert [c[0] for c in changes] == [0, 1] and all(len(c) == 5 for c in changes)


def test_increment_norm_kernel_equals_the_numpy_terms():
    """The energy ledger's dv^T M(A, q) dv + dq^T k_hat dq of a dense reduced body in one
    compiled call (bodies.momentum.increment_norm, from the carried L(q)) equals
    FlexibleBody.mass_times and the numpy products to 1e-13 relative: the same sums in
    another order (measured ~1e-16), a spinning body with all of dv's parts nonzero."""
    from flexmvm.bodies.body import FlexibleBody
    from flexmvm.bodies.momentum import increment_norm
    from flexmvm.bodies.rotation import expm_so3

    rng = np.random.default_rng(11)
    n, nq = 15, 6
    X = rng.standard_normal((n, 3)) * [0.03, 0.01, 0.02]
    psi = rng.standard_normal((3 * n, nq)) * 0.1
    k = rng.standard_normal((nq, nq))
    body = FlexibleBody.build(
        "flex", X, sp.diags(rng.uniform(0.1, 1.0, n)), psi, k @ k.T + nq * np.eye(nq)
    )
    A, q = expm_so3(rng.standard_normal(3)), rng.standard_normal(nq) * 1e-3
    dv, dq = rng.standard_normal(6 + nq), rng.standard_normal(nq) * 1e-4
    k_dq = body.k_hat @ dq
    mqq = np.asarray(body.inv.M_qq @ dv[6:]).ravel()
    ref = float(dv @ body.mass_times(A, q, dv)) + float(dq @ k_dq)
    inv = body.inv
    got = increment_norm(
        A, q, body.contractions(q), inv.mass, inv.S0, inv.S1, inv.G0, body.G1_array,
        dv, mqq, dq, k_dq,
    )  # fmt: skip
    assert abs(got - ref) <= 1e-13 * abs(ref)


def test_residual_ends_in_kernels_equal_numpy_bit_for_bit():
    """v_m, dv, F += applied, R = inertia - h F and the momentum scale of a body's residual
    (integrate.moreau_jean.residual_kernels) are numpy's expressions bit for bit (tolerance 0: the
    same elementwise operations in the same order), with and without an applied force, and with a
    NaN the scale is what numpy's path gives."""
    from flexmvm.integrate.moreau_jean.residual_kernels import (
        iterate_velocities,
        residual_and_scale,
    )

    rng = np.random.default_rng(12)
    v, vp = rng.standard_normal(40), rng.standard_normal(40)
    th, h = 0.5 + 1e-3 / 3.0, 0.7e-6
    vm, dv = iterate_velocities(v, vp, th)
    assert np.array_equal(vm, th * vp + (1.0 - th) * v) and np.array_equal(dv, vp - v)
    inertia, F, momentum = (rng.standard_normal(40) * 10.0**k for k in (0, 5, 1))
    for applied in (None, rng.standard_normal(40)):
        F_ref = F + applied if applied is not None else F.copy()
        F_k = F.copy()
        R, scale = residual_and_scale(
            inertia, F_k, momentum, np.zeros(0) if applied is None else applied, h
        )
        ref = max(np.abs(inertia).max(), h * np.abs(F_ref).max(), np.abs(momentum).max())
        assert np.array_equal(F_k, F_ref) and np.array_equal(R, inertia - h * F_ref)
        assert scale == ref
    for arr in (momentum, inertia):  # a NaN: Python's max over numpy's three maxima
        arr[3] = np.nan
        ref = max(np.abs(inertia).max(), h * np.abs(F).max(), np.abs(momentum).max())
        got = residual_and_scale(inertia, F.copy(), momentum, np.zeros(0), h)[1]
        assert got == ref or (np.isnan(got) and np.isnan(ref))
