"""Closest facet of each node, compiled (numba): broad phase, warm start, pruning.

The numpy path (geometry.BroadPhase, geometry.project_points, geometry.closest_facets, the
clamping of outside projections in pairs) is the specification, reproduced pair by pair to
round-off. What differs is the search: per slave node a cached superset of its broad-phase
candidates, rebuilt from a grid of the facets (contact.candidate_lists), and a warm start
from the facet chosen at the previous step, with facets pruned by a distance bound (see
:func:`_closest`); a node whose last facet is certified still to win (contact.certificate:
the other facets' bounds kept from its last search, less its motion since) is projected on
that facet alone, its candidates not read. What it reads and keeps comes in three typed
tuples (contact.search_state): the facets (FacetSurface), the per-node state (SearchState)
and the kept projections (MemoArrays); the two scans, :func:`scan_nodes` (the constraint pass) and
:func:`penetration_scan` (the penetration measure, contact.penetration), unpack them once
and hand their arrays to the per-node helpers (see :func:`_search_node` for why).

Projections made at unchanged node positions are kept and read again (search_state.
ProjectionMemo, :func:`_try`): the penetration measure at the end of a step and the next
step's search project the same pairs at the same positions. The helpers called per node
with many array arguments (_search_node, _closest, _try) are inlined into the scans (numba
``inline="always"``): a call cost ~0.4 us in the arguments' reference counts alone, as much
as a projection (docs/notes/2026-11-29-step-cost-cuts.md).

Units: metres, seconds. Node arrays hold the contact nodes of one body only ("local" node
indices 0..n_c-1); facets refer to local node indices of the body that carries them.
"""

from __future__ import annotations

import numba
import numpy as np

from flexmvm.contact.candidate_lists import node_candidates, row_distance
from flexmvm.contact.certificate import (
    MARGIN_ABS,
    MARGIN_D,
    MARGIN_R,
    certified,
    certify,
    far,
    list_holds,
    slab_bound,
)
from flexmvm.contact.geometry import TIE_ABS, TIE_REL
from flexmvm.contact.projection import (
    REC_DIST,
    REC_GAP,
    REC_IN,
    REC_LEN,
    REC_N,
    REC_W,
    REC_XI,
    project_pair,
)


@numba.njit(cache=True)
def _score(rec):
    """A projection's distance to its facet [m] for closest_facets' order: |gap| inside, the
    distance to the clamped facet outside, the latter raised by a round-off margin
    (TIE_REL, TIE_ABS) so that an inside projection wins a tie."""
    if rec[REC_IN] == 1.0:
        return abs(rec[REC_GAP])
    return rec[REC_DIST] * (1.0 + TIE_REL) + TIE_ABS


@numba.njit(cache=True)
def _better(rec, g, best, best_g):
    """closest_facets' order: the closer facet (_score), then an inside projection, then the
    lower facet index."""
    if best_g < 0:
        return True
    sa, sb = _score(rec), _score(best)
    if sa != sb:
        return sa < sb
    a_in = rec[REC_IN] == 1.0
    b_in = best[REC_IN] == 1.0
    if a_in != b_in:
        return a_in
    return g < best_g


@numba.njit(cache=True)
def _memo_begin(memo):
    """Forget the kept projections of memo (search_state.MemoArrays) unless the node and
    facet positions are still those they were made at (their ContactNodes versions)."""
    count, versions = memo.count, memo.versions
    ver_s, ver_m = memo.node_version, memo.facet_version
    if versions[0] != ver_s[0] or versions[1] != ver_m[0]:
        count[:] = 0
        versions[0], versions[1] = ver_s[0], ver_m[0]


