"""Reference condition (3-2-1) and reduction bases on a small HEX27 beam.

Beam: 0.12 x 0.02 x 0.02 m, 6 x 2 x 2 HEX27 cells (325 nodes, 975 DOF), aluminium. The
3-2-1 support is on the x = L face; region II (retained nodes) on the x = 0 face.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from flexmvm.errors import InputError
from flexmvm.fe import assemble, constrained_modes
from flexmvm.materials import ALUMINIUM
from flexmvm.mesh.mesh import CellBlock, CellType, FacetSet, Mesh
from flexmvm.reduction import (
    BasisKind,
    ReferenceCondition,
    build_basis,
    reduced_matrices,
    rigid_body_modes,
    three_two_one,
)
from flexmvm.reduction.basis import MasslessStatics, massless_patterns
from flexmvm.reduction.interface import InterfaceSpec

# meshio/VTK hexahedron27 nodes as doubled reference coordinates (independent of the library).
_HEX27 = [
    (0, 0, 0),
    (2, 0, 0),
    (2, 2, 0),
    (0, 2, 0),
    (0, 0, 2),
    (2, 0, 2),
    (2, 2, 2),
    (0, 2, 2),
    (1, 0, 0),
    (2, 1, 0),
    (1, 2, 0),
    (0, 1, 0),
    (1, 0, 2),
    (2, 1, 2),
    (1, 2, 2),
    (0, 1, 2),
    (0, 0, 1),
    (2, 0, 1),
    (2, 2, 1),
    (0, 2, 1),
    (0, 1, 1),
    (2, 1, 1),
    (1, 0, 1),
    (1, 2, 1),
    (1, 1, 0),
    (1, 1, 2),
    (1, 1, 1),
]


def beam(n=(6, 2, 2), size=(0.12, 0.02, 0.02)) -> Mesh:
    shape = tuple(2 * k + 1 for k in n)
    ids = np.arange(np.prod(shape)).reshape(shape)
    ijk = np.stack(np.meshgrid(*[np.arange(s) for s in shape], indexing="ij"), -1).reshape(-1, 3)
    nodes = ijk / (np.array(shape) - 1) * np.array(size) - [0, size[1] / 2, size[2] / 2]
    base = np.stack(np.meshgrid(*[2 * np.arange(k) for k in n], indexing="ij"), -1).reshape(-1, 3)
    conn = np.stack([ids[tuple((base + o).T)] for o in np.array(_HEX27)], axis=1)
    return Mesh(nodes, (CellBlock(CellType.HEX27, conn),))


@pytest.fixture(scope="module")
def fe():
    return assemble(beam(), ALUMINIUM)


@pytest.fixture(scope="module")
def ref(fe):
    x = fe.mesh.nodes[:, 0]
    return three_two_one(fe.mesh, np.flatnonzero(np.isclose(x, x.max())))


@pytest.fixture(scope="module")
def face_a(fe):
    """Region II: the 25 nodes of the x = 0 face, centre node first."""
    nodes = fe.mesh.nodes
    ids = np.flatnonzero(np.isclose(nodes[:, 0], 0.0))
    return ids[np.argsort(np.linalg.norm(nodes[ids], axis=1), kind="stable")]


@pytest.fixture(scope="module")
def full_lam(fe, ref):
    """Reference-supported full-FE eigenvalues omega^2, first 12."""
    freqs, _ = constrained_modes(fe.M, fe.K, ref.fixed_dofs, 12)
    return (2 * np.pi * freqs) ** 2


def reduced_lam(fe, basis):
    m, k = reduced_matrices(fe, basis)
    m, k = (a.toarray() if sp.issparse(a) else a for a in (m, k))
    return sla.eigh(k, m, eigvals_only=True)


def _with_face(fe):
    """fe with facet set end_a: the x = 0 face as 4 x 4 linear quads (outward normal -x)."""
    X = fe.mesh.nodes
    ids = np.flatnonzero(np.isclose(X[:, 0], 0.0))
    grid = ids[np.lexsort((X[ids, 2], X[ids, 1]))].reshape(5, 5)  # [y index, z index]
    quads = [
        [grid[i, j], grid[i, j + 1], grid[i + 1, j + 1], grid[i + 1, j]]
        for i in range(4)
        for j in range(4)
    ]
    mesh = dataclasses.replace(fe.mesh, facet_sets={"end_a": FacetSet(quads=np.array(quads))})
    return dataclasses.replace(fe, mesh=mesh)


def make(fe, ref, face_a, kind, n_modes=6, retained=None):
    if kind is BasisKind.INTERFACE:  # two Hertz patches on the x = 0 face + modes
        return build_basis(
            _with_face(fe), kind, ref, (), n_modes, interface=InterfaceSpec(radii_m=(0.003, 0.006))
        )
    if kind in (BasisKind.FULL, BasisKind.MODAL):
        return build_basis(fe, kind, ref, (), 0 if kind is BasisKind.FULL else n_modes)
    return build_basis(fe, kind, ref, face_a if retained is None else retained, n_modes)


KINDS = list(BasisKind)


def test_three_two_one_choice(fe, ref):
    """A = face centre (x, y, z); B = a face corner, fixed in x and its smaller in-plane
    component; C fixed along AB x AC = +-x. The rigid modes at the six DOFs are well
    conditioned (< 10, unit-free) and the supported body has no zero-energy mode."""
    nodes = fe.mesh.nodes
    a, b, c = ref.nodes
    np.testing.assert_allclose(nodes[a], [0.12, 0.0, 0.0], atol=1e-15)
    assert np.isclose(np.linalg.norm(nodes[b] - nodes[a]), np.hypot(0.01, 0.01))
    assert ref.fixed_dofs[:3].tolist() == [3 * a, 3 * a + 1, 3 * a + 2]
    assert ref.fixed_dofs[3] == 3 * b and ref.fixed_dofs[5] == 3 * c
    rows = rigid_body_modes(nodes)[ref.fixed_dofs]
    assert np.linalg.cond(rows) < 1e4
    freqs, _ = constrained_modes(fe.M, fe.K, ref.fixed_dofs, 1)
    assert freqs[0] > 1.0


def test_reference_bad_inputs(fe):
    mesh = fe.mesh
    on_axis = np.flatnonzero(np.all(np.isclose(mesh.nodes[:, 1:], 0.0), axis=1))
    with pytest.raises(InputError, match="collinear"):
        three_two_one(mesh, on_axis)
    with pytest.raises(InputError, match="at least 3"):
        three_two_one(mesh, [0, 1])
    with pytest.raises(InputError, match="in 0.."):
        three_two_one(mesh, [0, 1, mesh.n_nodes])
    with pytest.raises(InputError, match="rigid-body"):
        ReferenceCondition.from_dofs(mesh, 3 * np.arange(6))  # six x components
    with pytest.raises(InputError, match="in 0.."):
        ReferenceCondition.from_dofs(mesh, [0, 1, 2, 3, 4, mesh.n_dof])
    with pytest.raises(InputError, match="6 integer"):
        ReferenceCondition((0,), np.arange(5))
    # Nodes 0, 2, 14 lie in the x = 0 face, AB along z, AB x AC along x.
    with pytest.raises(InputError, match="rigid-body"):  # B clamped along AB
        ReferenceCondition.from_dofs(mesh, [0, 1, 2, 3 * 2 + 1, 3 * 2 + 2, 3 * 14 + 2])
    ok = ReferenceCondition.from_dofs(mesh, [0, 1, 2, 3 * 2, 3 * 2 + 1, 3 * 14])
    assert ok.nodes == (0, 2, 14)


@pytest.mark.parametrize("kind", KINDS, ids=lambda k: k.value)
def test_basis_structure(fe, ref, face_a, kind):
    """Zero reference rows; m_hat, k_hat symmetric (exactly, symmetrised); m_hat positive
    definite and k_hat positive definite (the support removes rigid motion), checked by
    eigenvalues > 0; retained columns are unit columns at the retained nodes' DOFs."""
    basis = make(fe, ref, face_a, kind)
    psi = basis.psi.toarray() if sp.issparse(basis.psi) else basis.psi
    assert psi.shape == (fe.n_dof, basis.nq)
    assert np.all(psi[ref.fixed_dofs] == 0.0)
    m, k = (a.toarray() if sp.issparse(a) else a for a in reduced_matrices(fe, basis))
    assert np.array_equal(m, m.T) and np.array_equal(k, k.T)
    assert np.linalg.eigvalsh(m).min() > 0
    assert sla.eigh(k, m, eigvals_only=True).min() > 0
    cols = basis.retained_columns()
    if kind is not BasisKind.MODAL:
        dofs = 3 * basis.retained_nodes[:, None] + np.arange(3)
        assert np.all(psi[dofs, cols] == 1.0)
        assert np.all(np.abs(psi[np.ix_(dofs.ravel(), cols.ravel())] - np.eye(cols.size)) == 0)


