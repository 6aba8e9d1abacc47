"""Point-to-surface contact pairs as unilateral constraints (seed eq. 7-10).

Slave nodes of one body against master facets of another. Each step: positions of the slave
nodes and the master surface (current configuration), broad phase in the master body frame,
closest-point projection, normal gap g = n . (x_S - sum_P N^P x^P). Pairs predicted to close
within the step (g + h u_N <= gap_tol) become rows of Phi_c,

    Phi_c v = n . (x_dot_S - sum_P N^P x_dot_P)      (normal relative velocity u_N)

with the Moreau condition u_N(v+) >= beta max(0, -g)/h, lambda >= 0 (see integrate.midpoint).
Bonded contact (seed eq. 7, all three components) locks a pair once it has carried a
compressive impulse: three equality rows x_S - x_C = 0 at the frozen shape functions, until
the normal component of its impulse would turn tensile.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np
import scipy.sparse as sp

from flexmvm.constraints.rows import Rows
from flexmvm.contact.geometry import BroadPhase, MasterSurface, closest_facets, project_points
from flexmvm.errors import InputError
from flexmvm.integrate.midpoint import PENETRATION_RECOVERY
from flexmvm.integrate.system import ContactProvider, ContactRows


class ContactKind(Enum):
    FRICTIONLESS = "frictionless"
    BONDED = "bonded"


@dataclass
class _Kinematics:
    x_slave: np.ndarray        # (ns, 3)
    v_slave: np.ndarray        # (ns, 3)
    x_master: np.ndarray       # (n_master_nodes_total, 3), filled on the surface nodes
    v_master: np.ndarray


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
    sel = sp.csr_matrix((data.ravel(), (np.repeat(np.arange(m), 3 * k), cols.ravel())),
                        shape=(m, 3 * len(body.X)))
    q = sel @ body.psi
    q = q.toarray() if sp.issparse(q) else np.asarray(q)
    return frame, q, sel


def _clamp(proj, out, x_slave, x_master, n_quads):
    """Replace the projections flagged `out` by the closest point of their facet: local
    coordinates clamped to the facet, shape functions and gap recomputed there."""
    xi = proj.xi.copy()
    w = proj.weights.copy()
    quad = out & (proj.facet < n_quads)
    tri = out & ~(proj.facet < n_quads)
    if quad.any():
        e, h = np.clip(xi[quad, 0], -1, 1), np.clip(xi[quad, 1], -1, 1)
        w[quad] = 0.25 * np.column_stack([(1 - e) * (1 - h), (1 + e) * (1 - h), (1 + e) * (1 + h), (1 - e) * (1 + h)])
        xi[quad] = np.column_stack([e, h])
    if tri.any():
        bary = np.clip(np.column_stack([1 - xi[tri, 0] - xi[tri, 1], xi[tri, 0], xi[tri, 1]]), 0, None)
        bary /= bary.sum(axis=1, keepdims=True)
        w[tri] = np.column_stack([bary, np.zeros(len(bary))])
        xi[tri] = bary[:, 1:]
    xc = np.einsum("mk,mki->mi", w, x_master[proj.nodes])
    gap = np.einsum("mi,mi->m", proj.normal, x_slave[proj.point] - xc)
    return type(proj)(proj.point, proj.facet, proj.nodes, w, xi, proj.normal,
                      np.where(out, gap, proj.gap), np.ones_like(proj.inside), proj.distance)


class PointToSurfaceContact(ContactProvider):
    """Contact of slave nodes (body `slave`) with master facets (body `master`)."""

    def __init__(self, bodies, slave: int, slave_nodes, master: int, surface: MasterSurface,
                 kind: ContactKind = ContactKind.FRICTIONLESS, search_radius_m: float = 1e-3,
                 gap_tol_m: float = 1e-9, name: str = "contact"):
        if slave == master:
            raise InputError(f"{name}: slave and master must be different bodies")
        self.slave, self.master = slave, master
        self.slave_nodes = np.unique(np.asarray(slave_nodes, dtype=np.int64))
        n_s, n_m = len(bodies[slave].X), len(bodies[master].X)
        if self.slave_nodes.size == 0 or self.slave_nodes.max() >= n_s:
            raise InputError(f"{name}: slave nodes must be node ids of body {bodies[slave].name!r}")
        if surface.connectivity.max() >= n_m:
            raise InputError(f"{name}: master facets refer to nodes outside body {bodies[master].name!r}")
        self.surface = surface
        self.master_nodes = surface.nodes()
        self.broad = BroadPhase(bodies[master].X, surface)
        Xs = bodies[master].X[self.master_nodes]
        self._box = (Xs.min(axis=0), Xs.max(axis=0))
        self.kind = kind
        self.search_radius = float(search_radius_m)
        self.gap_tol = float(gap_tol_m)
        self.name = name
        self._bonds: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    # -- geometry -----------------------------------------------------------------------------
    def _kinematics(self, bodies, states) -> _Kinematics:
        bs, bm = bodies[self.slave], bodies[self.master]
        ss, sm = states[self.slave], states[self.master]
        xs = bs.node_positions(self.slave_nodes, ss.r, ss.A, ss.q)
        vs = bs.node_velocities(self.slave_nodes, ss.A, ss.q, ss.v)
        xm = np.zeros((len(bm.X), 3))
        vm = np.zeros((len(bm.X), 3))
        xm[self.master_nodes] = bm.node_positions(self.master_nodes, sm.r, sm.A, sm.q)
        vm[self.master_nodes] = bm.node_velocities(self.master_nodes, sm.A, sm.q, sm.v)
        return _Kinematics(xs, vs, xm, vm)

    def _projection(self, bodies, states, kin: _Kinematics, reach: float):
        """Closest facet of every slave node within reach of the master surface. A node that
        falls outside every candidate facet (above a vertex of a convex surface, or beside an
        edge of a dented, locally concave one) is kept with its clamped projection, so a
        penetration can never go unseen."""
        sm = states[self.master]
        local = (kin.x_slave - sm.r) @ sm.A
        lo, hi = self._box
        near = np.nonzero(np.all((local >= lo - reach) & (local <= hi + reach), axis=1))[0]
        if near.size == 0:
            return None
        pt, fc = self.broad.query(local[near], reach)
        if pt.size == 0:
            return None
        proj = closest_facets(project_points(kin.x_slave, kin.x_master, self.surface, (near[pt], fc)))
        if not len(proj):
            return None
        out = ~proj.inside
        if out.any():
            proj = _clamp(proj, out, kin.x_slave, kin.x_master, self.surface.n_quads)
        return proj

    def _normal_velocity(self, kin, proj) -> np.ndarray:
        vc = np.einsum("mk,mki->mi", proj.weights, kin.v_master[proj.nodes])
        return np.einsum("mi,mi->m", proj.normal, kin.v_slave[proj.point] - vc)

    def min_gap_ahead(self, bodies, states, horizon_s: float) -> float:
        kin = self._kinematics(bodies, states)
        speed = float(np.abs(kin.v_slave).max() + np.abs(kin.v_master).max())
        proj = self._projection(bodies, states, kin, self.search_radius + speed * horizon_s)
        if proj is None:
            return np.inf
        if self._bonds:
            return -np.inf
        u_n = self._normal_velocity(kin, proj)
        return float(np.min(proj.gap + horizon_s * np.minimum(u_n, 0.0)))

    # -- constraint rows ----------------------------------------------------------------------
    def candidate_rows(self, bodies, states, h: float) -> ContactRows:
        kin = self._kinematics(bodies, states)
        speed = float(np.abs(kin.v_slave).max() + np.abs(kin.v_master).max())
        proj = self._projection(bodies, states, kin, self.search_radius + 2 * speed * h)
        eq_nodes, eq_w, eq_dirs, eq_lower, eq_keys = self._bond_rows(kin)
        if proj is not None:
            bonded = np.isin(self.slave_nodes[proj.point], list(self._bonds))
            u_n = self._normal_velocity(kin, proj)
            active = (proj.gap + h * u_n <= self.gap_tol) & ~bonded
            proj = proj.take(active)
        if (proj is None or len(proj) == 0) and not eq_keys:
            return ContactRows.empty()
        m_n = 0 if proj is None else len(proj)
        slave_nodes = np.concatenate([eq_nodes, self.slave_nodes[proj.point] if m_n else []]).astype(np.int64)
        master_nodes = np.vstack([eq_w[1], proj.nodes if m_n else np.zeros((0, 4), np.int64)]).astype(np.int64)
        master_w = np.vstack([eq_w[0], proj.weights if m_n else np.zeros((0, 4))])
        dirs = np.vstack([eq_dirs, proj.normal if m_n else np.zeros((0, 3))])
        m = len(dirs)
        rows = Rows(m, {})
        sf, sq, ssel = body_rows(bodies[self.slave], states[self.slave], slave_nodes[:, None],
                                 np.ones((m, 1)), dirs)
        mf, mq, msel = body_rows(bodies[self.master], states[self.master], master_nodes, master_w, dirs)
        rows.blocks[self.slave] = (sf, sq)
        rows.blocks[self.master] = (-mf, -mq)
        if ssel is not None:
            rows.nodal[self.slave] = ssel
        if msel is not None:
            rows.nodal[self.master] = -msel
        gaps = proj.gap if m_n else np.zeros(0)
        lower_n = PENETRATION_RECOVERY * np.maximum(0.0, -gaps) / h
        keys = eq_keys + ([(self.name, int(s), int(f)) for s, f in
                           zip(self.slave_nodes[proj.point], proj.facet)] if m_n else [])
        self._last = (proj, len(eq_keys))
        weight = np.ones(m)
        if eq_keys:  # bond rows x, y, z: their compressive part is the component along the normal
            weight[: len(eq_keys)] = [self._bond_normal[k[2]][k[3]] for k in eq_keys]
        return ContactRows(rows, np.concatenate([eq_lower, lower_n]), keys, gaps, len(eq_keys), weight)

    def _bond_rows(self, kin):
        """Three equality rows per bonded pair (seed eq. 7): x_S - x_C -> 0."""
        if not self._bonds:
            return (np.zeros(0, np.int64), (np.zeros((0, 4)), np.zeros((0, 4), np.int64)),
                    np.zeros((0, 3)), np.zeros(0), [])
        s_nodes, w_rows, n_rows, dirs, lower, keys = [], [], [], [], [], []
        index = {int(n): i for i, n in enumerate(self.slave_nodes)}
        for s, (nodes, w) in self._bonds.items():
            err = kin.x_slave[index[s]] - w @ kin.x_master[nodes]
            for d, e in enumerate(np.eye(3)):
                s_nodes.append(s)
                w_rows.append(w)
                n_rows.append(nodes)
                dirs.append(e)
                lower.append(-PENETRATION_RECOVERY * err[d] / self._h_last)
                keys.append((self.name, "bond", s, d))
        return (np.array(s_nodes), (np.array(w_rows), np.array(n_rows)), np.array(dirs),
                np.array(lower), keys)

    _h_last = 1.0

    def after_step(self, crows: ContactRows, impulses: np.ndarray, h: float) -> None:
        """Bonded contact: lock pairs that carried a compressive impulse; release a bond
        whose normal impulse component turned tensile."""
        self._h_last = h
        if self.kind is not ContactKind.BONDED:
            return
        proj, n_eq = getattr(self, "_last", (None, 0))
        # release: normal component of the bond impulse (bond rows come in x, y, z triples)
        released = []
        for i in range(0, n_eq, 3):
            s = crows.keys[i][2]
            lam = impulses[i : i + 3]
            normal = self._bond_normal.get(s)
            if normal is not None and lam @ normal < 0.0:
                released.append(s)
        for s in released:
            self._bonds.pop(s, None)
        if proj is None:
            return
        lam_n = impulses[n_eq:]
        for j in np.nonzero(lam_n > 0.0)[0]:
            s = int(self.slave_nodes[proj.point[j]])
            self._bonds[s] = (proj.nodes[j].copy(), proj.weights[j].copy())
            self._bond_normal[s] = proj.normal[j].copy()

    @property
    def _bond_normal(self) -> dict:
        if not hasattr(self, "_bn"):
            self._bn = {}
        return self._bn