@numba.njit(cache=True, inline="always")
def _try(g, i, xs, xm, conn, n_quads, params, work, memo, best, best_g):
    """Project xs (node i) on facet g; keep it in best when it beats best_g. Returns (status,
    best_g). memo = (facets (n, k), count (n,), records (n, k, REC_LEN)) of MemoArrays: up to k
    projections of node i at the current positions (_memo_begin), read instead of projecting
    again (project_pair writes every entry of a record and depends on xs, the facet's nodes
    and params only: the same record bit for bit); k = 0: none kept."""
    C, t, r, P, rec = work
    m_fac, m_count, m_rec = memo[0], memo[1], memo[2]
    kept = -1
    for k in range(m_count[i]):
        if m_fac[i, k] == g:
            kept = k
            break
    if kept >= 0:
        rec[:] = m_rec[i, kept]
        status = 0
    else:
        for a in range(4):
            for j in range(3):
                P[a, j] = xm[conn[g, a], j]
        status = project_pair(xs, P, g < n_quads, params, C, t, r, rec)
        c = m_count[i]
        if status == 0 and c < m_fac.shape[1]:
            m_fac[i, c] = g
            m_rec[i, c] = rec
            m_count[i] = c + 1
    if status == 0 and _better(rec, g, best, best_g):
        best[:] = rec
        best_g = g
    return status, best_g


@numba.njit(cache=True, inline="always")
def _closest(
    i,
    xs,
    p,
    plane,
    n,
    cand,
    lb,
    mark,
    tag,
    f0,
    adj_ptr,
    adj_idx,
    geo,
    u_max,
    xm,
    conn,
    n_quads,
    params,
    work,
    memo,
    best,
):
    """Closest facet among the n candidates (marked mark[g] == tag) of node i (xs (3,) global,
    p (3,) in the facet body's frame): the previous facet f0 first (warm start), its
    neighbours next unless f0 holds an inside projection, then the rest. Once a projection
    with score s (_score) is known, a candidate g is skipped when a lower bound of its
    distance minus u_max (undeformed facet moved by at most the largest facet node
    displacement u_max) and a margin for the inside tolerance and round-off exceeds s: any
    projection on g scores at least its distance, so g cannot win. The bound: |p - c_g| - R_g
    (lb, the ball), then, when that does not skip g, certificate.slab_bound (the facet's
    slab, plane (nf, 4)): on a smooth surface it leaves the facets next to the foot point, where the
    ball alone leaves every facet within the node's gap (a scan projected 4 to 5 times as
    many). Skipping only facets that cannot win, the result is the same as without it.
    Returns (status, facet; -1 when none)."""
    best_g = -1
    if f0 >= 0:
        if mark[f0] == tag:
            status, best_g = _try(f0, i, xs, xm, conn, n_quads, params, work, memo, best, best_g)
            mark[f0] = tag + 1
            if status:
                return status, f0
        start = adj_ptr[f0 + 1] if best_g >= 0 and best[REC_IN] == 1.0 else adj_ptr[f0]
        for k in range(start, adj_ptr[f0 + 1]):
            g = adj_idx[k]
            if mark[g] == tag:
                status, best_g = _try(g, i, xs, xm, conn, n_quads, params, work, memo, best, best_g)
                mark[g] = tag + 1
                if status:
                    return status, g
    for k in range(n):
        g = cand[k]
        if mark[g] != tag:
            continue
        if best_g >= 0:
            R = geo[g, 3]
            margin = u_max * (1.0 + MARGIN_R) + MARGIN_R * R + MARGIN_D * (lb[k] + R) + MARGIN_ABS
            score = _score(best)
            if lb[k] - margin > score or slab_bound(p, geo, plane, g) - margin > score:
                continue
        status, best_g = _try(g, i, xs, xm, conn, n_quads, params, work, memo, best, best_g)
        mark[g] = tag + 1
        if status:
            return status, g
    return 0, best_g


