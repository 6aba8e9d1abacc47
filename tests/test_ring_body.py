"""The ring basis (kind mvm-sparse, reduction/kinds/mvm_sparse.py) and its body (bodies/ring_body.py): Craig-Bampton with the
region's ring as its only boundary, stored sparse.

Its columns are those of the dense Craig-Bampton basis of the same retained nodes (the
constraint mode of a region DOF off the ring is exactly zero outside the region), so every
reduced matrix and inertia invariant must agree with the dense body's to round-off: the
tolerance 1e-12 relative is ~5000 machine epsilons, the round-off of the K_EE solves and of
products summing ~1e3 terms (measured: <= 7e-14). Tried on the shipped gmsh block (tet10), not
a rod, with a small and a large region."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm.bodies.build import body_from_fe
from flexmvm.bodies.ring_body import RingBody, ring_body_from_parts, ring_parts
from flexmvm.fe import assemble
from flexmvm.materials import ALUMINIUM
from flexmvm.mesh.io import read_mesh
from flexmvm.reduction.basis import Basis, BasisKind, build_basis
from flexmvm.reduction.kinds.mvm_sparse import ring_columns, ring_psi, split_ring_psi
from flexmvm.reduction.reference_condition import far_reference

BLOCK = Path(__file__).parents[1] / "scenarios" / "meshes" / "block_60x60x30.msh"
TOL = 1e-12


def _rel(a, b) -> float:
    a = a.toarray() if sp.issparse(a) else np.asarray(a)
    b = b.toarray() if sp.issparse(b) else np.asarray(b)
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


@pytest.fixture(scope="module")
def block_fe():
    return assemble(read_mesh(BLOCK), ALUMINIUM)


def _region(fe, radius_m: float) -> np.ndarray:
    """The nodes within radius_m of the top face's centre (the contact point)."""
    return np.flatnonzero(np.linalg.norm(fe.mesh.nodes, axis=1) <= radius_m)


def _pair(fe, nodes, n_modes=12):
    """(dense Craig-Bampton basis, ring basis as a Basis with csr psi, RingColumns)."""
    ref = far_reference(fe.mesh, nodes)
    dense = build_basis(fe, BasisKind.CRAIG_BAMPTON, ref, nodes, n_modes)
    cols, n_s, freqs = ring_columns(fe, ref, nodes, n_modes)
    nq = 3 * nodes.size + n_s + n_modes
    psi = ring_psi(fe.n_dof, nodes, cols, nq)
    ring = Basis(BasisKind.CRAIG_BAMPTON, psi, nodes, n_modes, ref, freqs)
    return dense, ring, cols


@pytest.mark.parametrize("radius_m", [0.5e-3, 0.9e-3])
def test_ring_basis_and_parts_are_craig_bamptons(block_fe, radius_m):
    """psi, k_hat, M_qq and every inertia invariant of the ring body equal the dense
    Craig-Bampton body's (TOL); the dense corner is the ring's DOFs and the modes only, and
    for the larger region the ring is a strict part of it."""
    fe = block_fe
    nodes = _region(fe, radius_m)
    dense, ring, cols = _pair(fe, nodes)
    assert ring.nq == dense.nq
    assert _rel(ring.psi, dense.psi) <= TOL
    np.testing.assert_allclose(ring.mode_freqs_hz, dense.mode_freqs_hz, rtol=1e-10)
    body = body_from_fe("block", fe, dense)
    parts = ring_parts(fe, nodes, cols, ring.nq)
    inv, ref = parts.inv, body.inv
    assert _rel(parts.k_hat, body.k_hat) <= TOL
    assert _rel(inv.M_qq, ref.M_qq) <= TOL
    assert _rel(inv.S1, ref.S1) <= TOL and _rel(inv.G0, ref.G0) <= TOL
    assert abs(inv.mass - ref.mass) <= TOL * ref.mass
    for a in range(3):
        for b in range(3):
            assert _rel(inv.G1[a][b], ref.G1[a][b]) <= TOL
            assert _rel(inv.G2[a][b], ref.G2[a][b]) <= TOL
    assert cols.corner.size == 3 * cols.ring.size + 12
    # the exterior couples to the region through the ring alone: k_hat has no entry between
    # a region DOF off the ring and a modal coordinate
    off_ring = np.setdiff1d(np.arange(3 * nodes.size), cols.corner)
    assert sp.csr_matrix(parts.k_hat)[off_ring][:, 3 * nodes.size :].nnz == 0
    if radius_m > 0.6e-3:
        assert cols.ring.size < 0.7 * nodes.size  # measured 0.9 mm: 233 of 388 nodes
        assert parts.k_hat.nnz < 0.5 * dense.nq**2


def test_split_ring_psi_gives_back_the_columns(block_fe):
    """The setup cache keeps psi; split_ring_psi recovers the RingColumns it was made of."""
    nodes = _region(block_fe, 0.5e-3)
    _, ring, cols = _pair(block_fe, nodes)
    again = split_ring_psi(block_fe, ring.reference, ring.psi, nodes)
    assert np.array_equal(again.interior, cols.interior)
    assert np.array_equal(again.corner, cols.corner)
    assert np.array_equal(again.ring, cols.ring)
    assert np.array_equal(again.B, cols.B)