@pytest.mark.parametrize("kind", KINDS, ids=lambda k: k.value)
def test_rayleigh_ritz_upper_bounds(fe, ref, face_a, full_lam, kind):
    """Reduced omega^2 >= full omega^2 (reference-supported), to a relative round-off margin
    of 1e-9 (the soft 3-2-1 support modes come out to ~2e-10 in either solve); FULL and
    MODAL reproduce the full values (rel 1e-8: MODAL's subspace holds the exact modes)."""
    lam = reduced_lam(fe, make(fe, ref, face_a, kind))
    k = min(len(lam), 12) if kind is not BasisKind.MODAL else 6
    assert np.all(lam[:k] >= full_lam[:k] * (1 - 1e-9))
    if kind in (BasisKind.FULL, BasisKind.MODAL):
        np.testing.assert_allclose(lam[:k], full_lam[:k], rtol=1e-8)


@pytest.mark.parametrize(
    "kind", [BasisKind.CRAIG_BAMPTON, BasisKind.SEED_BLOCK, BasisKind.MODAL], ids=lambda k: k.value
)
def test_frequencies_decrease_with_modes(fe, ref, face_a, full_lam, kind):
    """Adding modes nests the subspaces, so every reduced omega^2_k of the smaller basis
    (k <= its nq) is >= the one of the larger basis (margin rel 1e-9: the soft 3-2-1
    support modes are computed to ~2e-10 here). CB and SEED_BLOCK must also strictly improve
    some value (> 1e-6) at each step; MODAL reproduces the same exact modes. With 30 modes CB
    is within 1e-3 of full for the first 4 (measured 7e-7 .. 7e-5)."""
    previous = None
    for n_modes in (4, 8, 16, 30):
        lam = reduced_lam(fe, make(fe, ref, face_a, kind, n_modes))
        if previous is not None:
            assert np.all(lam[: len(previous)] <= previous * (1 + 1e-9))
            if kind is not BasisKind.MODAL:
                assert np.any(lam[: len(previous)] < previous * (1 - 1e-6))
        previous = lam
    if kind is BasisKind.CRAIG_BAMPTON:
        np.testing.assert_allclose(previous[:4], full_lam[:4], rtol=1e-3)