@numba.njit(cache=True)
def _finish(i, g, best, xs, vs, xm, vm, conn, n_quads, out):
    """Row i of out (ns, 11): weights (4), xi (2), normal (3), gap [m], normal velocity u_N
    [m/s]. A projection outside its facet is clamped as reference.clamp does: local coordinates
    clamped to the facet, weights and gap recomputed there, the normal kept."""
    e, h = best[REC_XI], best[REC_XI + 1]
    w = out[i, 0:4]
    w[:] = best[REC_W : REC_W + 4]
    gap = best[REC_GAP]
    if best[REC_IN] == 0.0:
        if g < n_quads:
            e, h = min(max(e, -1.0), 1.0), min(max(h, -1.0), 1.0)
            w[0], w[1] = 0.25 * ((1 - e) * (1 - h)), 0.25 * ((1 + e) * (1 - h))
            w[2], w[3] = 0.25 * ((1 + e) * (1 + h)), 0.25 * ((1 - e) * (1 + h))
        else:
            b0, b1, b2 = max((1 - e) - h, 0.0), max(e, 0.0), max(h, 0.0)
            total = (b0 + b1) + b2
            w[0], w[1], w[2], w[3] = b0 / total, b1 / total, b2 / total, 0.0
            e, h = w[1], w[2]
        gap = 0.0
        for k in range(3):
            xc = (w[0] * xm[conn[g, 0], k] + w[1] * xm[conn[g, 1], k]) + w[2] * xm[conn[g, 2], k]
            gap += best[REC_N + k] * (xs[k] - (xc + w[3] * xm[conn[g, 3], k]))
    un = 0.0
    for k in range(3):
        vc = (w[0] * vm[conn[g, 0], k] + w[1] * vm[conn[g, 1], k]) + w[2] * vm[conn[g, 2], k]
        un += best[REC_N + k] * (vs[k] - (vc + w[3] * vm[conn[g, 3], k]))
    out[i, 4], out[i, 5] = e, h
    out[i, 6:9] = best[REC_N : REC_N + 3]
    out[i, 9], out[i, 10] = gap, un


@numba.njit(cache=True)
def _in_box(i, xs, r_m, A_m, box, reach, p):
    """Whether node i of xs (global) is within reach [m] of the box (2, 3) of the facets in
    their body's frame (r_m, A_m); its position in that frame into p (3,). The scans test
    it before calling _search_node: a node outside then costs this test only (when
    _search_node tested it, a node outside the box cost 0.42 us, this test 0.01 us:
    docs/notes/2026-11-29-broad-phase.md)."""
    inside_box = True
    for j in range(3):
        p[j] = ((xs[i, 0] - r_m[0]) * A_m[0, j] + (xs[i, 1] - r_m[1]) * A_m[1, j]) + (
            xs[i, 2] - r_m[2]
        ) * A_m[2, j]
        inside_box = inside_box and box[0, j] - reach <= p[j] <= box[1, j] + reach
    return inside_box


@numba.njit(cache=True, inline="always")
def _search_node(
    i,
    xs,
    xm,
    reach,
    rho,
    u_max,
    geo,
    plane,
    conn,
    n_quads,
    adj_ptr,
    adj_idx,
    params,
    lists,
    ref,
    prev,
    mark,
    counter,
    cand,
    lb,
    grid,
    work,
    memo,
    best,
    p,
    cert,
    edges,
):
    """Closest facet of node i of xs (scan_nodes, penetration_scan) within the box (_in_box
    wrote p, its facet-body frame position): its last facet if certified (contact.certificate),
    else the closest among its candidates. Returns (searched: False without any, status, facet).

    The per-node helpers take the fields of FacetSurface and SearchState (unpacked once per
    scan), not the named tuples: a field read from a tuple passed in takes a reference count
    (an atomic increment and decrement per array): passed down to here and to _try, they
    made a scan a quarter slower (docs/notes/2026-11-27-contact-kernels-split.md)."""
    f0 = prev[i]
    if (
        f0 >= 0
        and cert[i, 0] > -np.inf
        and list_holds(i, p, reach, ref)
        and row_distance(p, geo, f0) <= reach + geo[f0, 3]
    ):
        status, g = _try(f0, i, xs[i], xm, conn, n_quads, params, work, memo, best, -1)
        if status:
            return True, status, f0
        if best[REC_IN] == 1.0 and certified(i, p, f0, _score(best), u_max, cert):
            return True, 0, f0
    counter[0] += 2
    tag = counter[0]
    n = node_candidates(i, p, reach, rho, geo, lists, ref, mark, tag, cand, lb, grid)
    if n == 0:
        return False, 0, -1
    status, g = _closest(
        i,
        xs[i],
        p,
        plane,
        n,
        cand,
        lb,
        mark,
        tag,
        prev[i],
        adj_ptr,
        adj_idx,
        geo,
        u_max,
        xm,
        conn,
        n_quads,
        params,
        work,
        memo,
        best,
    )
    if status == 0:
        certify(i, p, g, geo, plane, edges, lists, ref, cert)
    return True, status, g


