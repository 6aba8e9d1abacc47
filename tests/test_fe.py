"""FE assembly (flexmvm.fe.assembly) and eigenmodes (flexmvm.fe.modes) on small meshes.

The meshes are built here, independently of the library's mesh generators: structured boxes
of HEX8, HEX27, TET10 (Kuhn split) and WEDGE6 + HEX8, and a curved HEX27 tube.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh

from flexmvm.errors import InputError, MeshError, SolverError
from flexmvm.fe import assemble, constrained_modes, free_modes
from flexmvm.materials import ALUMINIUM, Material
from flexmvm.mesh.mesh import CellBlock, CellType, Mesh

STEEL = Material(E=210e9, nu=0.3, rho=7800.0, name="steel")

# meshio/VTK reference positions, doubled to lattice offsets (0, 1, 2).
_HEX8 = [(0, 0, 0), (2, 0, 0), (2, 2, 0), (0, 2, 0), (0, 0, 2), (2, 0, 2), (2, 2, 2), (0, 2, 2)]
_HEX27 = _HEX8 + [
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


def _lattice(shape):
    """Node id of lattice point (i, j, k) in a grid of the given shape, and its coordinates."""
    ids = np.arange(np.prod(shape)).reshape(shape)
    ijk = np.stack(np.meshgrid(*[np.arange(s) for s in shape], indexing="ij"), axis=-1)
    return ids, ijk.reshape(-1, 3).astype(float)


def _cells(ids, n, offsets, stride, origin=(0, 0, 0)):
    """Connectivity (n_cells, len(offsets)) of a structured grid of n = (nx, ny, nz) cells
    whose first cell starts at lattice point ``origin``."""
    base = np.stack(np.meshgrid(*[np.arange(k) * stride for k in n], indexing="ij"), -1)
    base = base.reshape(-1, 3) + np.asarray(origin)
    return np.stack([ids[tuple((base + o).T)] for o in np.asarray(offsets)], axis=1)


def box_hex(n=(3, 2, 2), size=(0.3, 0.2, 0.1), order=1) -> Mesh:
    """Box [0, size] of n HEX8 (order 1) or HEX27 (order 2) cells."""
    shape = tuple(order * k + 1 for k in n)
    ids, ijk = _lattice(shape)
    nodes = ijk / (np.array(shape) - 1) * np.array(size)
    if order == 1:
        conn = _cells(ids, n, np.array(_HEX8) // 2, 1)
        return Mesh(nodes, (CellBlock(CellType.HEX8, conn),))
    conn = _cells(ids, n, _HEX27, 2)
    return Mesh(nodes, (CellBlock(CellType.HEX27, conn),))


def box_tet10(n=(2, 2, 2), size=(0.2, 0.2, 0.2)) -> Mesh:
    """Box of Kuhn-split TET10 cells (6 per cube), mid-edge nodes on the doubled lattice."""
    shape = tuple(2 * k + 1 for k in n)
    ids, ijk = _lattice(shape)
    nodes = ijk / (np.array(shape) - 1) * np.array(size)
    tets = []
    for perm in itertools.permutations(range(3)):
        path = [np.zeros(3, int)]
        for axis in perm:
            path.append(path[-1] + 2 * np.eye(3, dtype=int)[axis])
        edges = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]
        mids = [(path[a] + path[b]) // 2 for a, b in edges]
        tets.append(_cells(ids, n, path + mids, 2))
    return Mesh(nodes, (CellBlock(CellType.TET10, np.concatenate(tets)),))


def hex_wedge_mesh() -> Mesh:
    """0.2 x 0.2 x 0.3 box: 2x2x2 HEX8 cells under a layer of WEDGE6 cells (each hex of a
    2x2x1 layer split in two prisms); the blocks share the nodes of the plane z = 0.2."""
    ids, ijk = _lattice((3, 3, 4))
    hexes = _cells(ids, (2, 2, 2), np.array(_HEX8) // 2, 1)
    top = _cells(ids, (2, 2, 1), np.array(_HEX8) // 2, 1, origin=(0, 0, 2))
    wedges = np.concatenate([top[:, [0, 1, 2, 4, 5, 6]], top[:, [0, 2, 3, 4, 6, 7]]])
    return Mesh(ijk * 0.1, (CellBlock(CellType.HEX8, hexes), CellBlock(CellType.WEDGE6, wedges)))


def tube_hex27(r_in=0.5e-2, r_out=1e-2, length=0.04, n_theta=8, n_r=1, n_x=2) -> Mesh:
    """Curved HEX27 tube along x: exact radii and angles at every node (periodic in theta)."""
    i, j, k = np.meshgrid(
        np.arange(2 * n_x + 1), np.arange(2 * n_r + 1), np.arange(2 * n_theta), indexing="ij"
    )
    x = i / (2 * n_x) * length
    r = r_in + j / (2 * n_r) * (r_out - r_in)
    th = k / (2 * n_theta) * 2 * np.pi
    nodes = np.stack([x, r * np.cos(th), r * np.sin(th)], axis=-1).reshape(-1, 3)
    ids = np.arange(nodes.shape[0]).reshape(i.shape)
    base = np.stack(
        np.meshgrid(2 * np.arange(n_x), 2 * np.arange(n_r), 2 * np.arange(n_theta), indexing="ij"),
        -1,
    ).reshape(-1, 3)
    conn = np.stack(
        [
            ids[base[:, 0] + o[0], base[:, 1] + o[1], (base[:, 2] + o[2]) % (2 * n_theta)]
            for o in _HEX27
        ],
        axis=1,
    )
    return Mesh(nodes, (CellBlock(CellType.HEX27, conn),))


def boundary_mask(mesh: Mesh) -> np.ndarray:
    """Nodes on the outer surface of a box mesh or of the tube (by coordinates)."""
    x = mesh.nodes
    on_box = np.any(np.isclose(x, x.min(0)) | np.isclose(x, x.max(0)), axis=1)
    r = np.hypot(x[:, 1], x[:, 2])
    if np.isclose(r.min(), 0.5e-2) and np.isclose(r.max(), 1e-2):  # the tube
        return (
            np.isclose(r, r.min())
            | np.isclose(r, r.max())
            | np.isclose(x[:, 0], 0)
            | (np.isclose(x[:, 0], x[:, 0].max()))
        )
    return on_box


MESHES = {
    "hex8": lambda: box_hex(order=1),
    "hex27": lambda: box_hex(order=2),
    "tet10": lambda: box_tet10(),
    "hex8+wedge6": hex_wedge_mesh,
    "tube-hex27": tube_hex27,
}
BOX_VOLUME = {"hex8": 0.006, "hex27": 0.006, "tet10": 0.008, "hex8+wedge6": 0.012}


@pytest.fixture(scope="module", params=sorted(MESHES))
def case(request):
    return request.param, assemble(MESHES[request.param](), STEEL)


def test_mass_is_rho_times_volume(case):
    """Consistent mass: the shape functions sum to one, so sum(M_scalar) = rho * quadrature
    volume to round-off (rel 1e-12). The box cells all have affine maps, for which the
    Gauss rules integrate the volume exactly: the brief's 0.1 % bound is met at round-off
    (rel 1e-12 asserted)."""
    name, fe = case
    assert fe.mass == pytest.approx(STEEL.rho * fe.volume, rel=1e-12)
    if name in BOX_VOLUME:
        assert fe.volume == pytest.approx(BOX_VOLUME[name], rel=1e-12)
    kron = sp.kron(fe.M_scalar, sp.identity(3), format="csr")
    assert abs(fe.M - kron).max() == 0.0  # M == kron(M_scalar, I3) exactly


def test_curved_hex27_integrated_on_true_geometry():
    """Tube r 5..10 mm, 16 quadratic cells around: the isoparametric volume must match
    pi (r_o^2 - r_i^2) L to 1e-4 (measured 5.0e-5: quadratic arcs); cells with straight edges
    between the same nodes (32 chords) would be 6.4e-3 short, so a mid-node mapped to the
    wrong place or a straight-sided integration fails this. Mass = rho * volume, rel 1e-12."""
    mesh = tube_hex27(n_theta=16)
    fe = assemble(mesh, STEEL)
    exact = np.pi * (1e-2**2 - 0.5e-2**2) * 0.04
    assert abs(fe.volume / exact - 1) < 1e-4
    assert fe.mass == pytest.approx(STEEL.rho * fe.volume, rel=1e-12)


def _skfem_reference(mesh_skfem, elem, nodes):
    """K, M_scalar assembled by scikit-fem itself (its own DOF numbering and forms),
    renumbered to our nodes by matching coordinates (test only)."""
    import skfem
    from skfem.models.elasticity import linear_elasticity

    basis = skfem.Basis(mesh_skfem, elem)
    vbasis = basis.with_element(skfem.ElementVector(elem))
    lam, mu = STEEL.lame
    k = skfem.asm(linear_elasticity(lam, mu), vbasis)
    m = skfem.asm(skfem.BilinearForm(lambda u, v, w: STEEL.rho * u * v), basis)
    locs = basis.doflocs.T
    dist = np.linalg.norm(locs[:, None, :] - nodes[None, :, :], axis=2)
    node_of = dist.argmin(axis=1)
    assert np.all(dist.min(axis=1) < 1e-12)
    vnode = 3 * node_of[basis.element_dofs]
    vmap = np.empty(vbasis.N, dtype=int)
    for d in range(3):
        vmap[vbasis.element_dofs[d::3]] = vnode + d
    p_s = sp.csr_matrix((np.ones(len(node_of)), (node_of, np.arange(len(node_of)))))
    p_v = sp.csr_matrix((np.ones(vbasis.N), (vmap, np.arange(vbasis.N))))
    return p_v @ k @ p_v.T, p_s @ m @ p_s.T


@pytest.mark.parametrize("order", [1, 2])
def test_matches_scikit_fem_assembly(order):
    """Our DOF mapping + batched element kernel against scikit-fem's own asm() with
    linear_elasticity on MeshHex1/MeshHex2 (affine box: both integrate exactly), matched by
    coordinates: equal to round-off (rel 1e-12 of the largest entry)."""
    import skfem

    size, n = (0.3, 0.2, 0.1), (3, 2, 2)
    ours = assemble(box_hex(n, size, order), STEEL)
    axes = [np.linspace(0, s, k + 1) for s, k in zip(size, n, strict=True)]
    m1 = skfem.MeshHex1.init_tensor(*axes)
    msk = m1 if order == 1 else skfem.MeshHex2.from_mesh(m1)
    elem = skfem.ElementHex1() if order == 1 else skfem.ElementHex2()
    k_ref, m_ref = _skfem_reference(msk, elem, ours.mesh.nodes)
    assert abs(ours.K - k_ref).max() <= 1e-12 * abs(k_ref).max()
    assert abs(ours.M_scalar - m_ref).max() <= 1e-12 * abs(m_ref).max()


def test_stiffness_symmetric_and_element_kernel_symmetric(case):
    """K is exactly symmetric (symmetrised) and the raw element kernel is symmetric to
    round-off (rel 1e-13) before that, so symmetrising hides no modelling error."""
    from flexmvm.fe.assembly import _element_stiffness, block_basis, shape_arrays

    _, fe = case
    assert abs(fe.K - fe.K.T).max() == 0.0
    block = fe.mesh.cells[0]
    basis, _ = block_basis(fe.mesh.nodes, block)
    _, grad, dx = shape_arrays(basis, slice(0, 4))
    ke = _element_stiffness(grad, dx, *STEEL.lame)
    assert np.max(np.abs(ke - np.swapaxes(ke, 1, 2))) <= 1e-13 * np.max(np.abs(ke))


def test_patch_test_uniform_strain(case):
    """u = eps X (general eps: strain + rotation) is in every element's span, so the
    internal force K u vanishes at interior nodes: |f_interior| <= 1e-12 |K|max |u|max."""
    _, fe = case
    eps = np.array([[1.0, 0.3, 0.2], [0.1, -0.5, 0.4], [0.0, 0.25, 0.7]]) * 1e-3
    u = (fe.mesh.nodes @ eps.T).ravel()
    f = (fe.K @ u).reshape(-1, 3)
    interior = ~boundary_mask(fe.mesh)
    assert interior.sum() >= 2
    scale = abs(fe.K).max() * np.abs(u).max()
    assert np.abs(f[interior]).max() <= 1e-12 * scale


def test_exactly_six_rigid_modes(case):
    """Free-free: six zero-energy modes (omega^2 below 1e-8 of the first elastic one, which
    is what shift-invert round-off leaves), the 7th clearly elastic (> 1e-3 of the 8th,
    here they are of the same order); modes M-orthonormal to 1e-10."""
    _, fe = case
    freqs, modes = free_modes(fe, 8)
    lam = (2 * np.pi * freqs) ** 2
    assert np.all(lam[:6] <= 1e-8 * lam[6])
    assert lam[6] > 1e-3 * lam[7] > 0
    gram = modes.T @ (fe.M @ modes)
    assert np.abs(gram - np.eye(8)).max() < 1e-10


def test_lumped_mass(case):
    """HRZ lumping: diagonal, all entries > 0 (also for the TET10/HEX27 corner nodes,
    where row-sum lumping fails), total equal to the consistent total (rel 1e-12)."""
    _, fe = case
    lumped = assemble(fe.mesh, STEEL, lumped=True)
    d = lumped.M_scalar.diagonal()
    assert abs(lumped.M_scalar - sp.diags(d)).max() == 0.0
    assert d.min() > 0
    assert lumped.mass == pytest.approx(fe.mass, rel=1e-12)
    assert abs(lumped.K - fe.K).max() == 0.0


def test_nonconforming_mesh_raises():
    """Two HEX27 cells that name different nodes for their shared face centre."""
    mesh = box_hex((2, 1, 1), (0.2, 0.1, 0.1), order=2)
    conn = mesh.cells[0].connectivity.copy()
    nodes = np.vstack([mesh.nodes, mesh.nodes[conn[1, 20]]])
    conn[1, 20] = len(nodes) - 1  # cell 1's x=0 face centre, shared with cell 0
    bad = Mesh(nodes, (CellBlock(CellType.HEX27, conn),))
    with pytest.raises(MeshError, match="non-conforming"):
        assemble(bad, STEEL)


def test_mode_solver_errors():
    """Bad shift, too many modes, and an indefinite 'stiffness' are reported, not hidden;
    every mode (n_modes = the DOFs) is a dense solve, M-orthonormal."""
    fe = assemble(box_hex(order=1), ALUMINIUM)
    with pytest.raises(InputError):
        free_modes(fe, 4, sigma=1.0)
    with pytest.raises(InputError):
        free_modes(fe, fe.n_dof + 1)
    freqs, phi = free_modes(fe, fe.n_dof)
    assert freqs.shape == (fe.n_dof,) and np.all(np.diff(freqs) >= 0)
    np.testing.assert_allclose(phi.T @ (fe.M @ phi), np.eye(fe.n_dof), atol=1e-9)
    fixed = np.arange(12)  # nodes 0..3 clamped: no rigid motion left
    with pytest.raises(SolverError, match="negative eigenvalue"):
        constrained_modes(fe.M, -fe.K, fixed, 3)


def test_constrained_modes_zero_at_fixed_dofs():
    """Clamped modes: zero rows at the fixed DOFs, positive frequencies, M-normalised, and
    equal (rel 1e-9) to a dense solve of the 108-DOF reduced problem."""
    import scipy.linalg as sla

    fe = assemble(box_hex(order=1), ALUMINIUM)
    fixed = np.flatnonzero(np.repeat(np.isclose(fe.mesh.nodes[:, 0], 0.0), 3))
    freqs, modes = constrained_modes(fe.M, fe.K, fixed, 5)
    assert np.all(modes[fixed] == 0.0) and freqs.min() > 0
    free = np.setdiff1d(np.arange(fe.n_dof), fixed)
    lam = sla.eigh(fe.K[free][:, free].toarray(), fe.M[free][:, free].toarray(), eigvals_only=True)[
        :5
    ]
    assert np.allclose((2 * np.pi * freqs) ** 2, lam, rtol=1e-9)
    assert np.allclose(np.diag(modes.T @ fe.M @ modes), 1.0, rtol=1e-10)


def test_sparse_lu_spd_ordering_and_general_path():
    """fe.modes.factor: the SPD path (symmetric minimum-degree ordering, diagonal pivots) and
    SuperLU's general path solve the same SPD system to round-off (tolerance 1e-12 relative:
    the matrix is well conditioned, cond < 1e3); an exactly singular matrix is a SolverError,
    not a RuntimeError."""
    from flexmvm.fe.modes import factor

    rng = np.random.default_rng(3)
    B = sp.random(200, 200, density=0.02, random_state=rng, format="csr")
    A = (B.T @ B + 10.0 * sp.eye(200)).tocsc()
    b = rng.standard_normal((200, 3))
    for spd in (True, False):
        x = factor(A, spd=spd)(b)
        assert np.linalg.norm(A @ x - b) <= 1e-12 * np.linalg.norm(b)
    with pytest.raises(SolverError, match="failed"):
        factor(sp.csc_matrix((4, 4)))


def test_spd_solver_choice(monkeypatch):
    """spd_solver takes fe.cholesky's L D L^T (solved by fe.ldl) from CHOLESKY_MIN_N rows,
    SuperLU below; SuperLU's LU also when fe.cholesky refuses the matrix: a symmetric
    indefinite one (a pivot not positive) or an unsymmetric one (its lower triangle factors,
    but the solve's backward error against the matrix fails the check). Every choice solves
    the system to a backward error of 1e-12 (stable solves give ~1e-16)."""
    from flexmvm.fe.solvers import spd as modes
    from flexmvm.fe.solvers.ldl import SupernodalLDL

    fe = assemble(box_hex(n=(4, 2, 2)), STEEL)
    free = np.arange(12, fe.n_dof)
    A = sp.csc_matrix(fe.K[free][:, free])
    b = np.random.default_rng(1).standard_normal(A.shape[0])
    monkeypatch.setattr(modes, "CHOLESKY_MIN_N", A.shape[0])
    many = modes.spd_solver(A)
    monkeypatch.setattr(modes, "CHOLESKY_MIN_N", A.shape[0] + 1)
    few = modes.spd_solver(A)
    assert isinstance(many.__self__, SupernodalLDL)
    assert not isinstance(few.__self__, SupernodalLDL)
    monkeypatch.setattr(modes, "CHOLESKY_MIN_N", 1)
    U = sp.csc_matrix(A + sp.triu(A, 1) * 1e-3)  # unsymmetric
    shift = 0.5 * float(eigsh(A, k=1, return_eigenvectors=False)[0])
    S = sp.csc_matrix(A - shift * sp.eye(A.shape[0]))  # symmetric indefinite
    refused = [modes.spd_solver(U), modes.spd_solver(S)]
    assert not any(isinstance(r.__self__, SupernodalLDL) for r in refused)
    for solve, M in ((many, A), (few, A), (refused[0], U), (refused[1], S)):
        x = solve(b)
        scale = abs(M).sum(axis=1).max() * np.abs(x).max() + np.abs(b).max()
        assert np.abs(M @ x - b).max() <= 1e-12 * scale