def _static_full(fe, ref, f):
    free = ref.free_dofs(fe.n_dof)
    u = np.zeros(fe.n_dof)
    u[free] = spla.spsolve(sp.csc_matrix(fe.K[free][:, free]), f[free])
    return u


@pytest.mark.parametrize("n_retained", [1, 25])
def test_craig_bampton_static_exact(fe, ref, face_a, n_retained):
    """A load at a retained node lies in the CB constraint-mode space, so the reduced static
    response psi k_hat^-1 psi^T f equals the full (reference-supported) solution: relative
    error <= 1e-9 (measured 2.5e-12 with one node, 4.6e-12 with 25)."""
    basis = build_basis(fe, BasisKind.CRAIG_BAMPTON, ref, face_a[:n_retained], 5)
    f = np.zeros(fe.n_dof)
    f[3 * face_a[0] + np.arange(3)] = [100.0, 50.0, -30.0]
    u_full = _static_full(fe, ref, f)
    _, k = reduced_matrices(fe, basis)
    u_cb = basis.psi @ np.linalg.solve(k, basis.psi.T @ f)
    assert np.linalg.norm(u_cb - u_full) <= 1e-9 * np.linalg.norm(u_full)


def test_single_retained_node(fe, ref, face_a):
    """Seed selection 1-1: one node, 3 DOF + modes; columns: its x, y, z, then the modes."""
    basis = build_basis(fe, BasisKind.CRAIG_BAMPTON, ref, [face_a[0]], 7)
    assert basis.nq == 10 and basis.n_modes == 7 and len(basis.mode_freqs_hz) == 7
    assert basis.retained_columns().tolist() == [[0, 1, 2]]
    assert np.all(np.diff(basis.mode_freqs_hz) >= 0) and basis.mode_freqs_hz[0] > 0
    seed = build_basis(fe, BasisKind.SEED_BLOCK, ref, [face_a[0]], 7)
    assert seed.retained_columns().tolist() == [[7, 8, 9]]


