"""What a sparse reduced body (kind mvm-sparse: reduction/kinds/mvm_sparse.py, its body
bodies/ring_body.py) will cost before it is built, read off the mesh and the region: the
guard of assembly/cost.py for the kind whose dense part is its ring, not its region.

From the mesh's cells (no FE model): the region's nodes R, its ring Gamma (the retained nodes
sharing a cell with a node of the rest that has a free DOF, as ring_positions reads K's
pattern), the exterior's free DOFs n_i, the corner c = 3 n_Gamma + n_s + n_eta, the region's
block of K (9 entries per node pair sharing a cell) and the fill of its L D L^T factor (the
symbolic analysis of that block in the integrator's elimination order, as
assembly.cost.full_factor does for full FE). Then, in 8-byte numbers:

- held at run time with the setup cache (psi's exterior rows mapped from its file, only
  the rows read resident): k_hat and M_qq (the region's block plus the dense c x c corner,
  csr), the nine G2 blocks (csr, each with the corner) and their split for the contraction
  (the stacked off-corner part, the six distinct dense corner blocks), the contact
  surface's rows of psi outside the region (dense on the corner: 16 bytes an entry as
  contact.nodes keeps them), and s factors of the bordered iteration matrix: the region's
  fill plus the dense corner's triangle (the minimum-degree order eliminates the region's
  inner DOFs first; the corner, a clique, is last);
- the cold set-up's peak (what the guard's fit is judged on, with the FE model's K, M and
  M_s), the largest of its stages: K_EE's factorization (its factor and multifrontal fronts,
  read off full FE's W's analysis in minimum-degree order, the order K_EE is factored in:
  the exterior is the body less the region), then its factor with psi's exterior rows (12
  bytes an entry, csr) being filled in blocks of columns (ring_block_bytes a block's
  right-hand sides, as many for their solutions) and the modes' dense columns; the body's
  parts made from psi in blocks of rows (the c x c products: CORNER_WORK numbers); the
  truncation guard's (K_EE cut out of K and factored again beside psi); the body with psi
  and its contact rows being gathered;
- a Newton iteration streams the bordered factor twice (forward and backward), k_hat, M_qq,
  the stacked G2 part and the packed corner blocks (4.5 c^2).

Checked against measured runs: docs/notes/2026-11-29-cost-guard.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from flexmvm.assembly.cost import BodyCost, FullFactor
from flexmvm.reduction.kinds.mvm_sparse import ring_block_bytes

#: Bytes of a number and of a csr entry (value and column index), as assembly.cost counts.
_BYTES, _CSR_BYTES = 8, 12

#: The dense c x c arrays the ring body's parts hold at once while they are made (the
#: corner blocks D, k_hat's C and their coo/csr copies: measured ~12 of them).
CORNER_WORK = 12.0
#: Static columns of the massless retained nodes (MasslessStatics.PATCH: massless_patterns'
#: 11 patterns), when some retained node is massless.
MASSLESS_COLUMNS = 11


@dataclass(frozen=True)
class RingShape:
    """The sizes a ring basis and body of a region will have (module doc)."""

    region_nodes: int
    ring_nodes: int
    extra_columns: int  # static columns of massless nodes + modes
    exterior_dof: int  # n_i: the free DOFs of the nodes outside the region
    region_k_nnz: int  # K_RR's nonzeros
    region_l_nnz: int  # stored entries of the region block's L D L^T factor
    contact_rows: int = 0  # rows of psi the contact gathers outside the region (dense on c)

    @property
    def corner(self) -> int:
        return 3 * self.ring_nodes + self.extra_columns

    @property
    def nq(self) -> int:
        return 3 * self.region_nodes + self.extra_columns


def node_graph(mesh) -> sp.csr_matrix:
    """Which nodes share a cell (n, n) pattern, diagonal included: K's pattern by nodes."""
    rows, cols = [], []
    for block in mesh.cells:
        conn = np.asarray(block.connectivity, dtype=np.int64)
        k = conn.shape[1]
        rows.append(np.repeat(conn, k, axis=1).ravel())
        cols.append(np.tile(conn, (1, k)).ravel())
    n = mesh.n_nodes
    r, c = np.concatenate(rows), np.concatenate(cols)
    g = sp.csr_matrix((np.ones(r.size, np.int8), (r, c)), shape=(n, n))
    g.sum_duplicates()
    g.data[:] = 1
    return g


