"""Sparse mass and stiffness matrices of a linear-elastic body (scikit-fem elements).

For a mesh with n nodes the matrices are 3n x 3n, numbered node-major (DOF ``3*k + d``):

    K_ab = sum_e  int_e  B_a^T D B_b dV        (isotropic Hooke law, Lame lambda, mu)
    M    = kron(M_scalar, I3),   M_scalar_ab = sum_e int_e rho N_a N_b dV

Each cell block gets its own scikit-fem mesh and CellBasis (shape functions, isoparametric
map, Gauss rule); the element matrices are batched array products of those values (one
matmul per chunk of cells instead of skfem's loop over the 81 x 81 local DOF pairs of a
HEX27, ~10x faster), scattered to our node ids and added into the global matrices (blocks
may share nodes, e.g. hex8 + wedge6). tests/test_fe.py checks K and M_scalar against
scikit-fem's own ``asm(linear_elasticity)`` to round-off.

DOF mapping (by topology, never by physical coordinates): the local DOFs of a skfem element
(vertices, then one DOF per edge in ``refdom.edges`` order, per facet in ``refdom.facets``
order, per interior) sit at reference-element points given by ``element.doflocs``; meshio /
VTK local nodes sit at their cell type's ``reference_nodes`` (mesh/cells). Matching these exact
reference points (values in {0, 1/2, 1}) gives a fixed local permutation per cell type.
The skfem connectivity ``t`` is built from our corner nodes in that order; skfem keeps ``t``
as given (``sort_t=False``, checked), so skfem's edge/facet/interior DOF of element e is our
mid-edge/mid-face/centre node of cell e. Every skfem DOF shared by several cells must receive
the same node from all of them (checked: MeshError for a non-conforming mesh). Higher-order
cells (HEX27, TET10) are integrated on their true, possibly curved, isoparametric geometry:
the skfem ``doflocs`` are our node coordinates in skfem DOF order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import skfem
from skfem.quadrature import get_quadrature, get_quadrature_line, get_quadrature_tri

from flexmvm.errors import MeshError
from flexmvm.materials import Material
from flexmvm.mesh.mesh import CellBlock, CellType, Mesh


@dataclass(frozen=True)
class _SkfemCell:
    """How scikit-fem handles one of our cell types.

    linear_mesh: skfem mesh class holding the corner topology; mesh: the class integrated on
    (isoparametric, carries all nodes); element: scalar element; intorder: quadrature degree
    (full integration: 2x2x2 Gauss for HEX8, 3x3x3 for HEX27, degree 4 triangle x 3-point
    line for WEDGE6, degree 2 / 4 for TET4 / TET10; mass exact for straight-sided cells).
    """

    linear_mesh: type
    mesh: type
    element: type[skfem.Element]
    intorder: int

    def quadrature(self) -> tuple[np.ndarray, np.ndarray]:
        """Reference points (3, nqp) and weights (nqp,) of degree ``intorder``.

        The wedge rule is built here as triangle x line: scikit-fem 12.0.2's RefWedge rule
        pairs triangle x- and y-coordinates independently and its weights sum to 1/4
        instead of the reference volume 1/2.
        """
        if self.element.refdom is not skfem.refdom.RefWedge:
            return get_quadrature(self.element.refdom, self.intorder)
        xt, wt = get_quadrature_tri(self.intorder)
        xl, wl = get_quadrature_line(self.intorder)
        pts = np.vstack([np.repeat(xt, xl.shape[1], axis=1), np.tile(xl, xt.shape[1])])
        return pts, np.outer(wt, wl).ravel()


#: Cells per chunk of element matrices (a HEX27 stiffness is 81 x 81 doubles = 52 kB).
ELEMENT_CHUNK = 1024

#: The fe stage's part of each cell type (its mesh/cells spec holds the rest), keyed by CellType.
_SKFEM: dict[CellType, _SkfemCell] = {
    CellType.HEX8: _SkfemCell(skfem.MeshHex1, skfem.MeshHex1, skfem.ElementHex1, 3),
    CellType.HEX27: _SkfemCell(skfem.MeshHex1, skfem.MeshHex2, skfem.ElementHex2, 5),
    CellType.WEDGE6: _SkfemCell(skfem.MeshWedge1, skfem.MeshWedge1, skfem.ElementWedge1, 4),
    CellType.TET4: _SkfemCell(skfem.MeshTet1, skfem.MeshTet1, skfem.ElementTetP1, 2),
    CellType.TET10: _SkfemCell(skfem.MeshTet1, skfem.MeshTet2, skfem.ElementTetP2, 4),
}


@dataclass(frozen=True)
class FEModel:
    """Assembled linear-elastic FE model of one body (SI units).

    M, K: (3n, 3n) csr [kg], [N/m], node-major DOFs; M == kron(M_scalar, I3).
    M_scalar: (n, n) csr [kg], rho-weighted scalar mass (HRZ-diagonal if lumped).
    mass: total mass [kg] = sum(M_scalar); volume: quadrature volume [m^3].
    """

    mesh: Mesh
    material: Material
    M: sp.csr_matrix
    K: sp.csr_matrix
    M_scalar: sp.csr_matrix
    mass: float
    volume: float
    lumped: bool = False

    @property
    def n_dof(self) -> int:
        return self.K.shape[0]


def local_permutation(cell_type: CellType) -> np.ndarray:
    """skfem local DOF i -> meshio/VTK local node index, shape (nodes_per_cell,).

    Found by matching the exact reference-element points of both numberings. Raises
    MeshError if the two node sets differ (a cell type skfem cannot represent).
    """
    elem = _SKFEM[cell_type].element()
    skl = np.asarray(elem.doflocs, dtype=float)
    vtk = cell_type.spec.reference_nodes
    dist = np.abs(skl[:, None, :] - vtk[None, :, :]).sum(axis=2)
    perm = np.argmin(dist, axis=1)
    if (
        skl.shape != vtk.shape
        or not np.all(dist[np.arange(len(perm)), perm] == 0)
        or len(np.unique(perm)) != len(perm)
    ):
        raise MeshError(f"cannot map scikit-fem {type(elem).__name__} DOFs to {cell_type.value}")
    return perm


def block_basis(nodes: np.ndarray, block: CellBlock) -> tuple[skfem.CellBasis, np.ndarray]:
    """skfem scalar basis of one block and its DOF -> node-id map, shape (n_skfem_dofs,).

    Raises MeshError if neighbouring cells disagree on a shared mid-edge/face node.
    """
    kind = _SKFEM[block.cell_type]
    perm = local_permutation(block.cell_type)
    elem = kind.element()
    n_vert = elem.refdom.nnodes
    local_nodes = block.connectivity[:, perm]  # (ne, nloc) our ids, skfem order
    corner_ids, t = np.unique(local_nodes[:, :n_vert], return_inverse=True)
    t = np.ascontiguousarray(t.reshape(-1, n_vert).T.astype(np.int32))
    lin = kind.linear_mesh(np.ascontiguousarray(nodes[corner_ids].T), t)
    if not np.array_equal(lin.t, t):
        raise MeshError(f"scikit-fem reordered the {block.cell_type.value} connectivity")
    if kind.mesh is kind.linear_mesh:
        return skfem.CellBasis(lin, elem, quadrature=kind.quadrature()), corner_ids
    element_dofs = skfem.assembly.Dofs(lin, elem).element_dofs
    dof_to_node = np.full(int(element_dofs.max()) + 1, -1, dtype=np.int64)
    dof_to_node[element_dofs] = local_nodes.T
    if dof_to_node.min() < 0 or not np.array_equal(dof_to_node[element_dofs], local_nodes.T):
        raise MeshError(
            f"{block.cell_type.value} cells disagree on shared mid-edge/face nodes "
            "(non-conforming mesh)"
        )
    high = kind.mesh(np.ascontiguousarray(nodes[dof_to_node].T), t)
    basis = skfem.CellBasis(high, elem, quadrature=kind.quadrature())
    if not np.array_equal(basis.element_dofs, element_dofs):
        raise MeshError(f"scikit-fem renumbered the {block.cell_type.value} DOFs")
    return basis, dof_to_node


def _hrz_diagonal(basis: skfem.CellBasis, rho: float) -> np.ndarray:
    """Element-wise HRZ lumped masses (Hinton, Rock, Zienkiewicz 1976), (nloc, ne) [kg].

    m_ea = (int_e rho N_a^2) * m_e / sum_b int_e rho N_b^2,  m_e = int_e rho: all > 0 and
    each cell keeps its mass.
    """
    dx = basis.dx  # (ne, nqp)
    diag = np.stack([np.sum(np.asarray(b[0]) ** 2 * dx, axis=1) for b in basis.basis])
    return diag * (rho * dx.sum(axis=1) / diag.sum(axis=0))


def shape_arrays(basis: skfem.CellBasis, cells: slice) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Shape functions at the quadrature points of the cells ``cells``, from scikit-fem.

    Returns N (ne, nloc, nqp), grad N (ne, nloc, 3, nqp) [1/m] and dx = |det J| w (ne, nqp)
    [m^3], local DOFs in skfem order.
    """
    n = np.stack([np.asarray(b[0])[cells] for b in basis.basis], axis=1)
    g = np.stack([np.moveaxis(b[0].grad[:, cells], 0, 1) for b in basis.basis], axis=1)
    return n, g, basis.dx[cells]


