"""The contact nodes of one body: psi rows gathered once, kinematics and rows per step.

psi rows of the contact nodes are gathered at construction, dense (n_c, 3, nq) when they are
mostly non-zero, else in CSR form (a full-FE body, or the retained nodes of a Craig-Bampton
basis, whose rows select single q entries). Per step, body_kinematics fills the node
positions and velocities and body_rows the constraint rows, both compiled (contact.kernels)
and on arrays preallocated here.

The kinematics are kept with the state they were computed at (q, v, r, A, by value, bit for
bit): an update at the same state again (the penetration measure at the end of a step and the
next step's search, which share these objects when their node sets are equal) reuses them,
and so do the closest-point projections made at those positions (ProjectionMemo).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from flexmvm.constraints.rows import NodalSelector
from flexmvm.contact import kernels

_DENSE_FILL = 0.25  # gathered rows with more non-zeros than this fraction are stored dense


class ContactNodes:
    """Contact nodes `nodes` (n_c,) of `body`, in the order given (their local indices)."""

    def __init__(self, body, nodes: np.ndarray):
        self.nodes = np.asarray(nodes, dtype=np.int64)
        self.nq = body.nq
        self.n_dofs = 3 * len(body.X)
        n = len(self.nodes)
        self.X = np.ascontiguousarray(body.X[self.nodes], dtype=np.float64)
        self.gdof = 3 * self.nodes
        self._gather(body, n)
        self.u, self.ud, self.s, self.x, self.xd = (np.zeros((n, 3)) for _ in range(5))
        # the state of the last update (kernels.body_kinematics_memo): q, v, [r, A], result;
        # version[0]: how many updates computed (positions kept for other uses are valid as
        # long as it stands: ProjectionMemo)
        self.version = np.zeros(1, dtype=np.int64)
        self._last = (np.zeros(self.nq), np.zeros(6 + self.nq), np.full(12, np.nan), np.zeros(2),
                      self.version)

    def _gather(self, body, n: int) -> None:
        self.psi_c = np.zeros((0, 3, 0))
        self.indptr = np.zeros(3 * n + 1, dtype=np.int64)
        self.indices = np.zeros(0, dtype=np.int64)
        self.data = np.zeros(0)
        self.dense = False
        if not self.nq:
            return
        idx = (3 * self.nodes[:, None] + np.arange(3)).ravel()
        rows = body.psi[idx]
        if not sp.issparse(rows) and np.count_nonzero(rows) > _DENSE_FILL * rows.size:
            self.psi_c = np.ascontiguousarray(np.asarray(rows, dtype=np.float64).reshape(n, 3, -1))
            self.dense = True
            return
        rows = sp.csr_matrix(rows)
        rows.eliminate_zeros()
        rows.sort_indices()
        self.indptr = rows.indptr.astype(np.int64)
        self.indices = rows.indices.astype(np.int64)
        self.data = rows.data.astype(np.float64)

    def update(self, st) -> tuple[float, float]:
        """Positions x, velocities xd (global), body-frame positions s at state st (kept
        when st holds the values of the last update). Returns (largest velocity component
        [m/s], largest displacement |u| [m])."""
        return kernels.body_kinematics_memo(self.X, self.psi_c, self.indptr, self.indices,
                                            self.data, self.dense, st.q, st.v, st.r, st.A,
                                            self.u, self.ud, self.s, self.x, self.xd, *self._last)

    def rows(self, nodes, w, kc, dirs, A, sign: float):
        """sign * rows of the pairs (nodes, w (m, k) local ids / weights, kc (m,) nodes per
        row, dirs (m, 3)), from the positions of the last update: frame (m, 6), elastic
        (m, nq) and the nodal selector (NodalSelector (m, 3 n_nodes), rows with ascending
        columns; None for a rigid body)."""
        m, k = nodes.shape
        frame, elastic = np.empty((m, 6)), np.empty((m, self.nq))
        sel_data, sel_idx = np.empty(3 * k * m), np.empty(3 * k * m, dtype=np.int64)
        sel_ptr = np.empty(m + 1, dtype=np.int64)
        kernels.body_rows(nodes, w, kc, dirs, A, self.s, sign, self.psi_c, self.indptr,
                          self.indices, self.data, self.dense, self.gdof, frame, elastic,
                          sel_data, sel_idx, sel_ptr)
        if not self.nq:
            return frame, elastic, None
        n = sel_ptr[m]
        return frame, elastic, NodalSelector(sel_data[:n], sel_idx[:n], sel_ptr, (m, self.n_dofs))


class SearchState:
    """Search state of kernels.scan_nodes / kernels.penetration_scan for n nodes against nf
    facets: per node its candidate superset (lists, ref) and last facet (prev); work arrays
    (mark, counter, cand, lb); and a uniform grid of the facets (facet_grid of their
    undeformed centroids and circumradii geo (nf, 4)), so that a node's superset is rebuilt
    from the cells about it, not from every facet: the search's cost follows the facets near
    the nodes, not the surface's size (benchmarks/bench_search.py)."""

    def __init__(self, n: int, nf: int, cap: int = 256, geo: np.ndarray | None = None):
        self.lists = np.zeros((n, min(nf, cap) + 1), dtype=np.int64)
        self.ref = np.full((n, 4), -1.0)
        self.prev = np.full(n, -1, dtype=np.int64)
        self.mark = np.zeros(nf, dtype=np.int64)
        self.counter = np.zeros(1, dtype=np.int64)
        self.cand = np.zeros(nf, dtype=np.int64)
        self.lb = np.zeros(nf)
        self.grid = facet_grid(np.zeros((nf, 4)) if geo is None else np.asarray(geo, float))

    def arrays(self):
        return (self.lists, self.ref, self.prev, self.mark, self.counter, self.cand, self.lb,
                *self.grid)