def ring_shape(
    mesh, retained: np.ndarray, fixed_dofs: np.ndarray, extra: int, contact_nodes=None
) -> RingShape:
    """The RingShape of retained node ids ``retained`` on ``mesh`` under the reference
    condition's ``fixed_dofs``, with ``extra`` static and modal columns; ``contact_nodes``:
    the body's contact-surface nodes, whose rows of psi the contact gathers (contact.nodes)."""
    from flexmvm.fe.solvers.ordering import elimination_order
    from flexmvm.fe.solvers.symbolic import SymbolicFactor

    nodes = np.unique(np.asarray(retained, dtype=np.int64))
    n = mesh.n_nodes
    graph = node_graph(mesh)
    fixed = np.zeros(3 * n, dtype=bool)
    fixed[np.asarray(fixed_dofs, dtype=np.int64)] = True
    in_region = np.zeros(n, dtype=bool)
    in_region[nodes] = True
    free_node = ~fixed.reshape(n, 3).all(axis=1)
    outside = ~in_region & free_node
    reach = graph[nodes] @ outside.astype(np.int64)
    ring = int(np.count_nonzero(reach))
    free_dof = ~fixed
    free_dof.reshape(n, 3)[nodes] = False
    g_rr = sp.csr_matrix(graph[nodes][:, nodes])
    block = sp.csr_matrix(sp.kron(g_rr, np.ones((3, 3), np.int8)))
    l_nnz = 0
    if block.shape[0]:
        order = elimination_order(block)
        l_nnz = SymbolicFactor(block, order if order is not None and order.size else None).nnz
    touched = np.setdiff1d(np.asarray(contact_nodes if contact_nodes is not None else []), nodes)
    return RingShape(
        int(nodes.size),
        ring,
        int(extra),
        int(free_dof.sum()),
        int(block.nnz),
        int(l_nnz),
        3 * int(touched.size),
    )


def ring_factor_nnz(shape: RingShape) -> float:
    """Stored entries of the bordered iteration matrix's factor: the region's fill and the
    dense corner's triangle (module doc)."""
    c = shape.corner
    return shape.region_l_nnz + 0.5 * c * (c + 1)


#: Bytes a gathered row entry of psi holds in contact.nodes (int64 column, float64 value)
#: and, while it is gathered, besides (the gathered csr's int32 column; its values are kept).
_ROW_HELD, _ROW_GATHER = 16, 4


def ring_held_bytes(shape: RingShape, sizes: int = 1) -> float:
    """Bytes the ring body and its contact rows hold at run time beside psi's exterior rows
    (module doc): a run with the setup cache maps those from the cache's file and makes
    resident only the rows it reads (the contact's, counted here)."""
    c2 = float(shape.corner) ** 2
    k_rr = float(shape.region_k_nnz)
    # k_hat, M_qq (a third of K's pattern per component pair: 3 x k_rr / 9), nine G2 blocks
    parts = _CSR_BYTES * (k_rr + c2 + k_rr / 3 + c2 + k_rr + 9 * c2)
    split = _CSR_BYTES * k_rr + _BYTES * 6 * c2  # the contraction's stack and corner blocks
    rows = _ROW_HELD * float(shape.contact_rows) * shape.corner
    return parts + split + rows + _BYTES * sizes * ring_factor_nnz(shape)