def test_bad_basis_inputs(fe, ref, face_a):
    cb = BasisKind.CRAIG_BAMPTON
    cases = [
        (cb, [ref.nodes[1]], 2, "reference"),
        (cb, [face_a[0], face_a[0]], 2, "repeat"),
        (cb, [fe.mesh.n_nodes], 2, "in 0.."),
        (cb, [-1], 2, "in 0.."),
        (cb, [0.5], 2, "integer"),
        (cb, [], 2, "at least one"),
        (cb, face_a, fe.n_dof, "modes"),
        (cb, face_a, -1, "n_modes"),
        (BasisKind.MODAL, (), 0, "n_modes >= 1"),
        (BasisKind.MODAL, face_a, 3, "no retained"),
        (BasisKind.FULL, (), 3, "no modes"),
        ("mvm", face_a, 3, "BasisKind"),
    ]
    for kind, nodes, n_modes, match in cases:
        with pytest.raises(InputError, match=match):
            build_basis(fe, kind, ref, nodes, n_modes)
    other = assemble(beam((2, 1, 1), (0.04, 0.02, 0.02)), ALUMINIUM)
    basis = build_basis(fe, BasisKind.MODAL, ref, (), 2)
    with pytest.raises(InputError, match="rows"):
        reduced_matrices(other, basis)


def _redistributed(fe, nodes):
    """fe with ``nodes`` massless: their rows and columns of M_scalar removed (the algebra
    under test needs only zero rows; fe.mass_redistribution, which also keeps the moments,
    needs a finer mesh than this beam's)."""
    keep = np.ones(fe.mesh.n_nodes)
    keep[nodes] = 0.0
    m = sp.csr_matrix(sp.diags(keep) @ fe.M_scalar @ sp.diags(keep))
    m.eliminate_zeros()
    return dataclasses.replace(fe, M_scalar=m, M=sp.csr_matrix(sp.kron(m, sp.identity(3))))


def _condensed_lam_dense(k, m, s):
    """omega^2 of (k, m) with the massless coordinates s condensed out (exact: they carry no
    inertia), ascending."""
    n = np.setdiff1d(np.arange(k.shape[0]), s)
    k_eff = k[np.ix_(n, n)] - k[np.ix_(n, s)] @ np.linalg.solve(k[np.ix_(s, s)], k[np.ix_(s, n)])
    return sla.eigh(k_eff, m[np.ix_(n, n)], eigvals_only=True)


def _condensed_lam(fe, basis, s):
    m, k = reduced_matrices(fe, basis)
    return _condensed_lam_dense(k, m, s)


