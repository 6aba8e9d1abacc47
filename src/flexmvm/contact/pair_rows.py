"""The active pairs of a scan and their constraint rows, compiled (numba).

From the scan's output (search.scan_nodes: facet (ns,), out (ns, 11): weights, xi, normal,
gap [m], u_N [m/s]) the pairs predicted to close within the step, their row data (slave node
and master facet nodes with weights), and the rows of one body, d^T sum_k w_k dx_k/dv
(seed eq. 9), on the arrays of contact.nodes.ContactNodes.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def predicted_min_gap(facet, out, horizon):
    """min over the projected nodes of gap + horizon min(u_N, 0) [m] (inf when none)."""
    low = np.inf
    for i in range(len(facet)):
        if facet[i] >= 0:
            low = min(low, out[i, 9] + horizon * min(out[i, 10], 0.0))
    return low


@numba.njit(cache=True)
def active_nodes(facet, out, h, gap_tol, bonded, idx):
    """Slave nodes predicted to close within the step, gap + h u_N <= gap_tol, not bonded,
    into idx (ascending). Returns their number."""
    m = 0
    for i in range(len(facet)):
        if facet[i] >= 0 and out[i, 9] + h * out[i, 10] <= gap_tol and not bonded[i]:
            idx[m] = i
            m += 1
    return m


@numba.njit(cache=True)
def active_pairs(facet, out, h, gap_tol, bonded, idx, conn, n_quads, slave_nodes):
    """active_nodes (into idx), then the data of those m pairs in one call: (m, nodes (m,)
    their slave indices, slave_ids (m,) = slave_nodes[nodes], facets (m,), normal (m, 3),
    gap (m,), u_N (m,) (copies of their rows of out), and pair_nodes' slave (s_nodes,
    s_w, s_k) and master (m_nodes, m_w, m_k) row data)."""
    m = active_nodes(facet, out, h, gap_tol, bonded, idx)
    nodes = idx[:m].copy()
    slave_ids, facets = np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64)
    normal, gap, u_n = np.empty((m, 3)), np.empty(m), np.empty(m)
    for a in range(m):
        i = nodes[a]
        slave_ids[a], facets[a] = slave_nodes[i], facet[i]
        normal[a, 0], normal[a, 1], normal[a, 2] = out[i, 6], out[i, 7], out[i, 8]
        gap[a], u_n[a] = out[i, 9], out[i, 10]
    s_nodes, s_w, s_k = np.empty((m, 1), np.int64), np.empty((m, 1)), np.empty(m, np.int64)
    m_nodes, m_w, m_k = np.empty((m, 4), np.int64), np.empty((m, 4)), np.empty(m, np.int64)
    pair_nodes(nodes, facet, out, conn, n_quads, s_nodes, s_w, s_k, m_nodes, m_w, m_k)
    return (m, nodes, slave_ids, facets, normal, gap, u_n, (s_nodes, s_w, s_k), (m_nodes, m_w, m_k))


@numba.njit(cache=True)
def pair_nodes(idx, facet, out, conn, n_quads, s_nodes, s_w, s_k, m_nodes, m_w, m_k):
    """Row data of the m = len(idx) active pairs: slave (node idx, weight 1, one node) and
    master (facet nodes, weights, 4 for a quad, 3 for a triangle)."""
    for a in range(len(idx)):
        i = idx[a]
        g = facet[i]
        s_nodes[a, 0], s_w[a, 0], s_k[a] = i, 1.0, 1
        m_k[a] = 4 if g < n_quads else 3
        for b in range(4):
            m_nodes[a, b] = conn[g, b]
            m_w[a, b] = out[i, b]


@numba.njit(cache=True)
def body_rows(
    nodes,
    w,
    kc,
    dirs,
    A,
    s,
    sign,
    psi_c,
    indptr,
    indices,
    data,
    dense,
    gdof,
    frame,
    elastic,
    sel_data,
    sel_idx,
    sel_ptr,
):
    """sign * (rows d_a^T sum_k w_ak dx_{node_ak}/dv) of one body (seed eq. 9), as
    pairs.body_rows: frame (m, 6) = [d wsum, sw x A^T d], elastic (m, nq) = N psi with the
    nodal selector N (m, 3 n_nodes) in CSR (sel_data, sel_idx (m*12,), sel_ptr (m + 1,),
    columns gdof[node] + j, sorted within a row). nodes, w (m, 4) local node ids / weights,
    kc (m,) nodes used per row, dirs (m, 3) global directions, s (n_c, 3) body-frame node
    positions; psi rows dense or CSR as in body_kinematics."""
    sel_ptr[0] = 0
    elastic[:] = 0.0
    for a in range(len(kc)):
        dl0 = (dirs[a, 0] * A[0, 0] + dirs[a, 1] * A[1, 0]) + dirs[a, 2] * A[2, 0]
        dl1 = (dirs[a, 0] * A[0, 1] + dirs[a, 1] * A[1, 1]) + dirs[a, 2] * A[2, 1]
        dl2 = (dirs[a, 0] * A[0, 2] + dirs[a, 1] * A[1, 2]) + dirs[a, 2] * A[2, 2]
        wsum = sw0 = sw1 = sw2 = 0.0
        for k in range(len(w[a])):
            wk = w[a, k] if k < kc[a] else 0.0
            c = nodes[a, k]
            wsum += wk
            sw0 += wk * s[c, 0]
            sw1 += wk * s[c, 1]
            sw2 += wk * s[c, 2]
        frame[a, 0], frame[a, 1], frame[a, 2] = (
            sign * (dirs[a, 0] * wsum),
            sign * (dirs[a, 1] * wsum),
            sign * (dirs[a, 2] * wsum),
        )
        frame[a, 3] = sign * (sw1 * dl2 - sw2 * dl1)
        frame[a, 4] = sign * (sw2 * dl0 - sw0 * dl2)
        frame[a, 5] = sign * (sw0 * dl1 - sw1 * dl0)
        dl = (dl0, dl1, dl2)
        start = sel_ptr[a]
        for k in range(kc[a]):
            c = nodes[a, k]
            for j in range(3):
                coef = w[a, k] * dl[j]
                _add_row(elastic[a], sign * coef, psi_c, indptr, indices, data, dense, 3 * c + j)
                sel_data[start + 3 * k + j] = sign * coef
                sel_idx[start + 3 * k + j] = gdof[c] + j
        sel_ptr[a + 1] = start + 3 * kc[a]
        _sort_row(sel_idx, sel_data, start, sel_ptr[a + 1])


@numba.njit(cache=True, fastmath={"reassoc", "contract"})
def _add_row(out, coef, psi_c, indptr, indices, data, dense, row):
    """out += coef * psi row `row` (row 3 c + j of the gathered rows)."""
    if dense:
        src = psi_c[row // 3, row % 3]
        for k in range(len(out)):
            out[k] += coef * src[k]
    else:
        for e in range(indptr[row], indptr[row + 1]):
            out[indices[e]] += coef * data[e]


@numba.njit(cache=True)
def _sort_row(idx, val, lo, hi):
    """Insertion sort of idx[lo:hi] (with val alongside); a few entries per row."""
    for a in range(lo + 1, hi):
        ki, kv = idx[a], val[a]
        b = a - 1
        while b >= lo and idx[b] > ki:
            idx[b + 1], val[b + 1] = idx[b], val[b]
            b -= 1
        idx[b + 1], val[b + 1] = ki, kv