def psi_bytes(shape: RingShape) -> float:
    """psi's exterior rows over the corner and the region's unit rows, csr."""
    return _CSR_BYTES * (float(shape.exterior_dof) * shape.corner + 3 * shape.region_nodes)


def ring_setup_bytes(shape: RingShape, k_ee: FullFactor, sizes: int = 1) -> float:
    """The cold set-up's peak beside the FE model (module doc), the largest of its stages:
    K_EE's factorization (its factor and fronts, ``k_ee``: the analysis in minimum-degree
    order), then its factor with psi and a block of columns (and the modes' columns); psi
    with the parts' corner arrays; the truncation guard's K_EE factorization beside psi and
    K_EE's copies; the body with psi, its contact rows gathered."""
    n_i, c = float(shape.exterior_dof), float(shape.corner)
    psi = psi_bytes(shape)
    modes = _BYTES * n_i * shape.extra_columns
    block = min(ring_block_bytes(shape.exterior_dof, shape.corner), _BYTES * n_i * c)
    factoring = _BYTES * (k_ee.stored + k_ee.fronts)
    basis = max(factoring, _BYTES * k_ee.stored + psi + 2 * block + modes)
    parts = psi + _BYTES * CORNER_WORK * c * c
    # the truncation guard (reduction/truncation.py): K_EE cut out of K (copies: rows,
    # columns, csc) and factored again beside psi
    guard = factoring + psi + 3 * _CSR_BYTES * k_ee.k_nnz
    gather = _ROW_GATHER * float(shape.contact_rows) * c
    body = psi + ring_held_bytes(shape, sizes) + gather
    return max(basis, parts, guard, body)


def ring_step_bytes(shape: RingShape) -> float:
    """Bytes a Newton iteration streams (module doc)."""
    c2 = float(shape.corner) ** 2
    k_rr = float(shape.region_k_nnz)
    mats = _CSR_BYTES * (k_rr + k_rr / 3 + 2 * c2 + k_rr)
    return 2 * _BYTES * ring_factor_nnz(shape) + mats + _BYTES * 4.5 * c2


def fe_model_bytes(full: FullFactor, n_nodes: int) -> float:
    """The FE model's resident bytes (K, M and the scalar mass M_s as csr, the mesh) that a
    reduced body's set-up holds beside its own arrays: for the fit, not the comparison (full
    FE holds it as well)."""
    return _CSR_BYTES * (full.k_nnz + full.m_nnz + full.m_nnz / 9) + 3 * _BYTES * n_nodes


def ring_cost(
    name: str, n_nodes: int, shape: RingShape, full: FullFactor, sizes: int = 1
) -> BodyCost:
    """The BodyCost of a ring body of ``shape`` on a mesh of n_nodes nodes against its
    full-FE body (``full``: the symbolic analysis, assembly.cost.full_factor, in minimum-degree
    order: K_EE's, and a lower bound of full FE's in the integrator's order, 0.54 of it on the
    263,685-DOF plate, whose own analysis would cost the guard full FE's set-up memory): memory
    what it holds at run time with the setup cache (ring_held_bytes), compared with full
    FE's as the dense kinds' is; the fit judged on the cold set-up's peak with the FE model
    (peak_bytes), K_EE's factorization read off the same analysis."""
    from flexmvm.assembly.cost import reduced_cost

    ref = reduced_cost(name, n_nodes, 0, full.k_nnz, full=full, sizes=sizes)
    held = ring_held_bytes(shape, sizes)
    # the set-up's last stage holds the body beside psi: its peak is at least the run's
    peak = ring_setup_bytes(shape, full, sizes) + fe_model_bytes(full, n_nodes)
    return BodyCost(
        name,
        6 + shape.nq,
        held,
        ref.full_dof,
        ref.full_bytes,
        ring_step_bytes(shape),
        ref.full_step_bytes,
        peak_bytes=peak,
        held="held (the ring body)",
    )
