"""Penetration of one contact surface into the other, measured on the nodes of both surfaces.

The constraint pass (contact.pairs) sees slave nodes against master facets, for the pairs it
built rows for. The measure here looks both ways after every step: every slave node against
the master facets, and every master surface node against the slave facets, with the compiled
closest-point search of the constraint pass (contact.search.penetration_scan:
cached candidate supersets, warm start from the last facet, pruning).

Definition. A node penetrates the other surface by d = -g > 0 when its closest facet of that
surface (within reach) has a projection that is inside the facet, to the constraint pass's
tolerance on the local coordinates (1e-6), or outside it by a lateral offset of at most
EDGE_TOL times the facet's circumradius, and the signed normal gap g there is negative. A node
that projects outside every facet by more than that is beside the other surface, not in it:
the free parts of a surface far from the contact, whose extended facet planes would give
negative gaps, are not read as penetrations. Depths beyond the reach (the contact's search
radius plus the spread of the facet nodes' displacements about their common offset,
ContactNodes.displacement_offset, per step) are not seen; the start check (``deep=True``)
reaches over both surfaces' extent.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.contact.geometry import BroadPhase, MasterSurface
from flexmvm.contact.nodes import ContactNodes
from flexmvm.contact.search import penetration_scan
from flexmvm.contact.search_state import ProjectionMemo, SearchState, facet_surface

EDGE_TOL = 0.01  # lateral offset beyond a facet edge, per facet circumradius, still counted:
# covers the round-off and the differential Poisson expansion of two faces
# with a common edge (both ~1e-7 m on facets of ~1e-4 m and more)
RESOLUTION_M = 1e-12  # depths up to this read 0 and are not sought: the round-off of node
# positions of metre-scale bodies (1e-16 m to 1e-14 m); touching faces
# (gaps of round-off size) then cost one projection per node


@dataclass(frozen=True)
class Penetration:
    """The deepest penetration of a node of body `body` (mesh node id `node`) into the surface
    of body `against` (its facet `facet`), depth_m [m]; depth 0 and node -1 when none."""

    depth_m: float
    body: int
    node: int
    against: int
    facet: int = -1


class _Direction:
    """Nodes `rows` (indices into node_set.nodes) of body `body` against the facets `surface` of
    body `against`, whose nodes are facet_set.nodes."""

    def __init__(
        self,
        bodies,
        body,
        node_set: ContactNodes,
        rows,
        against,
        facet_set: ContactNodes,
        surface: MasterSurface,
        search_radius: float,
        memo: ProjectionMemo | None = None,
    ):
        self.body, self.against = body, against
        self.node_set, self.facet_set = node_set, facet_set
        self.rows = None if len(rows) == len(node_set.nodes) else np.asarray(rows, np.int64)
        self.node_ids = node_set.nodes if self.rows is None else node_set.nodes[self.rows]
        local = np.full(len(bodies[against].X), -1, dtype=np.int64)
        local[facet_set.nodes] = np.arange(len(facet_set.nodes))
        conn = local[surface.connectivity]
        if conn.min() < 0:
            raise ValueError("facet nodes missing from the facet node set")
        self.surface = facet_surface(
            bodies[against].X, surface, conn, BroadPhase(bodies[against].X, surface), search_radius
        )
        Xs = bodies[against].X[surface.nodes()]
        Xn = bodies[body].X[self.node_ids]
        self.extent = float(np.linalg.norm(np.ptp(Xs, axis=0)) + np.linalg.norm(np.ptp(Xn, axis=0)))
        self.search_radius = search_radius
        self.search = SearchState.empty(len(self.node_ids), surface.n_facets)
        # projections kept at the current positions: the constraint pass's memo when it serves
        # this scan (all nodes of its node set against its facets: the next step's search
        # reads what this measure projected), else none (keeping costs more than the few
        # projections a measure repeats itself)
        if (
            memo is None
            or self.rows is not None
            or not memo.serves(node_set, facet_set, self.surface.conn, self.surface.params)
        ):
            memo = ProjectionMemo(node_set, facet_set, self.surface.conn, self.surface.params, k=0)
        self.memo = memo

    def measure(self, states, deep: bool, floor: float) -> tuple[int, int, Penetration]:
        x = self.node_set.x if self.rows is None else self.node_set.x[self.rows]
        st = states[self.against]
        # the facets searched as moved by d0 with at most u_rel more (displacement_offset):
        # the nodes' positions taken in the facet body's frame shifted by d0
        d0, u_rel = self.facet_set.displacement_offset()
        if deep:  # the start check: reach over both surfaces, a throwaway search state
            reach = self.search_radius + u_rel + self.extent
            search = SearchState.empty(len(x), len(self.surface.geo))
        else:
            reach, search = self.search_radius + u_rel, self.search
        status, bad, depth, i, g = penetration_scan(
            x,
            self.facet_set.x,
            st.r + st.A @ d0,
            st.A,
            reach,
            u_rel,
            self.surface,
            search,
            self.memo.arrays,
            EDGE_TOL,
            floor,
        )
        node = int(self.node_ids[i]) if i >= 0 else -1
        return status, bad, Penetration(float(depth), self.body, node, self.against, int(g))


class SurfaceMeasure:
    """Both directions of a contact between body `slave` (nodes slave_nodes, facets
    slave_surface, optional) and body `master` (facets master_surface): slave nodes against
    the master facets, and, when slave_surface is given, the master surface nodes against the
    slave facets. Positions come from ContactNodes of those node sets: `shared` (the
    constraint pass's, slave and master) where they hold the same nodes in the same order, so
    that the end-of-step measure and the next step's search (the same state) update them once
    (ContactNodes.update keeps them at an unchanged state); own ones otherwise."""

    def __init__(
        self,
        bodies,
        slave: int,
        slave_nodes,
        slave_surface: MasterSurface | None,
        master: int,
        master_surface: MasterSurface,
        search_radius: float,
        shared: tuple[ContactNodes, ContactNodes, ProjectionMemo] | None = None,
    ):
        s_ids = np.asarray(slave_nodes, dtype=np.int64)
        if slave_surface is not None:
            s_ids = np.union1d(s_ids, slave_surface.nodes())
        self.slave, self.master = slave, master
        sh_s, sh_m, memo = (None, None, None) if shared is None else shared
        self._s = _same_set(sh_s, s_ids) or ContactNodes(bodies[slave], s_ids)
        self._m = _same_set(sh_m, master_surface.nodes()) or ContactNodes(
            bodies[master], master_surface.nodes()
        )
        rows = np.searchsorted(s_ids, np.unique(np.asarray(slave_nodes, dtype=np.int64)))
        self.directions = [
            _Direction(
                bodies, slave, self._s, rows, master, self._m, master_surface, search_radius, memo
            )
        ]
        if slave_surface is not None:
            self.directions.append(
                _Direction(
                    bodies,
                    master,
                    self._m,
                    np.arange(len(self._m.nodes)),
                    slave,
                    self._s,
                    slave_surface,
                    search_radius,
                )
            )

    def rebind(self, index: int, body) -> None:
        """Body ``index``'s basis changed: its nodes' psi rows gathered again (a ContactNodes
        shared with the pair is gathered twice, to the same rows)."""
        for nodes, which in ((self._s, self.slave), (self._m, self.master)):
            if which == index:
                nodes.rebind(body)

    def measure(
        self, states, deep: bool = False, floors=None
    ) -> list[tuple[int, int, Penetration]]:
        """(status, failing facet, Penetration) per direction at the given states. floors
        (per direction, [m]; default 0): only depths above are sought, a shallower one reads 0
        (penetration_scan): the caller passes the deepest it has seen so far. Depths
        up to RESOLUTION_M always read 0."""
        self._s.update(states[self.slave])
        self._m.update(states[self.master])
        floors = [0.0] * len(self.directions) if floors is None else floors
        return [
            d.measure(states, deep, max(float(f), RESOLUTION_M))
            for d, f in zip(self.directions, floors)
        ]


def _same_set(nodes: ContactNodes | None, ids: np.ndarray) -> ContactNodes | None:
    """nodes when it holds exactly the node ids `ids` in that order, else None."""
    if nodes is not None and np.array_equal(nodes.nodes, np.asarray(ids, dtype=np.int64)):
        return nodes
    return None
