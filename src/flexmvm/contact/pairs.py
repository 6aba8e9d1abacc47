"""Point-to-surface contact pairs as unilateral constraints (seed eq. 7-10).

Slave nodes of one body against master facets of another. Each step: positions of the slave
nodes and the master surface (current configuration), broad phase in the master body frame,
closest-point projection, normal gap g = n . (x_S - sum_P N^P x^P). Pairs predicted to close
within the step (g + h u_N <= gap_tol) become rows of Phi_c,

    Phi_c v = n . (x_dot_S - sum_P N^P x_dot_P)      (normal relative velocity u_N)

with u_N(v+) >= lower, lambda >= 0 (see integrate.moreau_jean); the contact's law (a
ContactLawSpec, constraints/contact_laws/, one module per law) says which pairs are rows
(`row_window`) and their lower bound (`lower`), u_N- the pair's normal velocity at the start
of the step: the velocity law's Moreau impact law (restitution 0) with a penetration recovery
capped by the closing speed, or the position law's gap at the end of the step (Signorini at
t + h: the law of mass-redistributed contact nodes). Under the position law an open gap gives a
negative bound, which lets the node approach; an end gap g < 0 left by a step is closed within
the next, which does work lambda |g| / h.
Under a law that holds pairs (`holds_pairs`: the position law), frictionless, a pair that
carried an impulse keeps, while it stays closed, the geometry of the step it closed in: its master facet, shape-function weights and
normal (in the master's body frame), its gap taken as linear in the node positions,
g = n . (x_S - sum_P N^P x^P). A closed pair is then a linear holonomic constraint, whose
impulse does no work over a step of the midpoint rule (lambda n . dx = lambda dg = 0), as in
the energy-conserving contact of Laursen and Chawla (1997, IJNME 40) and Armero and Petocz
(1998, CMAME 158), where the gap's variation over the step is exact. Re-projected every step
instead, the contact force of a closed pair turns with the facets' step-scale motion and does
work on it: with both rods Craig-Bampton at theta = 1/2 that work grew the alternation of the
contact region by x 2 in energy per 20 us (docs/contact_law.md). The exact closest-point gap
is still computed: when the linear one has drifted from it by more than gap_tol since the
geometry was taken (sliding along a curved master, facets turning), or when its node has
slid (the scan's closest facet is another one, or its projection has moved more than
HOLD_SLIDE_MAX of the held facet: a node sliding along a flat face never moves the gaps
apart, and the load must follow it), the pair takes the projection's facet, weights and
normal with the offset that keeps its gap (no jump: no impulse, no work), and it goes back to
the projection outright when it opens (no impulse) or when the two gaps are more than
HOLD_DRIFT_MAX gap_tol apart.
Bonded contact (seed eq. 7, all three components) locks a pair once it has carried a
compressive impulse: three equality rows x_S - x_C = 0 at the frozen shape functions, until
the normal component of its impulse would turn tensile. Only slave nodes are held;
`penetration` measures both ways (contact.penetration), master surface nodes against the
slave facets too (given `slave_surface`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from flexmvm.constraints.contact import ContactKind, ContactLaw, ContactRows, FrictionRows
from flexmvm.constraints.rows import Rows
from flexmvm.contact.certificate import UN_SPEED
from flexmvm.contact.geometry import BroadPhase, MasterSurface
from flexmvm.contact.held_pairs import gap_offsets, hold_pairs
from flexmvm.contact.nodes import ContactNodes
from flexmvm.contact.numpy_step import body_rows
from flexmvm.contact.pair_options import pair_options
from flexmvm.contact.pair_rows import active_pairs, predicted_min_gap
from flexmvm.contact.penetration import Penetration, SurfaceMeasure
from flexmvm.contact.projection import DEGENERATE_QUAD, DEGENERATE_TRI
from flexmvm.contact.search import scan_nodes
from flexmvm.contact.search_state import ProjectionMemo, SearchState, facet_surface
from flexmvm.contact.slave_window import MARGIN_PER_SEARCH_RADIUS, WINDOW_MIN_NODES, SlaveWindow
from flexmvm.errors import InputError, SolverError

__all__ = ["PointToSurfaceContact", "body_rows", "tangent_basis"]


@dataclass
class _Active:
    """The active pairs of the last candidate_rows: point (m,) slave index, nodes (m, 4)
    master node ids, weights (m, 4), normal (m, 3)."""

    point: np.ndarray
    nodes: np.ndarray
    weights: np.ndarray
    normal: np.ndarray


#: beta: the fraction of a penetration (or a bond's drift) the rows push back per step,
#: u_N(v+) >= min(beta max(0, -g) / h, max(0, -u_N-)) (Moreau-Jean with a Baumgarte-like
#: position correction, capped by the closing speed so that it adds no restitution)
PENETRATION_RECOVERY = 0.2

#: a law that holds pairs (position): a held pair's linear gap may differ from the exact
#: closest-point gap by this many gap_tol before the pair is projected again (module doc)
HOLD_DRIFT_MAX = 10.0

#: a law that holds pairs: a held pair whose slave node has slid along the master by more than
#: this fraction of the held facet (or onto another facet) takes the scan's geometry, with the
#: offset that keeps its gap (module doc; contact.held_pairs.hold_pairs)
HOLD_SLIDE_MAX = 0.1


class PointToSurfaceContact:
    """Contact of slave nodes (body `slave`) with master facets (body `master`).

    Per call the contact-node kinematics, the search and the rows run in compiled kernels
    (contact.kinematics, contact.search, contact.pair_rows) on arrays kept here; the rows
    equal the numpy reference's (contact.numpy_step) to round-off. The search's state
    (contact.search_state, contact.certificate) never changes a row or the look-ahead."""

    def __init__(
        self,
        bodies,
        slave: int,
        slave_nodes,
        master: int,
        surface: MasterSurface,
        kind: ContactKind = ContactKind.FRICTIONLESS,
        search_radius_m: float = 1e-3,
        gap_tol_m: float = 1e-9,
        name: str = "contact",
        slave_surface: MasterSurface | None = None,
        beta: float = PENETRATION_RECOVERY,
        friction_coefficient: float = 0.0,
        law: ContactLaw = ContactLaw.VELOCITY,
        theta: float | Callable[[float], float] | None = None,
    ):
        if slave == master:
            raise InputError(f"{name}: slave and master must be different bodies")
        self.mu, self.beta, self.law, self.theta = pair_options(
            name, kind, friction_coefficient, beta, law, theta
        )
        # the last candidate rows' pairs and bond-row count
        self._last: tuple[tuple | None, int] = (None, 0)
        self._bond_normal: dict = {}  # bonded slave node -> the normal it was locked with
        self.slave, self.master = slave, master
        self.slave_nodes = np.unique(np.asarray(slave_nodes, dtype=np.int64))
        n_s, n_m = len(bodies[slave].X), len(bodies[master].X)
        if self.slave_nodes.size == 0 or self.slave_nodes.max() >= n_s:
            raise InputError(f"{name}: slave nodes must be node ids of body {bodies[slave].name!r}")
        if surface.connectivity.max() >= n_m:
            raise InputError(
                f"{name}: master facets refer to nodes outside body {bodies[master].name!r}"
            )
        self.surface = surface
        self.master_nodes = surface.nodes()
        self.broad = BroadPhase(bodies[master].X, surface)
        Xs = bodies[master].X[self.master_nodes]
        self._box = (Xs.min(axis=0), Xs.max(axis=0))
        self.kind = kind
        self.search_radius = float(search_radius_m)
        self.gap_tol = float(gap_tol_m)
        self.name = name
        self._who = f"{name} (body {bodies[slave].name!r} on {bodies[master].name!r})"
        self._bonds: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._setup(bodies)
        if slave_surface is not None and slave_surface.connectivity.max() >= n_s:
            raise InputError(
                f"{name}: slave facets refer to nodes outside body {bodies[slave].name!r}"
            )
        self._window = None  # the slave nodes moved per step (contact.slave_window)
        if len(self.slave_nodes) >= WINDOW_MIN_NODES:
            r_f = 0.0
            if slave_surface is not None:
                r_f = float(BroadPhase(bodies[slave].X, slave_surface).circumradius.max())
            self._window = SlaveWindow(
                self._s,
                self._facets.box,
                self.search_radius,
                r_f,
                MARGIN_PER_SEARCH_RADIUS * self.search_radius,
            )
        self._measure = SurfaceMeasure(
            bodies,
            slave,
            self.slave_nodes,
            slave_surface,
            master,
            surface,
            self.search_radius,
            shared=(self._s, self._m, self._memo),
        )

    def _setup(self, bodies) -> None:
        """Gathered node data, facet geometry and the search state (see search.scan_nodes)."""
        self._s = ContactNodes(bodies[self.slave], self.slave_nodes)
        self._m = ContactNodes(bodies[self.master], self.master_nodes)
        self._conn = np.searchsorted(self.master_nodes, self.surface.connectivity).astype(np.int64)
        self._facets = facet_surface(
            bodies[self.master].X, self.surface, self._conn, self.broad, self.search_radius
        )
        ns, nf = len(self.slave_nodes), self.surface.n_facets
        self._search = SearchState.empty(ns, nf)
        self._memo = ProjectionMemo(self._s, self._m, self._conn, self._facets.params)
        self._facet = np.full(ns, -1, dtype=np.int64)
        self._out = np.zeros((ns, 11))
        self._idx = np.zeros(ns, dtype=np.int64)
        self._bonded = np.zeros(ns, dtype=np.bool_)
        self._mlocal = np.full(len(bodies[self.master].X), -1, dtype=np.int64)
        self._mlocal[self.master_nodes] = np.arange(len(self.master_nodes))
        # closed pairs on the geometry they closed with (a law that holds pairs, frictionless:
        # module doc): facet (-1: none held), weights, normal in the master frame, gap offset
        self._holds = self.law.spec.holds_pairs and self.mu == 0.0
        self._held = np.full(ns, -1, dtype=np.int64)
        self._held_w = np.zeros((ns, 4))
        self._held_n = np.zeros((ns, 3))
        self._held_off = np.zeros(ns)
        self._held_d = np.zeros(ns)
        # the last candidate rows': (idx, facets, w, normal, off, A_m)
        self._row_geometry: tuple | None = None

    # -- geometry -----------------------------------------------------------------------------
    def _kinematics(self, states, reach=None) -> float:
        """Node positions / velocities of both bodies; returns the speed of the reach rule:
        largest slave plus largest master velocity component [m/s], the slave's over its
        window when it has one (the nodes that can reach the master). reach(speed) [m]: the
        reach of the call, which the slave window (if any) is made to cover; np.inf: every
        slave node moved."""
        vs, u_s = self._s.update(states[self.slave])
        vm, self._u_max = self._m.update(states[self.master])
        if self._window is not None and reach is not None:
            need = self._window.need(reach(float(vs + vm)), u_s, self._u_max)
            keep = np.flatnonzero((self._held >= 0) | self._bonded)
            if self._window.ensure(states[self.slave], states[self.master], need, keep):
                vs, _ = self._s.update(states[self.slave])  # the new window's
        return float(vs + vm)

    def _scan(self, states, reach: float, need: float) -> int:
        """Closest facet, gap and u_N of the slave nodes within reach, but those certified in
        front by more than need [m] (never held or bonded ones), into _facet, _out: n pairs."""
        sm = states[self.master]
        m = self._m
        d0, u_rel = m.displacement_offset()  # the facets as moved by d0, at most u_rel more
        status, facet, n = scan_nodes(
            self._s.x,
            self._s.xd,
            m.x,
            m.xd,
            sm.r + sm.A @ d0,
            sm.A,
            reach,
            u_rel,
            self._facets,
            self._search,
            self._memo.arrays,
            self._facet,
            self._out,
            need,
            (self._held >= 0) | self._bonded,
        )
        if status:
            raise SolverError(f"{self._who}: " + _failure(status, facet))
        return n

    def rebind(self, index: int, body) -> None:
        """Body ``index``'s basis changed (a moving region's switch): its nodes' psi rows here
        and in the penetration measure gathered again from ``body``, in place."""
        for nodes, which in ((self._s, self.slave), (self._m, self.master)):
            if which == index:
                nodes.rebind(body)
        self._measure.rebind(index, body)

    def min_gap_ahead(self, bodies, states, horizon_s: float) -> float:
        speed = self._kinematics(states, lambda v: self.search_radius + v * horizon_s)
        need = np.inf if self._bonds else UN_SPEED * speed * horizon_s  # gap <= horizon |u_N|
        if self._scan(states, self.search_radius + speed * horizon_s, need) == 0:
            return np.inf
        if self._bonds:
            return -np.inf
        return float(predicted_min_gap(self._facet, self._out, horizon_s))

    # -- penetration ----------------------------------------------------------------------------
    def penetration(self, bodies, states, deep: bool = False, floors=None) -> list[Penetration]:
        """Deepest penetration per direction at `states` (contact.penetration): slave nodes
        into the master surface, then (with a slave_surface) master surface nodes into the
        slave surface. deep: the start check's reach, over both surfaces' extent. floors (per
        direction [m], default 0): only deeper penetrations are sought; shallower read 0."""
        if self._window is not None:
            self._kinematics(states, lambda v: np.inf if deep else self.search_radius + self._u_max)
        out = []
        for status, facet, pen in self._measure.measure(states, deep, floors):
            if status:
                raise SolverError(f"{self._who}: " + _failure(status, facet))
            out.append(pen)
        return out

    # -- constraint rows ----------------------------------------------------------------------
    def candidate_rows(self, bodies, states, h: float) -> ContactRows:
        speed = self._kinematics(states, lambda v: self.search_radius + 2 * v * h)
        hp, tol = self.law.spec.row_window(h, self.gap_tol, speed)  # rows: g + hp u_N- <= tol
        self._scan(states, self.search_radius + 2 * speed * h, tol + abs(hp) * UN_SPEED * speed)
        A_m = states[self.master].A
        if self._holds:
            hold_pairs(
                self._held,
                self._held_w,
                self._held_n,
                self._held_off,
                self._held_d,
                self._facet,
                self._out,
                self._s.x,
                self._s.xd,
                self._m.x,
                self._m.xd,
                A_m,
                self._conn,
                self.gap_tol,
                HOLD_DRIFT_MAX * self.gap_tol,
                HOLD_SLIDE_MAX,
            )
        m_n, idx, slave_ids, facets, normal, gaps, u_n, s_pairs, m_pairs = active_pairs(
            self._facet,
            self._out,
            hp,
            tol,
            self._bonded,
            self._idx,
            self._conn,
            self.surface.n_quads,
            self.slave_nodes,
        )
        eq = self._bond_rows(h) if self._bonds else None
        if m_n == 0 and eq is None:
            self._last = (None, 0)
            self._row_geometry = None
            return ContactRows.empty()
        m_nodes, m_w = m_pairs[0], m_pairs[1]
        # the pairs for after_step (bonded contact): (slave index, master facet nodes (local),
        # weights, normal)
        self._last = ((idx, m_nodes, m_w, normal), 0 if eq is None else len(eq[4]))
        if self._holds:
            off = np.empty(m_n)
            gap_offsets(idx, self._facet, self._out, self._s.x, self._m.x, self._conn, off)
            self._row_geometry = (idx, facets, m_w, normal, off, A_m.copy())
        if eq is None:
            lower = self._lower(gaps, u_n, h)
            keys = list(zip([self.name] * m_n, slave_ids.tolist(), facets.tolist()))
            if self.mu > 0.0:
                return self._friction_rows(states, s_pairs, m_pairs, normal, lower, keys, gaps)
            rows = Rows(m_n, {})
            self._fill_rows(rows, states, s_pairs, m_pairs, normal)
            return ContactRows(rows, lower, keys, gaps, 0, np.ones(m_n))
        return self._rows_with_bonds(bodies, states, h, eq, idx, m_nodes, m_w, normal, gaps, u_n)

    def _lower(self, gaps: np.ndarray, u_n: np.ndarray, h: float) -> np.ndarray:
        """Lower bounds of u_N+ of normal rows with gaps g and start normal velocities u_N-:
        the law's (ContactLawSpec.lower; velocity: min(beta max(0, -g) / h, max(0, -u_N-)),
        position: -(g + h (1 - theta) u_N-) / (theta h))."""
        return self.law.spec.lower(gaps, u_n, h, self.beta, self.theta)

    def _friction_rows(self, states, slave_pairs, master_pairs, normal, lower, keys, gaps):
        """Rows [normal (m_n) | tangent 1 (m_n) | tangent 2 (m_n)] of the active pairs: the
        tangent rows act on the same nodes and weights as the normal row, along two
        orthonormal tangents of the master facet normal (tangent_basis)."""
        m_n = len(normal)
        t1, t2 = tangent_basis(normal)
        rows = Rows(3 * m_n, {})
        tile = lambda pairs: tuple(np.concatenate([p, p, p]) for p in pairs)
        self._fill_rows(
            rows, states, tile(slave_pairs), tile(master_pairs), np.vstack([normal, t1, t2])
        )
        ids = np.arange(m_n)
        friction = FrictionRows(
            ids,
            np.column_stack([m_n + ids, 2 * m_n + ids]),
            np.full(m_n, self.mu),
            np.stack([t1, t2], axis=1),
        )
        keys = keys + [k + (f"t{j}",) for j in (1, 2) for k in keys]
        weight = np.concatenate([np.ones(m_n), np.zeros(2 * m_n)])
        return ContactRows(
            rows, np.concatenate([lower, np.zeros(2 * m_n)]), keys, gaps, 0, weight, friction
        )

    def _fill_rows(self, rows: Rows, states, slave_pairs: tuple, master_pairs: tuple, dirs) -> None:
        """Rows of both bodies, compiled (slave +, master -), with their nodal selectors."""
        for b, nodes, pairs, sign in (
            (self.slave, self._s, slave_pairs, 1.0),
            (self.master, self._m, master_pairs, -1.0),
        ):
            pair_nodes, pair_w, pair_kc = pairs  # local ids, weights, nodes per row
            frame, elastic, sel = nodes.rows(pair_nodes, pair_w, pair_kc, dirs, states[b].A, sign)
            rows.blocks[b] = (frame, elastic)
            if sel is not None:
                rows.nodal[b] = sel

    def _rows_with_bonds(self, bodies, states, h, eq, idx, m_nodes, m_w, normal, gaps, u_n):
        """Bonded path (rare): the bond equality rows, then the normal rows, built with the
        numpy row builder."""
        eq_nodes, eq_w, eq_dirs, eq_lower, eq_keys = eq
        slave_nodes = np.concatenate([eq_nodes, self.slave_nodes[idx]]).astype(np.int64)
        master_nodes = np.vstack([eq_w[1], self.master_nodes[m_nodes]]).astype(np.int64)
        master_w = np.vstack([eq_w[0], m_w])
        dirs = np.vstack([eq_dirs, normal])
        m = len(dirs)
        rows = Rows(m, {})
        sf, sq, ssel = body_rows(
            bodies[self.slave], states[self.slave], slave_nodes[:, None], np.ones((m, 1)), dirs
        )
        mf, mq, msel = body_rows(
            bodies[self.master], states[self.master], master_nodes, master_w, dirs
        )
        rows.blocks[self.slave] = (sf, sq)
        rows.blocks[self.master] = (-mf, -mq)
        if ssel is not None:
            rows.nodal[self.slave] = ssel
        if msel is not None:
            rows.nodal[self.master] = -msel
        lower_n = self._lower(gaps, u_n, h)  # bonded contact: a law for it (velocity)
        keys = eq_keys + list(
            zip([self.name] * len(idx), self.slave_nodes[idx].tolist(), self._facet[idx].tolist())
        )
        weight = np.ones(m)
        # bond rows x, y, z: their compressive part is the component along the normal
        weight[: len(eq_keys)] = [self._bond_normal[k[2]][k[3]] for k in eq_keys]
        return ContactRows(
            rows, np.concatenate([eq_lower, lower_n]), keys, gaps, len(eq_keys), weight
        )

    def _bond_rows(self, h: float):
        """Three equality rows per bonded pair (seed eq. 7): x_S - x_C -> 0, at the node
        positions of the last kinematics update; a drift err is pushed back by beta err over
        the coming step h."""
        s_nodes, w_rows, n_rows, dirs, lower, keys = [], [], [], [], [], []
        index = {int(n): i for i, n in enumerate(self.slave_nodes)}
        for s, (nodes, w) in self._bonds.items():
            err = self._s.x[index[s]] - w @ self._m.x[self._mlocal[nodes]]
            for d, e in enumerate(np.eye(3)):
                s_nodes.append(s)
                w_rows.append(w)
                n_rows.append(nodes)
                dirs.append(e)
                lower.append(-self.beta * err[d] / h)
                keys.append((self.name, "bond", s, d))
        return (
            np.array(s_nodes),
            (np.array(w_rows), np.array(n_rows)),
            np.array(dirs),
            np.array(lower),
            keys,
        )

    def after_step(self, crows: ContactRows, impulses: np.ndarray, h: float) -> None:
        """Position law: pairs that carried an impulse keep this step's geometry, the others
        go back to the projection (module doc). Bonded contact: lock pairs that carried a
        compressive impulse; release a bond whose normal impulse component turned tensile."""
        if self._holds:
            self._hold_closed(impulses)
        if self.kind is not ContactKind.BONDED:
            return
        last, n_eq = self._last
        proj = (
            None if last is None else _Active(last[0], self.master_nodes[last[1]], last[2], last[3])
        )
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
        if proj is not None:
            lam_n = impulses[n_eq:]
            for j in np.nonzero(lam_n > 0.0)[0]:
                s = int(self.slave_nodes[proj.point[j]])
                self._bonds[s] = (proj.nodes[j].copy(), proj.weights[j].copy())
                self._bond_normal[s] = proj.normal[j].copy()
        self._bonded[:] = np.isin(self.slave_nodes, list(self._bonds))

    def _hold_closed(self, impulses: np.ndarray) -> None:
        """The pairs of the last candidate rows with a positive impulse are held on the
        geometry of those rows (the master frame A_m of the step's start turns the normal
        into body axes; a pair held before keeps its drift from the exact gap); every other
        pair is released."""
        before = self._held >= 0
        self._held[:] = -1
        if self._row_geometry is None:
            return
        idx, facets, w, normal, off, A_m = self._row_geometry
        on = np.flatnonzero(impulses[: len(idx)] > 0.0)
        i = idx[on]
        self._held[i] = facets[on]
        self._held_w[i] = w[on]
        self._held_n[i] = normal[on] @ A_m  # rows A_m^T n
        self._held_off[i] = off[on]
        self._held_d[i] = np.where(before[i], self._held_d[i], 0.0)


def tangent_basis(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two orthonormal tangents (m, 3) each of the unit normals (m, 3): t1 along the
    projection of the global axis least aligned with n, t2 = n x t1."""
    axis = np.eye(3)[np.argmin(np.abs(normal), axis=1)]
    t1 = axis - np.einsum("ij,ij->i", axis, normal)[:, None] * normal
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    return t1, np.cross(normal, t1)


def _failure(status: int, facet: int) -> str:
    """Message of a kernel failure status (contact.projection) on facet `facet`."""
    if status == DEGENERATE_QUAD:
        return f"quad facet {facet} degenerate (zero area at the centre) when deformed"
    if status == DEGENERATE_TRI:
        return f"triangle facet {facet} has zero area in the deformed state"
    return f"facet {facet} is degenerate at the contact point (tangents parallel)"