@numba.njit(cache=True)
def work_arrays():
    """The work arrays of a scan: (C (4, 3), t (2, 3), r (3,), P (4, 3), rec (REC_LEN,)) for
    _try and project_pair, best (REC_LEN,), p (3,)."""
    C, t, r = np.empty((4, 3)), np.empty((2, 3)), np.empty(3)
    P, rec, best = np.empty((4, 3)), np.empty(REC_LEN), np.empty(REC_LEN)
    return (C, t, r, P, rec), best, np.empty(3)


@numba.njit(cache=True)
def scan_nodes(
    xs, vs, xm, vm, r_m, A_m, reach, u_max, surface, state, memo, facet, out, need, keep
):  # fmt: skip
    """Closest facet of every slave node within reach, as PointToSurfaceContact's numpy path
    (box test in the master frame, BroadPhase candidates, project_points, closest_facets,
    clamping) and its normal velocity.

    xs, vs (ns, 3) slave node positions [m] / velocities [m/s]; xm, vm (nm, 3) master surface
    nodes; r_m (3,), A_m (3, 3) master frame; reach [m]; u_max [m] largest master node
    displacement; surface (FacetSurface) the master facets; state (SearchState, ns nodes)
    kept between calls; memo (MemoArrays) the projections kept at the current positions
    (_try). need [m]: a node certified in front of the surface by more than need
    (certificate.far; keep[i] != 0: never) gets no pair (np.inf: every node searched).
    Output: facet (ns,) (-1: none), out (ns, 11) as in _finish.
    Returns (status, facet of the failure, number of pairs)."""
    work, best, p = work_arrays()
    _memo_begin(memo)
    kept = (memo.facets, memo.count, memo.records)
    geo, conn, n_quads, adj_ptr, adj_idx, box, rho, params, grid, plane, edges = surface
    lists, ref, prev, mark, counter, cand, lb, cert = state
    n_pairs = 0
    for i in range(xs.shape[0]):
        facet[i] = -1
        if not _in_box(i, xs, r_m, A_m, box, reach, p):
            continue
        if keep[i] == 0 and far(i, p, need, u_max, cert):
            continue
        searched, status, g = _search_node(
            i,
            xs,
            xm,
            reach,
            rho,
            u_max,
            geo,
            plane,
            conn,
            n_quads,
            adj_ptr,
            adj_idx,
            params,
            lists,
            ref,
            prev,
            mark,
            counter,
            cand,
            lb,
            grid,
            work,
            kept,
            best,
            p,
            cert,
            edges,
        )
        if not searched:
            continue
        if status:
            return status, g, n_pairs
        facet[i] = g
        prev[i] = g
        _finish(i, g, best, xs[i], vs[i], xm, vm, conn, n_quads, out)
        if not out[i, 9] > 0.0:  # on or behind the surface: never far (certificate.far)
            cert[i, 5] = -np.inf
        n_pairs += 1
    return 0, -1, n_pairs


