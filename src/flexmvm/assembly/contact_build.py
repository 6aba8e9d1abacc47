"""A scenario contact (``[[contacts]]``) as its contact provider (contact/pairs.py
PointToSurfaceContact), and a probe (``[[probes]]``) as the node (or the tetrahedron's
nodes and weights) it reads."""

from __future__ import annotations

import numpy as np

from flexmvm.assembly.mesh_lookup import nearest_node
from flexmvm.contact.geometry import MasterSurface
from flexmvm.contact.pairs import PointToSurfaceContact
from flexmvm.errors import InputError, MeshError
from flexmvm.integrate.run_result import Probe
from flexmvm.mesh.point_location import tet_weights

DEFAULT_SEARCH_RADIUS_M = 2e-4  # broad-phase margin beyond the distance closed in one step


def contact_provider(c, k, bodies, infos, index, theta):
    """The contact provider of contacts[k]; theta: the scheme's theta of each step size
    (TimeGrid.theta_rule), which the position law's bound needs (the end gap is
    g + h (theta u_N+ + (1 - theta) u_N-))."""
    where = f"contacts[{k}]"
    s, m = index[c.slave_body], index[c.master_body]
    try:
        slave_facets = infos[s].mesh.facet_set(c.slave_surface)
        slave_nodes = slave_facets.nodes
        master = MasterSurface.from_facet_set(infos[m].mesh.facet_set(c.master_surface))
    except MeshError as exc:
        raise InputError(f"{where}: {exc}") from None
    radius = c.search_radius_m if c.search_radius_m is not None else DEFAULT_SEARCH_RADIUS_M
    return PointToSurfaceContact(
        bodies,
        s,
        slave_nodes,
        m,
        master,
        c.kind,
        radius,
        name=f"{c.slave}->{c.master}",
        slave_surface=MasterSurface.from_facet_set(slave_facets),
        friction_coefficient=c.friction_coefficient,
        law=c.law,
        theta=theta,
        **({} if c.penetration_recovery is None else {"beta": c.penetration_recovery}),
    )


def probe(p, where, infos, index) -> Probe:
    b = index[p.body]
    mesh = infos[b].mesh
    if p.node_set is not None:
        try:
            ids = mesh.node_set(p.node_set)
        except MeshError as exc:
            raise InputError(f"{where}.node_set: {exc}") from None
        return Probe(p.name, b, int(ids[0]), p.axis)
    tol = 0.05 * float(np.ptp(mesh.nodes, axis=0).min() or 1.0)
    d = np.linalg.norm(mesh.nodes - np.asarray(p.point_m, float), axis=1)
    if d.min() > tol:  # no node near: the point interpolated in the tet that holds it
        found = tet_weights(mesh, p.point_m)
        if found is not None:
            nodes, w = found
            near = int(nodes[np.argmax(w)])
            return Probe(p.name, b, near, p.axis, tuple(map(int, nodes)), tuple(map(float, w)))
    return Probe(p.name, b, nearest_node(mesh, p.point_m, f"{where}.point_m", tol), p.axis)
