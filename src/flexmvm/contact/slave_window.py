"""The slave nodes a contact step must move: a window of the nodes that can reach the master.

A contact's slave set is often a whole face (the top of a plate: 18,909 nodes) while the master
(a ball) can touch a few hundred of them. Per step the kinematics of every slave node (u =
psi q over all nq columns, seed eq. 1-3) and the scans over them cost more than the body's own
step. A :class:`SlaveWindow` keeps the rows of the nodes that can come within reach of the
master's facets, recomputes only those, and is refreshed (every node moved once, the window
chosen again) when a bound says an outside node might have come within reach:

- **Positions.** A node outside the window was, at the refresh, farther than reach_w (the L-inf
  distance in the master frame) from the box of the master surface nodes, which the scans test
  first (search._in_box). Since then its master-frame position p = A_m^T (x - r_m) has moved by
  at most D = |r - r0| + |A - A0|_F S0 + sum_k c_k |q_k - q0_k| + |r_m - r_m0| + |A_m - A_m0|_F
  L0 (slave frame r, A; c_k the largest |psi_i[:, k]| over outside nodes; S0, L0 their
  largest |s| and |x - r_m| at the refresh). While D + need < reach_w (need: the reach of the
  call) no outside node passes the box test, at its true position or at the stale one kept in
  x: the scans give it no facet, as they did when every node was moved. The other direction of
  the penetration measure (master nodes against the slave facets) projects only on facets
  within its reach of a master node: their nodes lie within reach + 2 R_f + u_s + u_m of the
  master box (R_f the largest slave facet circumradius; u the largest displacements), which
  the need of a measure covers.
- **The reach rule's maxima** (the largest slave velocity component, the speed of the reach
  rule and of the position law's row window, and the largest displacement, the slave facets'
  u_max) are the window's: those of the nodes that can reach the master. Before, they were
  over the whole face; on the plate of scenarios/plate_impact.toml the face's largest
  velocity component lay outside the window in 45 of 272 updates (a flexural wave; up to
  1.08 x the window's), and the histories were the same bit for bit
  (docs/notes/2026-11-29-big-part.md). A pair's gap and rows do not read them otherwise.

Units: metres, seconds.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numba
import numpy as np

from flexmvm.contact.kinematics import node_frame, remember, unchanged

if TYPE_CHECKING:
    from flexmvm.contact.nodes import ContactNodes

#: slave sets smaller than this are moved whole (the window's bookkeeping costs more than it
#: saves on a few hundred nodes)
WINDOW_MIN_NODES = 2000

#: the window's extra reach beyond the call's need, per search radius: a refresh every
#: (margin / approach speed) of motion
MARGIN_PER_SEARCH_RADIUS = 1.0

_ROUND = 1e-9  # relative round-off allowance of the bounds


@numba.njit(cache=True, fastmath={"reassoc", "contract"})
def _dense_rows(psi_c, rows, q, qd, u, ud):
    """u = psi_k q, ud = psi_k qd for the nodes `rows` of the gathered rows psi_c (n_c, 3, nq)
    (kinematics.dense_displacements on a subset)."""
    nq = psi_c.shape[2]
    for c in rows:
        for j in range(3):
            a = 0.0
            b = 0.0
            for k in range(nq):
                p = psi_c[c, j, k]
                a += p * q[k]
                b += p * qd[k]
            u[c, j] = a
            ud[c, j] = b


@numba.njit(cache=True)
def _csr_rows(indptr, indices, data, rows, q, qd, u, ud):
    """As _dense_rows for psi rows in CSR form (row 3 c + j of node c)."""
    for c in rows:
        for j in range(3):
            row = 3 * c + j
            a = 0.0
            b = 0.0
            for e in range(indptr[row], indptr[row + 1]):
                a += data[e] * q[indices[e]]
                b += data[e] * qd[indices[e]]
            u[c, j] = a
            ud[c, j] = b


@numba.njit(cache=True)
def _frame_rows(X, u, ud, r, A, v, rows, s, x, xd):
    """kinematics.frame_kinematics on the nodes `rows`: s, x, xd; returns (max |xd component|
    [m/s], max |u| [m]) over them."""
    vmax = 0.0
    umax = 0.0
    for c in rows:
        vmax, umax = node_frame(X, u, ud, r, A, v, c, s, x, xd, vmax, umax)
    return vmax, umax


@numba.njit(cache=True)
def rows_kinematics(X, psi_c, indptr, indices, data, dense, q, v, r, A, rows, u, ud, s, x, xd):
    """kinematics.body_kinematics on the contact nodes `rows` (int64) only; the other nodes'
    arrays are left as they are. Returns (max |xd component|, max |u|) over `rows`."""
    qd = v[6:]
    if psi_c.shape[2] > 0 or len(indices) > 0:
        if dense:
            _dense_rows(psi_c, rows, q, qd, u, ud)
        else:
            _csr_rows(indptr, indices, data, rows, q, qd, u, ud)
    else:
        for c in rows:
            for j in range(3):
                u[c, j] = 0.0
                ud[c, j] = 0.0
    return _frame_rows(X, u, ud, r, A, v, rows, s, x, xd)


@numba.njit(cache=True)
def window_kinematics_memo(
    X, psi_c, indptr, indices, data, dense, q, v, r, A, u, ud, s, x, xd, last, rows
):
    """kinematics.body_kinematics_memo on the window `rows` (int64) of the contact nodes:
    nothing when q, v, r, A are bit for bit those of the last call that computed (last =
    (last_q, last_v, last_frame, last_out, version), as there), else the window's rows.
    Returns (max |xd component| [m/s], max |u| [m]) over the window."""
    last_q, last_v, last_frame, last_out, version = last
    if unchanged(q, v, r, A, last_q, last_v, last_frame):
        return last_out[0], last_out[1]
    vmax, umax = rows_kinematics(
        X, psi_c, indptr, indices, data, dense, q, v, r, A, rows, u, ud, s, x, xd
    )
    remember(q, v, r, A, vmax, umax, last_q, last_v, last_frame, last_out, version)
    return vmax, umax


@numba.njit(cache=True)
def window_drift(q, q0, c_out, dr, dA, s0, dr_m, dA_m, l0):
    """D [m]: how far an outside node's master-frame position can have moved since the
    refresh (module doc); dr, dr_m the frame displacements, dA, dA_m the rotation changes."""
    d = 0.0
    for k in range(q.shape[0]):
        d += c_out[k] * abs(q[k] - q0[k])
    fa = 0.0
    fm = 0.0
    for i in range(3):
        for j in range(3):
            fa += dA[i, j] ** 2
            fm += dA_m[i, j] ** 2
    dn = np.sqrt(dr[0] ** 2 + dr[1] ** 2 + dr[2] ** 2)
    dm = np.sqrt(dr_m[0] ** 2 + dr_m[1] ** 2 + dr_m[2] ** 2)
    return d + dn + np.sqrt(fa) * s0 + dm + np.sqrt(fm) * l0


def column_bounds(nodes: ContactNodes, rows: np.ndarray) -> np.ndarray:
    """c (nq,): per column k the largest |psi_i[:, k]| (2-norm over x, y, z) over the contact
    nodes `rows` (their gathered psi rows, dense or CSR)."""
    c = np.zeros(nodes.nq)
    if nodes.nq == 0 or len(rows) == 0:
        return c
    if nodes.dense:
        for lo in range(0, len(rows), 2048):  # blocks: (2048, 3, nq) at a time
            block = nodes.psi_c[rows[lo : lo + 2048]]
            c = np.maximum(c, np.sqrt((block * block).sum(axis=1)).max(axis=0))
        return c
    _csr_column_bounds(nodes.indptr, nodes.indices, nodes.data, rows, np.zeros(nodes.nq), c)
    return c


@numba.njit(cache=True)
def _csr_column_bounds(indptr, indices, data, rows, work, c):
    """column_bounds for psi rows in CSR form (row 3 i + j of node i): c[k] = max over the
    nodes `rows` of sqrt(sum_j psi_ij,k^2); work (nq,) zeros, left zero."""
    for i in rows:
        for j in range(3):
            for e in range(indptr[3 * i + j], indptr[3 * i + j + 1]):
                work[indices[e]] += data[e] * data[e]
        for j in range(3):
            for e in range(indptr[3 * i + j], indptr[3 * i + j + 1]):
                k = indices[e]
                if work[k] > 0.0:
                    c[k] = max(c[k], np.sqrt(work[k]))
                    work[k] = 0.0


class SlaveWindow:
    """The window of the slave contact nodes `nodes` (ContactNodes, set on it) against a
    master whose surface nodes lie in `box` (2, 3) of its frame (search_state.FacetSurface.box).
    search_radius [m]: the contact's; facet_radius [m]: the largest circumradius of the slave
    facets the penetration measure projects on (0: none); margin [m]: the reach a refresh
    adds beyond the need. `refreshes` counts the refreshes."""

    def __init__(
        self,
        nodes: ContactNodes,
        box: np.ndarray,
        search_radius: float,
        facet_radius: float,
        margin: float,
    ):
        self.nodes = nodes
        self.box = np.asarray(box, dtype=np.float64)
        self.search_radius = float(search_radius)
        self.facet_radius = float(facet_radius)
        self.margin = float(margin)
        self.all_rows = np.arange(len(nodes.nodes), dtype=np.int64)
        self.reach_w = -np.inf
        self.refreshes = 0
        self._ref: tuple | None = None  # q0, r0, A0, r_m0, A_m0, s0, l0, c_out

    def need(self, reach: float, u_s: float, u_m: float) -> float:
        """The reach [m] the window must cover for a call searching within `reach` [m]: that
        and the penetration measure's other direction (master nodes against slave facets:
        search radius + 2 u_s + 2 R_f + u_m, module doc); u_s, u_m the largest slave and
        master node displacements [m]."""
        other = self.search_radius + 2.0 * u_s + 2.0 * self.facet_radius + u_m
        return max(float(reach), other)

    def ensure(self, st, st_m, need: float, keep: np.ndarray | None = None) -> bool:
        """Make the window valid for a call needing `need` [m] at slave state st and master
        state st_m (refreshed unless the drift bound allows it; np.inf: every node, as for
        the start's deep check). keep: rows kept in the window at a refresh (held pairs).
        Returns whether it was refreshed (the nodes' maxima are then the new window's)."""
        if self._holds(st, st_m, need):
            return False
        self._refresh(st, st_m, need, keep)
        return True

    def _holds(self, st, st_m, need: float) -> bool:
        # refreshed too when the window is far wider than the need (after a call with a long
        # reach: the start's deep check, min_gap_ahead's horizon), with room enough that
        # calls of different needs in turn do not refresh it each time
        if self._ref is None or not np.isfinite(need) or self.reach_w > 4.0 * need + self.margin:
            return False
        q0, r0, A0, rm0, Am0, s0, l0, c_out = self._ref
        d = window_drift(st.q, q0, c_out, st.r - r0, st.A - A0, s0, st_m.r - rm0, st_m.A - Am0, l0)
        slack = _ROUND * (d + need + s0 + l0) + 1e-15
        return d + need + slack < self.reach_w

    def _refresh(self, st, st_m, need: float, keep: np.ndarray | None) -> None:
        """Every node moved at st; the window: the nodes within need + margin (L-inf, master
        frame) of the box, and `keep`."""
        nodes = self.nodes
        self.refreshes += 1
        nodes.set_rows(self.all_rows, invalidate=True)
        nodes.update(st)
        if not np.isfinite(need):
            self._ref, self.reach_w = None, np.inf
            return
        reach_w = need + self.margin
        p = (nodes.x - st_m.r) @ st_m.A  # rows A_m^T (x - r_m)
        dist = np.maximum(self.box[0] - p, p - self.box[1]).max(axis=1)
        inside = dist <= reach_w
        if keep is not None:
            inside[keep] = True
        rows, out = self.all_rows[inside], self.all_rows[~inside]
        c_out = column_bounds(nodes, out)
        norm = lambda a: float(np.sqrt((a * a).sum(axis=1)).max()) if len(a) else 0.0
        s0, l0 = norm(nodes.s[out]), norm(nodes.x[out] - st_m.r)
        # the window's maxima at st (the update above gave every node's)
        nodes.set_rows(rows, invalidate=True)
        nodes.update(st)
        ref = (st.q, st.r, st.A, st_m.r, st_m.A)
        self._ref = tuple(np.array(a, dtype=np.float64) for a in ref) + (s0, l0, c_out)
        self.reach_w = reach_w
