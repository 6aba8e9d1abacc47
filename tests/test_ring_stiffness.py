"""The ring body's stiffness (bodies/ring_body.ring_stiffness) from the static condensation of
its ring: B^T K_EE B_s = -(K_Gamma,E B)^T for the ring's static columns, the products only for
the other corner columns; the products over every column where the relation does not hold.

On the shipped gmsh block (tet10), a region of 0.9 mm (388 nodes, 233 on the ring) with 12
modes. Both ways compute the same matrix, the one from the solves' relation, the other from
products summing thousands of terms: they agree to the round-off of those sums and of the
K_EE solves (TOL, ~5000 machine epsilons, as tests/test_ring_body.py; measured 1.4e-16 and
2.0e-16 against psi^T K psi)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm.bodies import ring_body as rb
from flexmvm.fe import assemble
from flexmvm.materials import ALUMINIUM
from flexmvm.mesh.io import read_mesh
from flexmvm.reduction.kinds.mvm_sparse import RingColumns, ring_columns
from flexmvm.reduction.reference_condition import far_reference

BLOCK = Path(__file__).parents[1] / "scenarios" / "meshes" / "block_60x60x30.msh"
TOL = 1e-12


@pytest.fixture(scope="module")
def block_fe():
    return assemble(read_mesh(BLOCK), ALUMINIUM)


def _rel(a, b) -> float:
    a, b = (x.toarray() if sp.issparse(x) else np.asarray(x) for x in (a, b))
    return float(np.abs(a - b).max() / np.abs(b).max())


def _exact(fe, nodes, cols: RingColumns, nq: int) -> np.ndarray:
    """psi^T K psi with psi whole (dense): the definition."""
    b = (3 * nodes[:, None] + np.arange(3)).ravel()
    psi = np.zeros((fe.n_dof, nq))
    psi[b, np.arange(b.size)] = 1.0
    psi[np.ix_(cols.interior, cols.corner)] = cols.B
    return psi.T @ (fe.K @ psi)


def _case(fe, radius_m=0.9e-3, massless_ring=0):
    """(fe, nodes, RingColumns, nq) of the region; massless_ring: that many ring nodes made
    massless (their rows of M_s removed), whose columns are zero on E."""
    nodes = np.flatnonzero(np.linalg.norm(fe.mesh.nodes, axis=1) <= radius_m)
    ref = far_reference(fe.mesh, nodes)
    if massless_ring:
        cols, _, _ = ring_columns(fe, ref, nodes, 12)
        gone = nodes[cols.ring[:massless_ring]]
        keep = np.ones(fe.mesh.n_nodes)
        keep[gone] = 0.0
        m = sp.csr_matrix(sp.diags(keep) @ fe.M_scalar @ sp.diags(keep))
        m.eliminate_zeros()
        fe = dataclasses.replace(fe, M_scalar=m, M=sp.csr_matrix(sp.kron(m, sp.identity(3))))
    cols, n_s, _ = ring_columns(fe, ref, nodes, 12)
    return fe, nodes, cols, 3 * nodes.size + n_s + 12


@pytest.mark.parametrize("massless_ring", [0, 3])
def test_the_condensation_is_the_products(block_fe, monkeypatch, massless_ring):
    """The relation holds for ring_solve's basis (the products are not taken) and gives
    psi^T K psi; with massless ring nodes too (their columns zero on E)."""
    fe, nodes, cols, nq = _case(block_fe, massless_ring=massless_ring)
    if massless_ring:
        assert np.count_nonzero(np.abs(cols.B).max(axis=0) == 0.0) == 3 * massless_ring

    def refuse(*args):
        raise AssertionError("the products were taken")

    monkeypatch.setattr(rb, "_direct_products", refuse)
    k_hat = rb.ring_stiffness(fe, nodes, cols, nq)
    exact = _exact(fe, nodes, cols, nq)
    assert _rel(k_hat, 0.5 * (exact + exact.T)) <= TOL


def test_a_basis_off_the_relation_takes_the_products(block_fe, monkeypatch):
    """Static columns that do not solve K_EE B_s = -K_E,Gamma (scaled by 1.001: not this K's
    statics) fail the check and k_hat comes from the products, psi^T K psi all the same."""
    fe, nodes, cols, nq = _case(block_fe)
    B = cols.B.copy()
    B[:, : cols.n_ring_dofs] *= 1.001
    off = RingColumns(cols.interior, cols.corner, B, cols.ring)
    taken = []
    direct = rb._direct_products
    monkeypatch.setattr(rb, "_direct_products", lambda *a: taken.append(1) or direct(*a))
    k_hat = rb.ring_stiffness(fe, nodes, off, nq)
    exact = _exact(fe, nodes, off, nq)
    assert taken and _rel(k_hat, 0.5 * (exact + exact.T)) <= TOL
