"""The sparse reduced body (kind ``mvm-sparse``): Craig-Bampton with the region's ring as its
only boundary, a reduced body that stays sparse where its FE model is (DESIGN.md, "A reduced
body that pays"); its body is built by bodies/ring_body.py.

Split the nodes into the retained region R (kept nodal), its ring Gamma (the region's nodes
that share an element with the rest) and the exterior E (the free DOFs of the other nodes).
The exterior couples to the region only through the ring (K_E,R\\Gamma = 0), so the
Craig-Bampton basis of R (Craig and Bampton 1968) is

    u_R = q_R,      u_E = Phi_E,Gamma q_Gamma + S_E s + Phi_E eta,
    Phi_E,Gamma = -K_EE^-1 K_E,Gamma   (static constraint modes: one per RING DOF)

with the fixed-interface modes Phi_E of E and, for massless retained nodes, their static
columns S_E (MasslessStatics). The constraint mode of a region DOF off the
ring is exactly zero on E, so this is kind mvm's basis (reduction/kinds/mvm.py) column by
column (same coordinates q = [u_R, s, eta], same span): only its storage differs. Psi is kept
as a csr matrix whose dense part is the E rows of the corner columns, c = [the ring's DOFs,
s, eta] (n_c = 3 n_Gamma + n_s + n_eta): it grows with the region's surface, not its volume.
One solve with K_EE's factor gives every constraint mode (3 n_Gamma right-hand sides, not
3 n_R), and the same factor is the shift-invert operator of the modes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
import scipy.sparse as sp
from threadpoolctl import threadpool_limits

from flexmvm.fe.assembly import FEModel
from flexmvm.fe.modes import solver_pool, spd_solver
from flexmvm.reduction.kinds.mvm import (
    CraigBampton,
    fixed_interface_modes,
    massless_mask,
    massless_patterns,
    node_dofs,
    static_columns,
)
from flexmvm.reduction.kinds.registry import ModelKind
from flexmvm.reduction.kinds.spec import Basis, BasisRequest, MasslessStatics
from flexmvm.reduction.reference_condition import ReferenceCondition


@dataclass(frozen=True)
class RingCraigBampton(CraigBampton):
    """Kind mvm's columns and answers (n_static), psi csr; no leading-columns cut (its parts
    are not the dense ones leading_columns cuts). Its body: bodies/ring_body.py attaches the
    builder (body_builder) when the bodies stage is imported; without it the generic sparse
    path would build a correct, slower body."""

    name: str = "mvm-sparse"
    cuts_modes: bool = False

    def build_basis(self, request: BasisRequest) -> Basis:
        return ring_basis(
            request.fe,
            request.reference,
            request.nodes,
            request.n_modes,
            MasslessStatics(request.massless_statics),
        )

    def cost_columns(self, n_retained: int, n_modes: int) -> int | None:
        # not costed by the dense estimate (assembly/cost.py: 8 nq^2 + 3 n nq numbers): its
        # dense part is the corner, which the region's node count does not give; the
        # assembly stage costs it by its ring (assembly/cost_sparse.py)
        return None


SPEC = RingCraigBampton()


#: Largest bytes of one block of the constraint modes' right-hand sides (as many again for
#: their solutions): the ring's columns are solved a block at a time and written where they
#: are kept (psi's exterior rows), so the set-up never holds all of them twice.
RING_BLOCK_BYTES = 256e6


def ring_block_bytes(n_rows: int, n_corner: int) -> float:
    """Bytes of one block of right-hand sides for n_rows exterior rows and n_corner corner
    columns: an eighth of psi's exterior rows (12 bytes an entry), from 16 MB up to
    RING_BLOCK_BYTES (each block is a pass over K_EE's factor: fewer on a big part)."""
    return min(RING_BLOCK_BYTES, max(16e6, 12.0 * n_rows * n_corner / 8))


def ring_basis(
    fe: FEModel,
    reference: ReferenceCondition,
    nodes: np.ndarray,
    n_modes: int,
    statics_kind: MasslessStatics = MasslessStatics.PATCH,
) -> Basis:
    """The ring basis of retained ``nodes`` (validated ids) with ``n_modes`` fixed-interface
    modes: psi (n_dof, 3 nb + n_static + n_modes) csr (ring_psi's layout), its exterior rows
    written block by block as they are solved (ring_solve)."""
    held: dict = {}

    def columns(interior: np.ndarray, corner: np.ndarray, ring: np.ndarray):
        nq = 3 * nodes.size + corner.size - 3 * ring.size
        empty = RingColumns(interior, corner, np.empty((0, corner.size)), ring)
        held["psi"] = psi = ring_psi(fe.n_dof, nodes, empty, nq)
        starts = psi.indptr[interior].astype(np.int64)
        return lambda j0, values: _write_exterior(starts, j0, values, psi.data)

    _, freqs = ring_solve(fe, reference, nodes, n_modes, statics_kind, columns)
    return Basis(ModelKind("mvm-sparse"), held["psi"], nodes, n_modes, reference, freqs)


@numba.njit(cache=True)
def _write_exterior(starts, j0, values, data):  # pragma: no cover - compiled
    """Corner columns j0.. of the exterior rows: data[starts[i] + j0 + j] = values[i, j]."""
    for i in range(values.shape[0]):
        p = starts[i] + j0
        for j in range(values.shape[1]):
            data[p + j] = values[i, j]


@dataclass(frozen=True)
class RingColumns:
    """The dense part of a ring basis: psi[interior][:, corner] = B.

    interior: (n_i,) the exterior's free DOFs (sorted); corner: (n_c,) the coordinates whose
    columns reach into E: the ring nodes' DOF columns (node-major, in retained-node order),
    then the static and modal columns; stored: (n_i, n_c) their exterior rows [m per unit
    q], or None where they are read from ``psi`` (ring_psi's layout) a block of rows at a
    time (rows); ring: (n_Gamma,) positions of the ring nodes in the retained-node order.
    """

    interior: np.ndarray
    corner: np.ndarray
    stored: np.ndarray | None
    ring: np.ndarray
    psi: sp.csr_matrix | None = None

    @property
    def n_ring_dofs(self) -> int:
        return 3 * self.ring.size

    @property
    def B(self) -> np.ndarray:
        """Every exterior row (n_i, n_c): ``stored``, or gathered from psi."""
        if self.stored is not None:
            return self.stored
        return self.rows(np.arange(self.interior.size))

    def rows(self, at: np.ndarray) -> np.ndarray:
        """B[at] (len(at), n_c) for positions ``at`` of interior."""
        if self.stored is not None:
            return self.stored[at]
        assert self.psi is not None
        out = np.empty((at.size, self.corner.size))
        psi = self.psi
        _gather_exterior(psi.indptr, psi.indices, psi.data, self.interior[at], self.corner, out)
        return out


def ring_positions(fe: FEModel, interior: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Positions (in the retained order) of the retained nodes that share an element with an
    exterior DOF: those whose DOFs have a structural entry in K[interior, b]."""
    k_ib = sp.csc_matrix(fe.K[interior][:, b])
    touched = np.flatnonzero(np.diff(k_ib.indptr))
    return np.unique(touched // 3)


def ring_columns(
    fe: FEModel,
    reference: ReferenceCondition,
    nodes: np.ndarray,
    n_modes: int,
    statics_kind: MasslessStatics = MasslessStatics.PATCH,
) -> tuple[RingColumns, int, np.ndarray]:
    """The corner columns of the ring basis of retained ``nodes`` (validated ids) with
    ``n_modes`` fixed-interface modes, held as a dense B: (RingColumns, number of static
    columns of the massless nodes, mode frequencies [Hz]) (ring_solve)."""
    held: dict = {}

    def columns(interior: np.ndarray, corner: np.ndarray, ring: np.ndarray):
        B = np.empty((interior.size, corner.size))
        held["cols"] = RingColumns(interior, corner, B, ring)

        def write(j0: int, values: np.ndarray) -> None:
            B[:, j0 : j0 + values.shape[1]] = values

        return write

    n_s, freqs = ring_solve(fe, reference, nodes, n_modes, statics_kind, columns)
    return held["cols"], n_s, freqs


def ring_solve(
    fe: FEModel,
    reference: ReferenceCondition,
    nodes: np.ndarray,
    n_modes: int,
    statics_kind: MasslessStatics,
    columns,
) -> tuple[int, np.ndarray]:
    """The corner columns of the ring basis of retained ``nodes``, each written once where
    it is kept: ``columns(interior, corner, ring)`` makes the store and returns
    write(j0, values) for corner columns j0.. (values (n_i, k)). K_EE is factored once
    (fe.modes.spd_solver); the massless ring nodes' static fields first (their static
    columns fix the corner's size), the modes, then the ring's constraint modes in blocks of
    ring_block_bytes: (number of static columns, mode frequencies [Hz])."""
    b = node_dofs(nodes)
    interior = np.setdiff1d(reference.free_dofs(fe.n_dof), b)
    ring = ring_positions(fe, interior, b)
    ring_cols = node_dofs(ring)  # q columns 3 pos + d of the ring nodes
    k_rows = fe.K[interior]
    massless = np.flatnonzero(massless_mask(fe, nodes))
    split = node_dofs(massless)
    on_ring = np.isin(split, ring_cols)
    at = np.searchsorted(ring_cols, split[on_ring])  # a massless node's column: its unit
    solved = np.setdiff1d(np.arange(ring_cols.size), at)  # vector alone, zero on E
    # one BLAS thread, as reduction.basis.build_basis: the many-right-hand-side solve calls
    # BLAS once per supernode, ~10x slower threaded when other jobs share the cores
    with threadpool_limits(limits=1, user_api="blas"), solver_pool() as pool:
        k_ii = k_rows[:, interior]
        solve = spd_solver(k_ii, pool)
        fields = np.zeros((interior.size, split.size))
        if at.size:
            fields[:, on_ring] = -np.asarray(solve(k_rows[:, b[ring_cols[at]]].toarray()))
        if statics_kind is MasslessStatics.PATCH and massless.size:
            fields = fields @ massless_patterns(fe.mesh.nodes[nodes[massless]])
        extra = static_columns(fe, interior, fields)
        del fields
        modes, freqs = fixed_interface_modes(fe, interior, k_ii, solve, n_modes)
        del k_ii
        n_s, n_g = extra.shape[1], ring_cols.size
        corner = np.concatenate([ring_cols, b.size + np.arange(n_s + n_modes)]).astype(np.int64)
        write = columns(interior, corner, ring)
        write(n_g, extra)
        write(n_g + n_s, modes)
        del extra, modes
        write_zero = np.zeros((interior.size, 1))
        for j in at:
            write(int(j), write_zero)
        block_bytes = ring_block_bytes(interior.size, corner.size)
        step = max(1, int(block_bytes // (8 * max(interior.size, 1))))
        for k in range(0, solved.size, step):
            block = solved[k : k + step]
            x = np.asarray(solve(k_rows[:, b[ring_cols[block]]].toarray()))
            np.negative(x, out=x)
            for run in _runs(block):
                write(int(block[run[0]]), x[:, run[0] : run[1]])
            del x
    return n_s, freqs


def _runs(block: np.ndarray) -> list[tuple[int, int]]:
    """The runs of consecutive values in ``block`` as (start, stop) positions."""
    breaks = np.flatnonzero(np.diff(block) != 1) + 1
    edges = np.concatenate([[0], breaks, [block.size]])
    return [(int(edges[i]), int(edges[i + 1])) for i in range(edges.size - 1)]


@numba.njit(cache=True)
def _fill_exterior(indptr, interior, corner, B, indices, data):  # pragma: no cover - compiled
    """Row interior[i] of psi: the corner's columns, B[i] (every entry, zeros kept)."""
    n_c = corner.shape[0]
    for i in range(interior.shape[0]):
        p = indptr[interior[i]]
        for j in range(n_c):
            indices[p + j] = corner[j]
            if B.shape[0]:
                data[p + j] = B[i, j]


def ring_psi(n_dof: int, nodes: np.ndarray, cols: RingColumns, nq: int) -> sp.csr_matrix:
    """The basis (n_dof, nq) as csr: a 1.0 at (3 k_j + d, 3 j + d) for retained node k_j, the
    row of B at each exterior DOF over the corner's columns (the corner is sorted, so are the
    rows), nothing at the reference DOFs. 12 bytes an entry, made in place (no copy of B);
    with no rows in cols.stored, the exterior's entries are left to be written
    (ring_basis)."""
    b = node_dofs(nodes)
    counts = np.zeros(n_dof, dtype=np.int64)
    counts[b] = 1
    counts[cols.interior] = cols.corner.size
    indptr = np.concatenate([[0], np.cumsum(counts)])
    index_type = np.int32 if indptr[-1] < np.iinfo(np.int32).max else np.int64
    indices = np.empty(indptr[-1], dtype=index_type)
    data = np.empty(indptr[-1])
    indices[indptr[b]] = np.arange(b.size)
    data[indptr[b]] = 1.0
    _fill_exterior(
        indptr,
        cols.interior,
        cols.corner.astype(index_type),
        np.ascontiguousarray(cols.B),
        indices,
        data,
    )
    return sp.csr_matrix((data, indices, indptr.astype(index_type)), shape=(n_dof, nq), copy=False)


def split_ring_psi(
    fe: FEModel, reference: ReferenceCondition, psi: sp.spmatrix, nodes: np.ndarray
) -> RingColumns:
    """RingColumns of a ring basis psi (ring_psi's output) of ``fe`` with retained ``nodes``
    and the reference condition it was built on: the ring from K's pattern (as ring_columns,
    massless ring nodes included: their columns are unit vectors but K couples them to E),
    the exterior rows of the corner columns read from psi when asked (RingColumns.rows: not
    copied whole), or gathered into B where psi does not have ring_psi's layout."""
    b = node_dofs(nodes)
    interior = np.setdiff1d(reference.free_dofs(fe.n_dof), b)
    ring = ring_positions(fe, interior, b)
    corner = np.concatenate([node_dofs(ring), np.arange(b.size, psi.shape[1])]).astype(np.int64)
    psi = sp.csr_matrix(psi)
    if _has_layout(psi.indptr, psi.indices, interior, corner):
        return RingColumns(interior, corner, None, ring, psi)
    B = np.asarray(psi[interior][:, corner].toarray())  # not ring_psi's layout
    return RingColumns(interior, corner, B, ring)


@numba.njit(cache=True)
def _has_layout(indptr, indices, interior, corner):  # pragma: no cover - compiled
    """Whether every row interior[i] of psi holds exactly the corner's columns in order
    (ring_psi's layout)."""
    n_c = corner.shape[0]
    for i in range(interior.shape[0]):
        p = indptr[interior[i]]
        if indptr[interior[i] + 1] - p != n_c:
            return False
        for j in range(n_c):
            if indices[p + j] != corner[j]:
                return False
    return True


@numba.njit(cache=True)
def _gather_exterior(indptr, indices, data, interior, corner, B):  # pragma: no cover - compiled
    """B[i] = row interior[i] of psi when it holds exactly the corner's columns in order
    (ring_psi's layout): True; False at the first row that does not."""
    n_c = corner.shape[0]
    for i in range(interior.shape[0]):
        p = indptr[interior[i]]
        if indptr[interior[i] + 1] - p != n_c:
            return False
        for j in range(n_c):
            if indices[p + j] != corner[j]:
                return False
            B[i, j] = data[p + j]
    return True