def test_craig_bampton_split_at_massless_retained_nodes(fe, ref, face_a):
    """MasslessStatics.ALL. Retained nodes without mass (the 9 central nodes of the x = 0 face redistributed; the
    face's 25 nodes retained): their columns are nodal unit vectors and their interior static
    fields columns of their own, M-orthonormal. Their coordinates have exactly zero rows in
    m_hat, the other retained nodes' keep their mass; the span holds the Craig-Bampton one of the
    same model (residual <= 1e-10: least squares in the 2-norm of nodal displacements), so
    its frequencies are Rayleigh-Ritz bounded by Craig-Bampton's (<= 1e-9 relative: the
    round-off of two eigen solves) and bound the full model's from above."""
    fe_r = _redistributed(fe, face_a[:9])
    cb_psi = _craig_bampton_unsplit(fe_r, ref, face_a, 6)
    split = build_basis(
        fe_r, BasisKind.CRAIG_BAMPTON, ref, face_a, 6, massless_statics=MasslessStatics.ALL
    )
    nb, ns = 3 * face_a.size, 27  # columns of the retained nodes, of the massless ones
    assert split.n_static == split.nq - nb - 6 and 0 < split.n_static <= ns
    dofs = (3 * face_a[:, None] + np.arange(3)).ravel()
    assert np.array_equal(split.psi[dofs, :nb], np.eye(nb))
    assert not split.psi[dofs, nb:].any()
    interior = np.setdiff1d(np.arange(fe.n_dof), np.r_[dofs, ref.fixed_dofs])
    # the massless nodes' columns move nothing but their node; the others are constraint modes
    assert not split.psi[interior, :ns].any()
    np.testing.assert_allclose(split.psi[:, ns:nb], cb_psi[:, ns:nb], rtol=0, atol=1e-12)
    stat = split.psi[interior, nb : nb + split.n_static]
    gram = stat.T @ (fe_r.M[interior][:, interior] @ stat)
    np.testing.assert_allclose(gram, np.eye(split.n_static), atol=1e-10)
    m, _ = reduced_matrices(fe_r, split)
    assert np.all(m[:ns] == 0.0) and np.all(np.diag(m)[ns:] > 0)
    coef = np.linalg.lstsq(split.psi, cb_psi, rcond=None)[0]
    assert np.linalg.norm(split.psi @ coef - cb_psi) <= 1e-10 * np.linalg.norm(cb_psi)
    lam_split = _condensed_lam(fe_r, split, np.arange(ns))[:8]
    m_cb, k_cb = (cb_psi.T @ (a @ cb_psi) for a in (fe_r.M, fe_r.K))
    lam_cb = sla.eigh(0.5 * (k_cb + k_cb.T), 0.5 * (m_cb + m_cb.T), eigvals_only=True)[:8]
    assert np.all(lam_split <= lam_cb * (1 + 1e-9))
    free = ref.free_dofs(fe.n_dof)
    s_full = np.searchsorted(free, dofs[:ns])  # the massless DOFs among the free ones
    k_f, m_f = (a[free][:, free].toarray() for a in (fe_r.K, fe_r.M))
    lam_full = _condensed_lam_dense(k_f, m_f, s_full)[:8]
    assert np.all(lam_full <= lam_split * (1 + 1e-9))


