"""Broad-phase candidates of a contact node, compiled (numba): the facets within reach of it,
read from a cached superset of them (its candidate list), rebuilt from the facet grid
(search_state.FacetGrid) only when the node has moved far enough to leave it.

The set is exactly geometry.BroadPhase.query's; contact.search calls
:func:`node_candidates` once per node and scan. Units: metres.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def row_distance(p, c, k):
    """|p - c[k, :3]| [m]: p (3,) and the point in the first three entries of row k of c
    (a facet's centroid, a node's reference position). Row k is read in place, not as a
    view c[k]: a view takes a reference count (two atomic operations), which cost a scan a
    third of its time when made per candidate facet."""
    return np.sqrt((p[0] - c[k, 0]) ** 2 + (p[1] - c[k, 1]) ** 2 + (p[2] - c[k, 2]) ** 2)


@numba.njit(cache=True)
def _refresh_list(i, p, reach, rho, geo, lists, ref, gmeta, gdims, gstart, gfacets):
    """Candidate superset of node i: facets g with |p - c_g| - R_g <= reach + rho (geo (nf, 4):
    centroid, circumradius), stored in lists[i] (count first; -1 when it overflows: all
    facets then); ref[i] = (p, reach + rho). The facets come from the cells of the facet grid
    (search_state.FacetGrid: gmeta = origin, cell edge, largest R; gdims; CSR gstart,
    gfacets) within reach + rho + R_max of p: a node's rebuild reads the facets about it,
    not all of them."""
    radius = reach + rho
    cap = lists.shape[1] - 1
    n = 0
    edge = gmeta[3]
    lo = np.empty(3, dtype=np.int64)
    hi = np.empty(3, dtype=np.int64)
    for j in range(3):
        top = gdims[j] - 1.0
        # clipped to the grid in floating point, then truncated (= floor of a value >= 0)
        lo[j] = np.int64(min(max((p[j] - radius - gmeta[4] - gmeta[j]) / edge, 0.0), top))
        hi[j] = np.int64(min(max((p[j] + radius + gmeta[4] - gmeta[j]) / edge, 0.0), top))
    overflow = False
    for ci in range(lo[0], hi[0] + 1):
        for cj in range(lo[1], hi[1] + 1):
            for ck in range(lo[2], hi[2] + 1):
                cell = (ci * gdims[1] + cj) * gdims[2] + ck
                for e in range(gstart[cell], gstart[cell + 1]):
                    g = gfacets[e]
                    if row_distance(p, geo, g) - geo[g, 3] <= radius:
                        if n == cap:
                            overflow = True
                            break
                        lists[i, 1 + n] = g
                        n += 1
                if overflow:
                    break
            if overflow:
                break
        if overflow:
            break
    lists[i, 0] = -1 if overflow else n
    ref[i, 0], ref[i, 1], ref[i, 2], ref[i, 3] = p[0], p[1], p[2], radius


@numba.njit(cache=True)
def node_candidates(i, p, reach, rho, geo, lists, ref, mark, tag, cand, lb, grid):
    """Broad-phase candidates of node i, exactly BroadPhase.query's set {g : |p - c_g| <=
    reach + R_g}, from its cached superset; the superset is rebuilt when the node has moved
    so far (|p - p_ref| + reach > radius_ref, with a round-off margin) that it may miss one.
    Marks mark[g] = tag, writes cand[:n] and lower bounds lb[:n] = |p - c_g| - R_g [m].
    Returns n."""
    radius = ref[i, 3]
    moved = row_distance(p, ref, i)
    if radius < 0.0 or moved + reach > radius - (1e-12 + 1e-9 * radius):
        _refresh_list(i, p, reach, rho, geo, lists, ref, grid[0], grid[1], grid[2], grid[3])
    n_list = lists[i, 0]
    n_all = geo.shape[0] if n_list < 0 else n_list
    n = 0
    for k in range(n_all):
        g = k if n_list < 0 else lists[i, 1 + k]
        d = row_distance(p, geo, g)
        if d <= reach + geo[g, 3]:
            mark[g] = tag
            cand[n] = g
            lb[n] = d - geo[g, 3]
            n += 1
    return n
