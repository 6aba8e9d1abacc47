"""The consistent tangent in the Newton step of a yielding body
(integrate/moreau_jean/plastic_tangent.py).

- The Woodbury solve on the elastic factor (and the refactored sparse form) equals a direct sparse solve of
  W_t = W_el + c P^T (K_t - K_el) P to round-off (relative 1e-9: the capacitance matrix of a
  yielding block is conditioned like W itself, ~1e4 here, times the 1e-16 of the factor's
  arithmetic leaves 1e-12; 1e-9 keeps three decades of margin), with P a psi that drops
  coordinates (the tangent's coordinate map); the dense (MVM) form by its refactored W_t to
  the same tolerance. A bent hex8 block yielding at its clamped corners: under a second.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from test_fe import box_hex

from flexmvm.fe import assemble
from flexmvm.integrate.moreau_jean import plastic_tangent
from flexmvm.integrate.moreau_jean.plastic_tangent import tangent_solve
from flexmvm.materials import Material
from flexmvm.plasticity.body import PlasticBody
from flexmvm.plasticity.material import J2Plasticity
from flexmvm.plasticity.step_history import StepHistory

STEEL = Material(E=200e9, nu=0.3, rho=7800.0, name="steel")
C_TH2H2 = (0.5 * 2e-6) ** 2  # (theta h)^2 [s^2] of a 2 us step at theta 1/2


class _Solver:
    """What tangent_solve reads of a BodySolver: its body, its elastic W_qq and solves."""

    def __init__(self, psi, k_hat, m_qq):
        dense = not sp.issparse(k_hat)
        self.body = SimpleNamespace(psi=psi, k_hat=k_hat, nq=k_hat.shape[0], name="block")
        self.w_el = m_qq + C_TH2H2 * k_hat
        lu = None if dense else spla.splu(sp.csc_matrix(self.w_el))
        self._solve = (lambda b: np.linalg.solve(self.w_el, b)) if dense else lu.solve

    def elastic_matrix(self, h):
        return self.w_el

    def elastic_solve(self, h):
        return self._solve

    def factor_like_w(self, W):
        return spla.splu(sp.csc_matrix(W)).solve

    def elastic_nodal_inverse(self, h, selector):
        """W_el^-1 psi^T N^T (BodySolver.nodal_inverse of the elastic W)."""
        return self._solve(np.asarray((selector @ self.body.psi).T.todense()))


def _yielding_block():
    """The nodal tangent difference K_t - K_el of a clamped block bent past yield, its K and
    lumped mass."""
    mesh = box_hex((6, 2, 2), (0.3, 0.05, 0.05), order=1)
    body = PlasticBody.build(mesh, STEEL, J2Plasticity(250e6, hardening_pa=2e9))
    x = mesh.nodes
    u = np.zeros(mesh.n_dof)
    u[2::3] = 1e-3 * (x[:, 0] / 0.3) ** 3  # bending, curvature growing to x = 0.3 m: yield there
    hist = StepHistory(body)
    hist.check(u)  # the set: cells above half of Y
    assert hist.correction(u) is not None
    diff = hist.tangent_difference()
    asm = assemble(mesh, STEEL)
    return diff, asm.K, asm.M, mesh.n_dof


@pytest.mark.parametrize("form", ["woodbury", "refactor"])
def test_woodbury_solve_is_the_direct_solve_of_the_tangent_w(form, monkeypatch):
    monkeypatch.setattr(plastic_tangent, "SPARSE_FORM", form)
    diff, K, M, n = _yielding_block()
    touched = np.flatnonzero(np.diff(diff.indptr))
    assert 0 < touched.size < n  # the yielding cells' DOFs only
    keep = np.arange(6, n)  # psi drops six coordinates (a floating frame's reference DOFs)
    psi = sp.csr_matrix((np.ones(keep.size), (keep, np.arange(keep.size))), shape=(n, keep.size))
    k_hat, m_qq = psi.T @ K @ psi, psi.T @ M @ psi
    w_t = m_qq + C_TH2H2 * (k_hat + psi.T @ diff @ psi)
    b = np.random.default_rng(1).normal(size=(keep.size, 2))
    exact = spla.splu(sp.csc_matrix(w_t)).solve(b)
    x = tangent_solve(_Solver(psi, k_hat, m_qq), 2e-6, C_TH2H2, diff)(b)
    assert np.abs(x - exact).max() <= 1e-9 * np.abs(exact).max()
    # the tangent is a real change of W here: the elastic solve is far from it
    y = spla.splu(sp.csc_matrix(m_qq + C_TH2H2 * k_hat)).solve(b)
    assert np.abs(y - exact).max() > 1e-3 * np.abs(exact).max()
    # the dense (MVM) form: W_t refactored, psi the identity
    dense = _Solver(np.eye(n), K.toarray(), M.toarray())
    x_d = tangent_solve(dense, 2e-6, C_TH2H2, diff)(np.ones((n, 2)))
    exact_d = np.linalg.solve(dense.w_el + C_TH2H2 * diff.toarray(), np.ones((n, 2)))
    assert np.abs(x_d - exact_d).max() <= 1e-9 * np.abs(exact_d).max()


class _History:
    """What PlasticTangent reads of a StepHistory: the yielding points of the last return."""

    def __init__(self):
        self.points = np.zeros(0, np.int64)

    def yielding_points(self):
        return self.points

    def tangent_difference(self):
        return "diff" if self.points.size else None


class _Installs:
    """What PlasticTangent calls on a BodySolver: the solves installed (None: elastic W)."""

    def __init__(self):
        self.installed = []

    def use_tangent(self, h, solve):
        self.installed.append(solve)


def test_lazy_policy_keeps_w_t_and_makes_it_again_only_when_due(monkeypatch):
    """The lazy update policy (plastic_tangent module doc), exact counts: not at the start
    guess, on a yielding set moved by more than SET_CHANGE of its size, on a small move only
    with a poor contraction, at most MAX_UPDATES_PER_STEP a step, W_t kept into the next step
    at the same h and dropped at another. Bookkeeping only: milliseconds."""
    monkeypatch.setattr(plastic_tangent, "tangent_solve", lambda solver, h, c, diff: ("W_t", h))
    monkeypatch.setattr(plastic_tangent, "MAX_UPDATES_PER_STEP", 1)
    hist, solver = _History(), _Installs()
    tangent = plastic_tangent.PlasticTangent(
        SimpleNamespace(history={0: hist}), {0: solver}, enabled=True, policy="lazy"
    )
    h, th = 1e-6, 0.5
    tangent.start_step(h)
    hist.points = np.arange(40)
    assert not tangent.update(h, th, it=0)  # the start guess's returns: never
    assert tangent.update(h, th, it=1)  # from none to 40 points
    hist.points = np.arange(60)  # grown by half of 40: due, but this step had its update
    assert not tangent.update(h, th, it=2, contraction=0.9)
    tangent.start_step(h)  # the next step keeps W_t: nothing installed
    assert solver.installed == [("W_t", h)]
    hist.points = np.arange(45)  # 5 of W_t's 40 (< SET_CHANGE): not with a good contraction ...
    assert not tangent.update(h, th, it=1, contraction=0.0)
    assert tangent.update(h, th, it=2, contraction=0.6)  # ... but with a poor one
    tangent.start_step(2 * h)  # another step size: the elastic W
    assert solver.installed[-1] is None and tangent.n_updates == 2
    # "every": each step from the elastic W, made again on any change, it 0 included
    every = plastic_tangent.PlasticTangent(
        SimpleNamespace(history={0: hist}), {0: _Installs()}, enabled=True, policy="every"
    )
    every.start_step(h)
    assert every.update(h, th, it=0) and not every.update(h, th, it=1)
    hist.points = np.arange(66)
    assert every.update(h, th, it=2, contraction=0.0)