def test_patch_statics_of_massless_retained_nodes(fe, ref, face_a):
    """MasslessStatics.PATCH (the default): the same 9 massless nodes keep their nodal unit
    vectors (zero rows of m_hat), and their static columns are the interior static fields of
    massless_patterns' 11 smooth patterns only, M-orthonormal: a boundary motion along a
    pattern, with its Craig-Bampton interior field, lies in the span (residual <= 1e-10), and
    the span lies in ALL's, so its frequencies are Rayleigh-Ritz bounded by ALL's from above
    (<= 1e-9 relative) and by the full model's from below. One massless node: its 3 static
    fields, as ALL."""
    fe_r = _redistributed(fe, face_a[:9])
    cb_psi = _craig_bampton_unsplit(fe_r, ref, face_a, 6)
    patch = build_basis(fe_r, BasisKind.CRAIG_BAMPTON, ref, face_a, 6)
    full_split = build_basis(
        fe_r, BasisKind.CRAIG_BAMPTON, ref, face_a, 6, massless_statics=MasslessStatics.ALL
    )
    nb, ns = 3 * face_a.size, 27
    P = massless_patterns(fe.mesh.nodes[face_a[:9]])
    assert P.shape == (ns, 11)
    assert 0 < patch.n_static <= 11 < full_split.n_static
    dofs = (3 * face_a[:, None] + np.arange(3)).ravel()
    assert np.array_equal(patch.psi[dofs, :nb], np.eye(nb)) and not patch.psi[dofs, nb:].any()
    interior = np.setdiff1d(np.arange(fe.n_dof), np.r_[dofs, ref.fixed_dofs])
    stat = patch.psi[interior, nb : nb + patch.n_static]
    gram = stat.T @ (fe_r.M[interior][:, interior] @ stat)
    np.testing.assert_allclose(gram, np.eye(patch.n_static), atol=1e-10)
    m, _ = reduced_matrices(fe_r, patch)
    assert np.all(m[:ns] == 0.0) and np.all(np.diag(m)[ns:] > 0)
    for basis_big, target in ((patch, cb_psi[:, :ns] @ P), (full_split, patch.psi)):
        coef = np.linalg.lstsq(basis_big.psi, target, rcond=None)[0]
        assert np.linalg.norm(basis_big.psi @ coef - target) <= 1e-10 * np.linalg.norm(target)
    lam_patch = _condensed_lam(fe_r, patch, np.arange(ns))[:8]
    lam_all = _condensed_lam(fe_r, full_split, np.arange(ns))[:8]
    assert np.all(lam_all <= lam_patch * (1 + 1e-9))
    free = ref.free_dofs(fe.n_dof)
    s_full = np.searchsorted(free, dofs[:ns])
    k_f, m_f = (a[free][:, free].toarray() for a in (fe_r.K, fe_r.M))
    assert np.all(_condensed_lam_dense(k_f, m_f, s_full)[:8] <= lam_patch * (1 + 1e-9))
    one = _redistributed(fe, face_a[:1])
    a, b = (
        build_basis(one, BasisKind.CRAIG_BAMPTON, ref, face_a, 6, massless_statics=k)
        for k in (MasslessStatics.PATCH, MasslessStatics.ALL)
    )
    assert a.n_static == b.n_static == 3


def test_split_needs_no_static_column_when_the_neighbours_are_retained(fe, ref, face_a):
    """A massless node whose element neighbours are all retained has no interior static
    field: its constraint mode already is the nodal unit vector, and no column is added."""
    x = fe.mesh.nodes[:, 0]
    deep = np.r_[face_a, np.flatnonzero(np.isclose(x, 0.01)), np.flatnonzero(np.isclose(x, 0.02))]
    fe_r = _redistributed(fe, face_a[:9])
    basis = build_basis(fe_r, BasisKind.CRAIG_BAMPTON, ref, deep, 6)
    m, _ = reduced_matrices(fe_r, basis)
    assert basis.n_static == 0 and basis.nq == 3 * deep.size + 6
    assert np.all(m[:27] == 0.0) and np.all(np.diag(m)[27:] > 0)


def _craig_bampton_unsplit(fe, ref, nodes, n_modes):
    """The textbook Craig-Bampton psi (constraint modes, fixed-interface modes) by dense
    algebra, for comparison."""
    b = (3 * np.asarray(nodes)[:, None] + np.arange(3)).ravel()
    i = np.setdiff1d(ref.free_dofs(fe.n_dof), b)
    K, M = fe.K.toarray(), fe.M.toarray()
    psi = np.zeros((fe.n_dof, b.size + n_modes))
    psi[b, np.arange(b.size)] = 1.0
    psi[i, : b.size] = -np.linalg.solve(K[np.ix_(i, i)], K[np.ix_(i, b)])
    _, v = sla.eigh(K[np.ix_(i, i)], M[np.ix_(i, i)], subset_by_index=[0, n_modes - 1])
    psi[i, b.size :] = v
    return psi