def _element_mass(n: np.ndarray, dx: np.ndarray, rho: float) -> np.ndarray:
    """Consistent scalar element masses m_ab = rho sum_q N_a N_b dx_q, (ne, nloc, nloc) [kg]."""
    return rho * np.matmul(n * dx[:, None, :], np.swapaxes(n, 1, 2))


def _element_stiffness(g: np.ndarray, dx: np.ndarray, lam: float, mu: float) -> np.ndarray:
    """Element stiffness (ne, 3 nloc, 3 nloc) [N/m], local DOF 3a + i (node a, component i).

    With S_aibj = sum_q dN_a/dx_i dN_b/dx_j dx_q (isotropic Hooke law, eps:sigma):
    K_aibj = lam S_aibj + mu S_ajbi + mu delta_ij sum_k S_akbk.
    """
    ne, nloc = g.shape[:2]
    flat = g.reshape(ne, 3 * nloc, -1)
    s = np.matmul(flat * dx[:, None, :], np.swapaxes(flat, 1, 2)).reshape(ne, nloc, 3, nloc, 3)
    k = lam * s + mu * np.swapaxes(s, 2, 4)
    trace = np.einsum("eakbk->eab", s)
    for i in range(3):
        k[:, :, i, :, i] += mu * trace
    return k.reshape(ne, 3 * nloc, 3 * nloc)


