"""Closed pairs held on the geometry they closed with (position law), compiled (numba).

contact.pairs keeps, for a pair that carried an impulse under the position law, its master
facet, weights and normal (in the master's body frame) and a gap offset; its gap is then
linear in the node positions, g = n . (x_S - sum_P w_P x_P) + off (see contact.pairs' module
doc). Units: metres, seconds.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def _normal_offset(w, n, g, conn, xs_i, vs_i, xm, vm):
    """(n . (x_S - sum_P w_P x_P), n . (x_dot_S - sum_P w_P x_dot_P)) of slave node
    position xs_i and velocity vs_i (3,) against master facet g with weights w (4,)."""
    proj = un = 0.0
    for k in range(3):
        xc = vc = 0.0
        for b in range(4):
            wb = w[b]
            if wb != 0.0:
                xc += wb * xm[conn[g, b], k]
                vc += wb * vm[conn[g, b], k]
        proj += n[k] * (xs_i[k] - xc)
        un += n[k] * (vs_i[k] - vc)
    return proj, un


@numba.njit(cache=True)
def hold_pairs(
    held,
    held_w,
    held_n,
    held_off,
    held_d,
    facet,
    out,
    xs,
    vs,
    xm,
    vm,
    A_m,
    conn,
    tol,
    d_max,
    slide_max=np.inf,
):
    """Closed pairs on the geometry they closed with (pairs.PointToSurfaceContact, position
    law). held[i] >= 0: slave node i keeps master facet held[i], its weights held_w[i] (4,),
    its normal held_n[i] (3,) in the master's body frame and the gap offset held_off[i]; its
    gap is linear in the node positions, g = n . (x_S - sum_P w_P x_P) + off with n = A_m
    held_n[i], and its normal velocity n . (x_dot_S - sum_P w_P x_dot_P). Written over the
    scan's row i of out (weights, normal, gap, u_N; xi kept) and facet[i].

    d = g - g_scan is what the linear gap differs from the scan's exact one; held_d[i] is d
    when the geometry was taken. The pair takes the scan's geometry with the offset that
    keeps g where it is (no jump of the gap, so no work and no impulse: held_d[i] = d), while
    |d| <= d_max, when the contact has moved: d has moved by more than tol [m] since the
    geometry was taken (sliding along a curved master, facets turning), or the slave node has
    slid along the master (a flat face never moves d): the scan's closest facet is not the
    held one, or its projection on the held facet has moved by more than slide_max of the
    facet, measured as half the L1 distance of the weights, sum_P |w_P - w_held_P| / 2 (on a
    quad the move in xi or eta over the facet's parametric width 2, exactly for a move along
    one of them; on a triangle the barycentric distance). Beyond d_max, or when the scan found
    no facet, held[i] = -1 and the scan's row stays (the pair is projected again). Returns
    (taken anew, released)."""
    anew = released = 0
    for i in range(len(held)):
        g = held[i]
        if g < 0:
            continue
        n = np.empty(3)
        for k in range(3):
            n[k] = (A_m[k, 0] * held_n[i, 0] + A_m[k, 1] * held_n[i, 1]) + A_m[k, 2] * held_n[i, 2]
        proj, un = _normal_offset(held_w[i], n, g, conn, xs[i], vs[i], xm, vm)
        gap = held_off[i] + proj
        d = gap - out[i, 9]
        if facet[i] < 0 or abs(d) > d_max:
            held[i] = -1
            released += 1
            continue
        slid = 0.0
        for b in range(4):
            slid += abs(out[i, b] - held_w[i, b])
        if facet[i] != g or 0.5 * slid > slide_max or abs(d - held_d[i]) > tol:
            # the scan's geometry, offset so that the gap stays gap
            g = facet[i]
            for k in range(3):
                n[k] = out[i, 6 + k]
            proj, un = _normal_offset(out[i, 0:4], n, g, conn, xs[i], vs[i], xm, vm)
            held[i] = g
            for b in range(4):
                held_w[i, b] = out[i, b]
            for k in range(3):  # A_m^T n
                held_n[i, k] = (A_m[0, k] * n[0] + A_m[1, k] * n[1]) + A_m[2, k] * n[2]
            held_off[i] = gap - proj
            held_d[i] = d
            anew += 1
        facet[i] = g
        for b in range(4):
            out[i, b] = held_w[i, b]
        out[i, 6], out[i, 7], out[i, 8] = n[0], n[1], n[2]
        out[i, 9], out[i, 10] = gap, un
    return anew, released


@numba.njit(cache=True)
def gap_offsets(idx, facet, out, xs, xm, conn, offsets):
    """offsets[a] = g - n . (x_S - sum_P w_P x_P) of the pairs idx (rows of out): what a
    linear gap in the node positions must add to equal the scan's gap (0 up to round-off for
    a projection on its facet; the clamped ones are computed that way)."""
    for a in range(len(idx)):
        i = idx[a]
        d, _ = _normal_offset(out[i, 0:4], out[i, 6:9], facet[i], conn, xs[i], xs[i], xm, xm)
        offsets[a] = out[i, 9] - d
