"""Numpy reference of one contact step: node kinematics, projection, constraint rows.

The specification the compiled path (contact.search, contact.nodes, contact.pairs) is
tested against, and the row builder of the rare bonded path. Everything is recomputed from
the states on every call: positions and velocities of the contact nodes through psi,
BroadPhase candidates, project_points, closest_facets, clamping of outside projections.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from flexmvm.contact.geometry import (
    BroadPhase,
    MasterSurface,
    Projection,
    closest_facets,
    project_points,
)


@dataclass
class Kinematics:
    """x_slave, v_slave (ns, 3) [m, m/s]; x_master, v_master (n_master_nodes_total, 3),
    filled on the surface nodes only."""

    x_slave: np.ndarray
    v_slave: np.ndarray
    x_master: np.ndarray
    v_master: np.ndarray

    @property
    def speed(self) -> float:
        """Largest velocity component of a slave plus of a master node [m/s]."""
        return float(np.abs(self.v_slave).max() + np.abs(self.v_master).max())


def kinematics(bodies, states, slave: int, slave_nodes, master: int, master_nodes) -> Kinematics:
    bs, bm = bodies[slave], bodies[master]
    ss, sm = states[slave], states[master]
    xs = bs.node_positions(slave_nodes, ss.r, ss.A, ss.q)
    vs = bs.node_velocities(slave_nodes, ss.A, ss.q, ss.v)
    xm = np.zeros((len(bm.X), 3))
    vm = np.zeros((len(bm.X), 3))
    xm[master_nodes] = bm.node_positions(master_nodes, sm.r, sm.A, sm.q)
    vm[master_nodes] = bm.node_velocities(master_nodes, sm.A, sm.q, sm.v)
    return Kinematics(xs, vs, xm, vm)


def clamp(proj: Projection, out: np.ndarray, x_slave, x_master, n_quads: int) -> Projection:
    """Replace the projections flagged `out` by the closest point of their facet: local
    coordinates clamped to the facet, shape functions and gap recomputed there."""
    xi = proj.xi.copy()
    w = proj.weights.copy()
    quad = out & (proj.facet < n_quads)
    tri = out & ~(proj.facet < n_quads)
    if quad.any():
        e, h = np.clip(xi[quad, 0], -1, 1), np.clip(xi[quad, 1], -1, 1)
        w[quad] = 0.25 * np.column_stack(
            [(1 - e) * (1 - h), (1 + e) * (1 - h), (1 + e) * (1 + h), (1 - e) * (1 + h)]
        )
        xi[quad] = np.column_stack([e, h])
    if tri.any():
        bary = np.clip(
            np.column_stack([1 - xi[tri, 0] - xi[tri, 1], xi[tri, 0], xi[tri, 1]]), 0, None
        )
        bary /= bary.sum(axis=1, keepdims=True)
        w[tri] = np.column_stack([bary, np.zeros(len(bary))])
        xi[tri] = bary[:, 1:]
    xc = np.einsum("mk,mki->mi", w, x_master[proj.nodes])
    gap = np.einsum("mi,mi->m", proj.normal, x_slave[proj.point] - xc)
    return type(proj)(
        proj.point,
        proj.facet,
        proj.nodes,
        w,
        xi,
        proj.normal,
        np.where(out, gap, proj.gap),
        np.ones_like(proj.inside),
        proj.distance,
    )


def projection(
    kin: Kinematics,
    master_state,
    surface: MasterSurface,
    broad: BroadPhase,
    box: tuple[np.ndarray, np.ndarray],
    reach: float,
) -> Projection | None:
    """Closest facet of every slave node within reach of the master surface. A node that
    falls outside every candidate facet (above a vertex of a convex surface, or beside an
    edge of a dented, locally concave one) is kept with its clamped projection, so no slave
    node's penetration goes unseen by the constraint (master nodes are not held; the measure
    of both directions is contact.penetration). None when no node has a candidate."""
    local = (kin.x_slave - master_state.r) @ master_state.A
    lo, hi = box
    near = np.nonzero(np.all((local >= lo - reach) & (local <= hi + reach), axis=1))[0]
    if near.size == 0:
        return None
    pt, fc = broad.query(local[near], reach)
    if pt.size == 0:
        return None
    proj = closest_facets(project_points(kin.x_slave, kin.x_master, surface, (near[pt], fc)))
    if not len(proj):
        return None
    out = ~proj.inside
    if out.any():
        proj = clamp(proj, out, kin.x_slave, kin.x_master, surface.n_quads)
    return proj


def normal_velocity(kin: Kinematics, proj: Projection) -> np.ndarray:
    """u_N = n . (x_dot_S - sum_P N^P x_dot_P) (m,) [m/s]."""
    vc = np.einsum("mk,mki->mi", proj.weights, kin.v_master[proj.nodes])
    return np.einsum("mi,mi->m", proj.normal, kin.v_slave[proj.point] - vc)


def body_rows(body, st, nodes: np.ndarray, weights: np.ndarray, dirs: np.ndarray):
    """Rows d_i^T sum_k w_ik dx_{node_ik}/dv of one body (seed eq. 9), vectorised.

    nodes, weights (m, k); dirs (m, 3) global. Returns frame (m, 6), elastic (m, nq) and the
    nodal selector N (m, 3 n_nodes), elastic = N psi (None for a rigid body).
    """
    m, k = nodes.shape
    dl = dirs @ st.A  # rows: A^T d
    u = body.local_displacements(nodes.ravel(), st.q).reshape(m, k, 3)
    s = body.X[nodes] + u
    sw = np.einsum("mk,mki->mi", weights, s)
    wsum = weights.sum(axis=1)
    frame = np.hstack([dirs * wsum[:, None], np.cross(sw, dl)])
    if not body.nq:
        return frame, np.zeros((m, 0)), None
    cols = (3 * nodes[:, :, None] + np.arange(3)).reshape(m, -1)
    data = (weights[:, :, None] * dl[:, None, :]).reshape(m, -1)
    sel = sp.csr_matrix(
        (data.ravel(), (np.repeat(np.arange(m), 3 * k), cols.ravel())), shape=(m, 3 * len(body.X))
    )
    q = sel @ body.psi
    q = q.toarray() if sp.issparse(q) else np.asarray(q)
    return frame, q, sel