#: Cells of a facet grid per facet, at most (the cell edge grows until it holds).
GRID_CELLS_PER_FACET = 2.0


def facet_grid(geo: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A uniform grid over facet centroids geo[:, :3] [m] (circumradii geo[:, 3]): (meta
    (5,) = origin xyz, cell edge [m], largest circumradius [m]; dims (3,) cells per axis;
    start (n_cells + 1,) and facets (nf,): the facets of cell c, in CSR, by increasing index).
    The cell edge is twice the median circumradius, grown until the grid has at most
    GRID_CELLS_PER_FACET cells per facet; no facets: one empty cell."""
    geo = np.asarray(geo, dtype=np.float64)
    nf = len(geo)
    if nf == 0:
        return (np.array([0.0, 0.0, 0.0, 1.0, 0.0]), np.ones(3, dtype=np.int64),
                np.zeros(2, dtype=np.int64), np.zeros(0, dtype=np.int64))
    c, r = geo[:, :3], geo[:, 3]
    lo, hi = c.min(axis=0), c.max(axis=0)
    span = np.maximum(hi - lo, 0.0)
    edge = max(2.0 * float(np.median(r)), 1e-12 * max(float(span.max()), 1e-300), 1e-300)
    while True:
        dims = np.maximum(np.floor(span / edge).astype(np.int64) + 1, 1)
        if float(np.prod(dims.astype(float))) <= max(GRID_CELLS_PER_FACET * nf, 1.0):
            break
        edge *= 1.5
    ijk = np.minimum(((c - lo) / edge).astype(np.int64), dims - 1)
    cell = (ijk[:, 0] * dims[1] + ijk[:, 1]) * dims[2] + ijk[:, 2]
    order = np.argsort(cell, kind="stable")
    start = np.zeros(int(np.prod(dims)) + 1, dtype=np.int64)
    np.add.at(start, cell + 1, 1)
    np.cumsum(start, out=start)
    meta = np.array([lo[0], lo[1], lo[2], edge, float(r.max())])
    return meta, dims, start, order.astype(np.int64)


class ProjectionMemo:
    """Closest-point projections of the nodes of `nodes` (ContactNodes, n nodes) on the facets
    conn (nf, 4) (local ids into `facets`, a ContactNodes), with the projection params, up to
    k per node, kept while neither set's positions changed (their versions): kernels.scan_nodes
    and kernels.penetration_scan read a kept one instead of projecting again (kernels._try).
    Scans of all of these nodes against these facets with these params may share one memo
    (serves); k = 0 keeps none."""

    def __init__(self, nodes: ContactNodes, facets: ContactNodes, conn: np.ndarray,
                 params: np.ndarray, k: int = 8):
        n = len(nodes.nodes)
        self.nodes, self.facets = nodes, facets
        self.conn, self.params = np.array(conn, dtype=np.int64), np.array(params, dtype=np.float64)
        self.fac = np.zeros((n, k), dtype=np.int64)
        self.count = np.zeros(n, dtype=np.int64)
        self.rec = np.zeros((n, k, kernels.REC_LEN))
        self.versions = np.full(2, -1, dtype=np.int64)

    def serves(self, nodes: ContactNodes, facets: ContactNodes, conn: np.ndarray,
               params: np.ndarray) -> bool:
        """Whether a scan of all nodes of `nodes` against the facets conn over `facets` with
        these params may use this memo."""
        return (nodes is self.nodes and facets is self.facets and self.fac.shape[1] > 0
                and np.array_equal(conn, self.conn) and np.array_equal(params, self.params))

    def arrays(self):
        return (self.fac, self.count, self.rec, self.versions, self.nodes.version,
                self.facets.version)
