"""Lower bounds of a node's distance to facets, and the warm start's certificate, compiled.

contact.search finds a node's closest facet among its broad-phase candidates: the previous
facet f0 first, then every other candidate unless a lower bound of its distance (the facet's
ball or its slab, :func:`slab_bound`) minus a margin exceeds the best score found (it cannot
win). On a node whose f0 still holds an inside projection, that loop tries f0 alone and only
tests the bounds of the others (on sphere_block, 20 candidates a node read, 0.85 us a node).

The certificate does the same test once for several scans. After a full search of node i
with winner g, it keeps C_i = min over every facet h != g of the node's candidate superset of
(a lower bound of the distance from p_i to h - the margin's parts that do not depend on the
motion), p_i the node's position then; the bound is the largest of the ball's, slab_bound and
triangle_bound (the slab alone gives a far node's neighbour facet the node's own gap: no
certificate). At a later scan, with the node at p and the facet body's largest node
displacement u_max, every such bound has fallen by at most |p - p_i| (a distance to a convex
set is 1-Lipschitz in p). So while the superset still holds every candidate (the node has not
moved so far that node_candidates would rebuild it), f0 = g is a candidate, its projection is
inside with score s, and C_i - |p - p_i| - u_max (with round-off allowances) > s, the search
would prune every other candidate: it tries f0 alone, and :func:`certified` says so without
reading the candidates. Results, kept projections and failures are those of the search bit for
bit (tests/test_contact_certificate.py).

The same bounds give D_i, a lower bound of the node's distance to the whole surface: a node
in front of it by more than its motion since plus the largest gap any consumer of the call
can read (`far`) needs no pair at all (search.scan_nodes' `need`, passed by
pairs.PointToSurfaceContact: the rows' window, the look-ahead's horizon).

Units: metres.
"""

from __future__ import annotations

import numba
import numpy as np

from flexmvm.contact.candidate_lists import row_distance

#: relative and absolute allowances of the search's pruning margin (search._closest), also
#: taken off the certificate: 1e-5 of the facet's circumradius, 1e-9 of the distance, 1e-15 m
MARGIN_R, MARGIN_D, MARGIN_ABS = 1e-5, 1e-9, 1e-15

#: |u_N| <= |v_S - v_C| <= sqrt(3) (the largest slave plus the largest master velocity
#: component: the reach rule's speed of pairs.PointToSurfaceContact), with a round-off margin:
#: a pair of gap g can close within a time t only if g <= t UN_SPEED speed (far's need)
UN_SPEED = np.sqrt(3.0) * (1.0 + 1e-6)


@numba.njit(cache=True)
def slab_bound(p, geo, plane, g):
    """Lower bound [m] of the distance from p (3,) to undeformed facet g, centroid and
    circumradius geo[g], unit normal and half-thickness plane[g] (search_state.facet_planes;
    rows read in place: candidate_lists.row_distance): the distance to the cylinder
    |n . (x - c)| <= t, |x - c - (n . (x - c)) n| <= R, which holds the facet,
    sqrt(max(|h| - t, 0)^2 + max(l - R, 0)^2) with h, l the normal and lateral offsets of p
    from c; at least the ball's |p - c| - R."""
    d0, d1, d2 = p[0] - geo[g, 0], p[1] - geo[g, 1], p[2] - geo[g, 2]
    h = (d0 * plane[g, 0] + d1 * plane[g, 1]) + d2 * plane[g, 2]
    dd = (d0 * d0 + d1 * d1) + d2 * d2
    a = max(abs(h) - plane[g, 3], 0.0)
    b = max(np.sqrt(max(dd - h * h, 0.0)) - geo[g, 3], 0.0)
    return max(np.sqrt(a * a + b * b), np.sqrt(dd) - geo[g, 3])


@numba.njit(cache=True)
def triangle_bound(p, geo, plane, edges, g):
    """Lower bound [m] of the distance from p (3,) to undeformed triangle g: sqrt(a^2 + b^2)
    with a = max(|n . (p - c)| - t, 0) the offset from its slab (plane[g]: unit normal n,
    half-thickness t; c its centroid geo[g]) and b = max(0, max_e m_e . p - o_e) the offset
    beyond its edges' half-planes (edges[g], search_state.facet_edges; 0 for a quad). The
    triangle lies in the set {|n . (x - c)| <= t, m_e . x <= o_e}, whose normal and in-plane
    conditions separate (m_e is normal to n): the distance to it is at least sqrt(a^2 + b^2).
    Where a node's foot point lies beyond the edge of a neighbouring facet, this is nearly
    its distance to that facet; slab_bound gives only its height above the plane."""
    d0, d1, d2 = p[0] - geo[g, 0], p[1] - geo[g, 1], p[2] - geo[g, 2]
    a = max(abs((d0 * plane[g, 0] + d1 * plane[g, 1]) + d2 * plane[g, 2]) - plane[g, 3], 0.0)
    b = 0.0
    for e in range(3):
        m = edges[g, e]
        b = max(b, ((m[0] * p[0] + m[1] * p[1]) + m[2] * p[2]) - m[3])
    return np.sqrt(a * a + b * b)