# -- the penetration measure (contact.penetration) ------------------------------------------------
@numba.njit(cache=True)
def _counted_depth(best, radius, edge_tol):
    """Depth -gap [m] of a node whose closest projection is best, on a facet of circumradius
    radius [m], when it counts (penetration_scan: a negative gap, inside the facet or outside
    by a lateral offset sqrt(distance^2 - gap^2) <= edge_tol * radius); -inf when not."""
    gap = best[REC_GAP]
    if gap >= 0.0:
        return -np.inf
    if best[REC_IN] == 0.0:
        lateral2 = best[REC_DIST] ** 2 - gap * gap
        if lateral2 > (edge_tol * radius) ** 2:
            return -np.inf
    return -gap


@numba.njit(cache=True)
def penetration_scan(xs, xm, r_m, A_m, reach, u_max, surface, state, memo, edge_tol, floor):
    """Deepest penetration of the nodes xs (ns, 3) [m] into the facets of `surface`
    (search_state.FacetSurface) over the nodes xm (nm, 3), searched as search.scan_nodes does
    (box test in the facet body's frame r_m, A_m; candidate supersets, warm start, pruning;
    the same search state and memo). u_max [m]: the facet body's largest node displacement.

    A node counts when the closest facet's projection is inside it (surface.params[6], the
    local coordinate tolerance of the constraint pass) or outside it by a lateral offset
    sqrt(distance^2 - gap^2) <= edge_tol * R_g (R_g the facet's circumradius), with a
    negative normal gap; its depth is -gap [m]. Nodes beyond reach of every facet are not
    seen: reach bounds the depth that can be measured.

    floor [m]: only depths above it are sought (0, -1 when none). Warm start: a node whose
    last facet (state.prev) still holds an inside projection with gap >= -depth (depth: the
    floor, or the deepest found so far in this call) is taken at that reading, without a
    search. With gap <= 0 that is exact: a facet that beats it in the search has an inside
    projection with a smaller |gap|, no deeper. With gap = g0 > 0 (in front of the facet),
    another facet could only win with an inside projection behind it at a distance < g0,
    i.e. if the other surface folded back over the facet within g0 of the node (a sheet
    thinner than the node's gap); at a ridge (convex edge) of plane facets the projection
    on the far facet is outside it. Contact surfaces do not fold so: the search is skipped.
    Projections kept as in scan_nodes (memo): the warm start's is not made again in the
    node's search, nor (the same memo and positions) in the next step's scan_nodes. Returns
    (status, facet of a failure, depth [m], node (-1 when none), facet of the deepest node)."""
    work, best, p = work_arrays()
    _memo_begin(memo)
    kept = (memo.facets, memo.count, memo.records)
    geo, conn, n_quads, adj_ptr, adj_idx, box, rho, params, grid, plane, edges = surface
    lists, ref, prev, mark, counter, cand, lb, cert = state
    depth, node, at = floor, -1, -1
    for i in range(xs.shape[0]):
        if not _in_box(i, xs, r_m, A_m, box, reach, p):
            continue
        f0 = prev[i]
        if f0 >= 0:
            status, g = _try(f0, i, xs[i], xm, conn, n_quads, params, work, kept, best, -1)
            if status:
                return status, f0, 0.0, -1, -1
            if best[REC_IN] == 1.0 and best[REC_GAP] >= -depth:
                continue
        searched, status, g = _search_node(
            i,
            xs,
            xm,
            reach,
            rho,
            u_max,
            geo,
            plane,
            conn,
            n_quads,
            adj_ptr,
            adj_idx,
            params,
            lists,
            ref,
            prev,
            mark,
            counter,
            cand,
            lb,
            grid,
            work,
            kept,
            best,
            p,
            cert,
            edges,
        )
        if not searched:
            continue
        if status:
            return status, g, 0.0, -1, -1
        if g < 0:
            continue
        prev[i] = g
        d = _counted_depth(best, geo[g, 3], edge_tol)
        if d > depth:
            depth, node, at = d, i, g
    return 0, -1, depth if node >= 0 else 0.0, node, at