def scatter(blocks: np.ndarray, ids: np.ndarray, n: int) -> sp.csr_matrix:
    """Sum element matrices blocks (ne, p, p) with global ids (ne, p) into an (n, n) csr."""
    p = ids.shape[1]
    rows = np.repeat(ids, p, axis=1).ravel()
    cols = np.tile(ids, (1, p)).ravel()
    return sp.csr_matrix((blocks.ravel(), (rows, cols)), shape=(n, n))


def _assemble_block(
    nodes: np.ndarray, block: CellBlock, material: Material, lumped: bool
) -> tuple[sp.csr_matrix, sp.csr_matrix, float]:
    """Scalar mass (n x n), stiffness (3n x 3n) and volume of one cell block.

    Cells are processed in chunks of ELEMENT_CHUNK so element matrices never fill memory.
    """
    n = len(nodes)
    lam, mu = material.lame
    basis, dof_to_node = block_basis(nodes, block)
    cell_nodes = dof_to_node[basis.element_dofs.T]  # (ne, nloc) our node ids
    m_sum, k_sum, volume = sp.csr_matrix((n, n)), sp.csr_matrix((3 * n, 3 * n)), 0.0
    if lumped:
        vals = _hrz_diagonal(basis, material.rho)
        ids = cell_nodes.T.ravel()
        m_sum = sp.csr_matrix((vals.ravel(), (ids, ids)), shape=(n, n))
    for start in range(0, len(cell_nodes), ELEMENT_CHUNK):
        sub = slice(start, start + ELEMENT_CHUNK)
        nval, grad, dx = shape_arrays(basis, sub)
        volume += float(dx.sum())
        if not lumped:
            m_sum = m_sum + scatter(_element_mass(nval, dx, material.rho), cell_nodes[sub], n)
        vec_ids = (3 * cell_nodes[sub][:, :, None] + np.arange(3)).reshape(len(dx), -1)
        k_sum = k_sum + scatter(_element_stiffness(grad, dx, lam, mu), vec_ids, 3 * n)
    return m_sum, k_sum, volume


def assemble(mesh: Mesh, material: Material, lumped: bool = False) -> FEModel:
    """Assemble consistent (or HRZ-lumped) mass and stiffness of ``mesh`` (see module doc).

    mesh: Mesh with HEX8, HEX27, WEDGE6, TET4 and/or TET10 blocks; material: isotropic.
    Shape functions, isoparametric maps and Gauss rules are scikit-fem's; the element
    matrices are batched products of them (``_element_mass``, ``_element_stiffness``).
    Returns FEModel with M, K (3n x 3n csr) and M_scalar (n x n csr).
    Raises MeshError for a cell type skfem cannot map or a non-conforming mesh.
    """
    n = mesh.n_nodes
    m_scalar, stiffness, volume = sp.csr_matrix((n, n)), sp.csr_matrix((3 * n, 3 * n)), 0.0
    for block in mesh.cells:
        if len(block.connectivity) == 0:
            continue
        m_b, k_b, v_b = _assemble_block(mesh.nodes, block, material, lumped)
        m_scalar, stiffness, volume = m_scalar + m_b, stiffness + k_b, volume + v_b
    if volume == 0.0:
        raise MeshError("mesh has no cells to assemble")
    m_scalar = sp.csr_matrix(0.5 * (m_scalar + m_scalar.T))
    stiffness = sp.csr_matrix(0.5 * (stiffness + stiffness.T))
    m_full = sp.csr_matrix(sp.kron(m_scalar, sp.identity(3, format="csr"), format="csr"))
    return FEModel(
        mesh=mesh,
        material=material,
        M=m_full,
        K=stiffness,
        M_scalar=m_scalar,
        mass=float(m_scalar.sum()),
        volume=volume,
        lumped=lumped,
    )


__all__ = ["FEModel", "assemble", "block_basis", "local_permutation", "shape_arrays"]
