"""The contact nodes of one body: psi rows gathered once, kinematics and rows per step.

psi rows of the contact nodes are gathered at construction, dense (n_c, 3, nq) when they are
mostly non-zero, else in CSR form (a full-FE body, or the retained nodes of a Craig-Bampton
basis, whose rows select single q entries). Per step, body_kinematics fills the node
positions and velocities and body_rows the constraint rows, both compiled (contact.kinematics,
contact.pair_rows) and on arrays preallocated here.

The kinematics are kept with the state they were computed at (q, v, r, A, by value, bit for
bit): an update at the same state again (the penetration measure at the end of a step and the
next step's search, which share these objects when their node sets are equal) reuses them,
and so do the closest-point projections made at those positions (search_state.
ProjectionMemo).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from flexmvm.constraints.rows import NodalSelector
from flexmvm.contact.kinematics import body_kinematics_memo
from flexmvm.contact.pair_rows import body_rows
from flexmvm.contact.slave_window import window_kinematics_memo

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
        # the state of the last update (kinematics.body_kinematics_memo): q, v, [r, A], result;
        # version[0]: how many updates computed (positions kept for other uses are valid as
        # long as it stands: search_state.ProjectionMemo)
        self.version = np.zeros(1, dtype=np.int64)
        self._last = (
            np.zeros(self.nq),
            np.zeros(6 + self.nq),
            np.full(12, np.nan),
            np.zeros(2),
            self.version,
        )
        # the rows moved per update (contact.slave_window; None: every node)
        self.window_rows: np.ndarray | None = None

    def set_rows(self, rows: np.ndarray | None, invalidate: bool) -> None:
        """Move only the nodes `rows` per update (None: every node; slave_window).
        invalidate: the next update recomputes even at an unchanged state."""
        self.window_rows = rows
        if invalidate:
            self._last[2][0] = np.nan

    def rebind(self, body) -> None:
        """Gather the rows of the same nodes from ``body`` (another basis of the same mesh: a
        moving region's window switch, integrate/moving_region.py); the last update forgotten and
        the version advanced (projections kept for the old rows are not reused)."""
        self.nq = body.nq
        self._gather(body, len(self.nodes))
        self.version[0] += 1
        self._last = (
            np.zeros(self.nq),
            np.zeros(6 + self.nq),
            np.full(12, np.nan),
            np.zeros(2),
            self.version,
        )

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
        # the gathered rows' own values, not a copy (a face of a big part's ring basis: GBs)
        self.data = np.asarray(rows.data, dtype=np.float64)

    def update(self, st) -> tuple[float, float]:
        """Positions x, velocities xd (global), body-frame positions s at state st (kept
        when st holds the values of the last update). Returns (largest velocity component
        [m/s], largest displacement |u| [m]). With a window (set_rows) only its nodes are
        moved, and the maxima are theirs."""
        if self.window_rows is not None:
            return window_kinematics_memo(
                self.X,
                self.psi_c,
                self.indptr,
                self.indices,
                self.data,
                self.dense,
                st.q,
                st.v,
                st.r,
                st.A,
                self.u,
                self.ud,
                self.s,
                self.x,
                self.xd,
                self._last,
                self.window_rows,
            )
        return body_kinematics_memo(
            self.X,
            self.psi_c,
            self.indptr,
            self.indices,
            self.data,
            self.dense,
            st.q,
            st.v,
            st.r,
            st.A,
            self.u,
            self.ud,
            self.s,
            self.x,
            self.xd,
            *self._last,
        )

    def displacement_offset(self) -> tuple[np.ndarray, float]:
        """(d0 (3,), r [m]): the centre d0 of the box of the nodes' body-frame displacements u
        at the last update and the largest |u - d0| (over the window's nodes when there is
        one: the ones moved). A search over these nodes' facets in their reference geometry
        may take the facets as moved by d0 with at most r more, instead of at most max |u|:
        a bar bent 6 mm at a contact strip moves the strip's facets by ~6 mm but apart from
        each other by ~0.2 mm."""
        u = self.u if self.window_rows is None else self.u[self.window_rows]
        if not self.nq or not len(u):  # a rigid body's nodes do not move in its frame
            return np.zeros(3), 0.0
        d0 = 0.5 * (u.min(axis=0) + u.max(axis=0))
        return d0, float(np.sqrt(((u - d0) ** 2).sum(axis=1).max()))

    def rows(self, nodes, w, kc, dirs, A, sign: float):
        """sign * rows of the pairs (nodes, w (m, k) local ids / weights, kc (m,) nodes per
        row, dirs (m, 3)), from the positions of the last update: frame (m, 6), elastic
        (m, nq) and the nodal selector (NodalSelector (m, 3 n_nodes), rows with ascending
        columns; None for a rigid body)."""
        m, k = nodes.shape
        frame, elastic = np.empty((m, 6)), np.empty((m, self.nq))
        sel_data, sel_idx = np.empty(3 * k * m), np.empty(3 * k * m, dtype=np.int64)
        sel_ptr = np.empty(m + 1, dtype=np.int64)
        body_rows(
            nodes,
            w,
            kc,
            dirs,
            A,
            self.s,
            sign,
            self.psi_c,
            self.indptr,
            self.indices,
            self.data,
            self.dense,
            self.gdof,
            frame,
            elastic,
            sel_data,
            sel_idx,
            sel_ptr,
        )
        if not self.nq:
            return frame, elastic, None
        n = sel_ptr[m]
        return frame, elastic, NodalSelector(sel_data[:n], sel_idx[:n], sel_ptr, (m, self.n_dofs))