def test_ring_basis_with_massless_contact_nodes(block_fe):
    """Retained nodes without mass (the 7 nearest the contact point, their rows of M_s
    removed as mass redistribution leaves them): their columns are unit vectors, their static
    fields the static columns (MasslessStatics.PATCH), as the dense basis. The static columns
    are an M-orthonormal basis of one span (an eigen solve of its Gram matrix), so they are
    compared through the span: the reduced stiffness and mass of both bodies, projected on
    the other's columns, and the lowest frequencies of the massless-condensed models agree."""
    fe = block_fe
    nodes = _region(fe, 0.5e-3)
    order = np.argsort(np.linalg.norm(fe.mesh.nodes[nodes], axis=1))
    keep = np.ones(fe.mesh.n_nodes)
    keep[nodes[order[:7]]] = 0.0
    m = sp.csr_matrix(sp.diags(keep) @ fe.M_scalar @ sp.diags(keep))
    m.eliminate_zeros()
    fe_r = dataclasses.replace(fe, M_scalar=m, M=sp.csr_matrix(sp.kron(m, sp.identity(3))))
    dense, ring, cols = _pair(fe_r, nodes, n_modes=6)
    assert ring.nq == dense.nq and dense.n_static > 0
    nb = 3 * nodes.size
    # everything but the static columns equal column by column
    other = np.r_[np.arange(nb), np.arange(nb + dense.n_static, dense.nq)]
    assert _rel(ring.psi[:, other], dense.psi[:, other]) <= TOL
    # the static columns span the same space: least-squares residual of one in the other.
    # They are Gram eigenvectors scaled by 1/sqrt(w), w down to 1e-12 of the largest, which
    # amplifies the fields' round-off: measured 3.2e-10 of the largest entry
    S_d = dense.psi[:, nb : nb + dense.n_static]
    S_r = ring.psi[:, nb : nb + dense.n_static].toarray()
    coef, *_ = np.linalg.lstsq(S_d, S_r, rcond=None)
    assert np.abs(S_d @ coef - S_r).max() <= 2e-9 * np.abs(S_r).max()
    parts = ring_parts(fe_r, nodes, cols, ring.nq)
    massless = (3 * order[:7][:, None] + np.arange(3)).ravel()
    assert not np.any(sp.csr_matrix(parts.inv.M_qq)[massless].data)
    body = body_from_fe("block", fe_r, dense)
    assert _rel(parts.k_hat[other][:, other], body.k_hat[np.ix_(other, other)]) <= TOL


@pytest.fixture(scope="module")
def bodies(block_fe):
    nodes = _region(block_fe, 0.9e-3)
    dense, ring, cols = _pair(block_fe, nodes)
    body_d = body_from_fe("block", block_fe, dense)
    parts = ring_parts(block_fe, nodes, cols, ring.nq)
    body_r = ring_body_from_parts("block", block_fe.mesh, ring, parts, cols.corner)
    return body_d, body_r


def test_ring_body_contractions_and_inertia_terms(bodies):
    """L(x) = G2[b][a] x, the inertia terms (S, J, M_wq, C), the rotational coupling and the
    quadratic-velocity forces of a spinning, deforming state: the ring body's split
    contraction (sparse part + packed corner) against the dense body's (TOL)."""
    body_d, body_r = bodies
    assert isinstance(body_r, RingBody) and body_r.nodal is None
    rng = np.random.default_rng(3)
    q = 1e-6 * rng.standard_normal(body_d.nq)
    qd = 1e-2 * rng.standard_normal(body_d.nq)
    assert _rel(body_r.contractions(qd), body_d.contractions(qd)) <= TOL
    for x, y in zip(body_r.inertia_terms(q), body_d.inertia_terms(q), strict=True):
        assert _rel(x, y) <= TOL
    assert _rel(body_r.rotational_coupling(q), body_d.rotational_coupling(q)) <= TOL
    v = np.r_[0.1, -0.2, 0.3, 40.0, -25.0, 60.0, qd]
    A = np.eye(3)
    assert _rel(body_r.velocity_forces(A, q, v), body_d.velocity_forces(A, q, v)) <= TOL
    a_vec = rng.standard_normal(body_d.nv)
    assert _rel(body_r.mass_times(A, q, a_vec), body_d.mass_times(A, q, a_vec)) <= TOL


def test_sphere_on_block_through_the_scenario_kind():
    """scenarios/sphere_block.toml over 30 us (the approach and the first third of the
    contact, 60 steps) with the block as kind mvm-sparse and as mvm, same region and modes:
    a RingBody, the same DOF, the contact force equal to 1e-10 of its peak (measured 2.4e-12
    here and 3.5e-11 over 100 us: the round-off of two factorizations carried through the
    steps)."""
    import flexmvm as fm
    from flexmvm.runs.run import run_scenario

    path = Path(__file__).parents[1] / "scenarios" / "sphere_block.toml"
    sc = fm.load_scenario(path).with_time(t_end_s=3e-5)
    region = {"ball": {"centre_m": [0.0, 0.0, 0.0], "radius_m": 0.5e-3}}
    runs = {}
    for kind in ("mvm", "mvm-sparse"):
        model = fm.mvm(region=region, modes=20, kind=fm.ModelKind(kind))
        runs[kind] = run_scenario(sc.with_model("block", model), warn=False)
    ring, dense = runs["mvm-sparse"], runs["mvm"]
    assert isinstance(ring.built.system.bodies[1], RingBody)
    assert ring.summary["dof"] == dense.summary["dof"]
    f_r, f_d = np.asarray(ring.result.contact_force), np.asarray(dense.result.contact_force)
    assert f_d.max() > 400.0  # in contact (peak 510 N at 30 us)
    assert np.abs(f_r - f_d).max() <= 1e-10 * f_d.max()
