"""A facet body whose nodes have all moved far (a bar bent 6 mm under a cam: its contact strip
moves ~6 mm, its facets apart by ~0.2 mm) is searched as moved by the centre d0 of its node
displacements with at most |u - d0| more (contact.nodes.ContactNodes.displacement_offset).

Geometry of tests/test_penetration.py: a master face of 0.5-spaced quads at z = 0 (normal -z;
node (0.5, 0.5) dips by D) and a slave face of unit quads at z = 0 below it (normal +z), here
with every master node given the same elastic displacement U up (a full-FE-like basis: psi
the identity on the nodal DOFs). Gaps and depths compared to 1e-12 m (flat facets, projections
exact to the Newton tolerance, 1e-12 of unit facets)."""

from __future__ import annotations

import types

import numpy as np
import scipy.sparse as sp
from test_penetration import D, _bodies

from flexmvm.bodies.body import FlexibleBody
from flexmvm.contact.pairs import PointToSurfaceContact

U = 1.0  # every master node's displacement up [m]: 20 search radii


def _displaced_master(two_way: bool):
    (top, bottom), master, slave = _bodies()
    n = len(top.X)
    psi = sp.identity(3 * n, format="csr")
    top = FlexibleBody("top", top.X, psi, types.SimpleNamespace(nq=3 * n), None)
    prov = PointToSurfaceContact(
        [top, bottom],
        1,
        slave.nodes(),
        0,
        master,
        search_radius_m=0.05,
        slave_surface=slave if two_way else None,
    )
    q = np.zeros(3 * n)
    q[2::3] = U
    st = lambda q: types.SimpleNamespace(r=np.zeros(3), A=np.eye(3), q=q, v=np.zeros(6 + q.size))
    return [top, bottom], prov, [st(q), st(np.zeros(0))]


def test_the_constraint_pass_finds_a_master_moved_beyond_its_search_radius():
    """The slave face lifted to 0.02 m under the displaced master face: every slave node (all
    within the master's extent) has a closest facet, the smallest gap 0.02 m. Before,
    the candidates were sought about the master's undeformed facets, U = 20 search radii
    away: no pair."""
    bodies, prov, states = _displaced_master(two_way=False)
    states[1].r = np.array([0.0, 0.0, U - 0.02])
    assert abs(prov.min_gap_ahead(bodies, states, 1e-3) - 0.02) < 1e-12  # inf before
    assert (prov._facet >= 0).sum() == 9  # the 3 x 3 slave nodes, all under the master face


def test_the_measure_reads_the_same_depths_when_both_faces_moved_together():
    """Slave face moved up by U as well: the dipping master node is D inside it, as in the
    undisplaced case of tests/test_penetration.py, and the slave nodes are in no facet."""
    bodies, prov, states = _displaced_master(two_way=True)
    states[1].r = np.array([0.0, 0.0, U])
    fwd, rev = prov.penetration(bodies, states)
    assert fwd.depth_m == 0.0
    assert abs(rev.depth_m - D) < 1e-12 and rev.node == 6