@numba.njit(cache=True)
def list_holds(i, p, reach, ref):
    """Whether node i's candidate superset (ref: the position and radius it was built for)
    still holds every facet within reach of p: node_candidates' rebuild test, negated."""
    radius = ref[i, 3]
    if radius < 0.0:
        return False
    return not (row_distance(p, ref, i) + reach > radius - (1e-12 + 1e-9 * radius))


@numba.njit(cache=True)
def certify(i, p, g, geo, plane, edges, lists, ref, cert):
    """After a full search of node i (at p, its position in the facet body's frame) that
    chose facet g: cert[i] = (C_i, p, g, D_i) (module doc); C_i = -inf (no certificate) when
    g < 0 or the superset overflowed (all facets are candidates), +inf when g is its only
    facet. Each facet's bound is the largest of its ball's, slab_bound and triangle_bound,
    the latter two computed only where the former would lower the minimum. D_i [m]: a lower
    bound of the node's distance to the whole surface, min(C_i, g's own bound, the facets
    beyond the superset's radius ref[i, 3] about ref[i, :3]) (far; -inf with C_i)."""
    cert[i, 0] = -np.inf
    cert[i, 5] = -np.inf
    n_list = lists[i, 0]
    if g < 0 or n_list < 0:
        return
    low = np.inf
    for k in range(n_list):
        h = lists[i, 1 + k]
        if h == g:
            continue
        R = geo[h, 3]
        lb = row_distance(p, geo, h) - R
        cut = MARGIN_R * R + MARGIN_D * (lb + R) + MARGIN_ABS
        if lb - cut < low:
            v = slab_bound(p, geo, plane, h) - cut
            if v < low:
                v = max(v, triangle_bound(p, geo, plane, edges, h) - cut)
            low = min(low, v)
    cert[i, 0] = low
    cert[i, 1], cert[i, 2], cert[i, 3] = p[0], p[1], p[2]
    cert[i, 4] = g
    R = geo[g, 3]
    own = max(slab_bound(p, geo, plane, g), triangle_bound(p, geo, plane, edges, g))
    own -= MARGIN_R * R + MARGIN_D * (abs(own) + R) + MARGIN_ABS
    beyond = ref[i, 3] - row_distance(p, ref, i) - (1e-12 + 1e-9 * ref[i, 3])
    cert[i, 5] = min(low, own, beyond)


@numba.njit(cache=True)
def certified(i, p, f0, score, u_max, cert):
    """Whether the search of node i at p, whose last facet f0 holds an inside projection with
    score [m] (search._score), would prune every other candidate (module doc); u_max [m] the
    facet body's largest node displacement. The caller has checked list_holds."""
    low = cert[i, 0]
    if not low > -np.inf or cert[i, 4] != f0:
        return False
    return low == np.inf or low - _slack(i, p, u_max, low, score, cert) > score


@numba.njit(cache=True)
def _slack(i, p, u_max, low, than, cert):
    """What a bound ``low`` [m] kept at node i's position p_i = cert[i, 1:4] may have fallen by
    at p, compared with ``than`` [m]: the node's motion |p - p_i| and the facets' u_max, with
    the round-off allowances (certified, far)."""
    moved = np.sqrt((p[0] - cert[i, 1]) ** 2 + (p[1] - cert[i, 2]) ** 2 + (p[2] - cert[i, 3]) ** 2)
    slack = u_max * (1.0 + MARGIN_R) + moved * (1.0 + MARGIN_D)
    slack += MARGIN_D * (abs(low) + moved + than) + MARGIN_ABS
    return slack


@numba.njit(cache=True)
def far(i, p, need, u_max, cert):
    """Whether node i, now at p, is certainly in front of the surface by more than need [m]:
    D_i (certify: a lower bound of its distance to the whole surface at p_i, where its gap
    was positive: the scan sets D_i = -inf otherwise) less |p - p_i| and u_max (with the
    round-off allowances) exceeds need. The ball about p_i of radius D_i - u_max holds no
    point of the surface, so p, inside it, is on p_i's side, at a distance over need: a pair
    of it would have a gap over need. pairs.PointToSurfaceContact passes the largest gap a
    pair can need in a call (a row's window, the look-ahead's horizon), so that the rows and
    the look-ahead's sign are those of the search of every node."""
    low = cert[i, 5]
    if not low > -np.inf or not need < np.inf:
        return False
    return low - _slack(i, p, u_max, low, need, cert) > need
