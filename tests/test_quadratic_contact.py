"""A tetra10 block's contact surface takes its load through every face node: a static Hertz
check (the evidence for mesh/subfacets.py).

A rigid sphere (R = 10 mm) is pressed by d into the top face of an aluminium block 60 x 60 x
30 mm (scenarios/meshes/block_60x60x30.msh, mesh/parts.hertz_block_part: tetra10, 0.3 mm
elements within 1 mm of the contact point, growing to 8 mm: 3,916 nodes), its bottom face
clamped. The candidate contact nodes are the nodes of the
facet set ``top`` within 0.6 mm of the axis; with P selecting their vertical DOFs and
G = P K^-1 P^T, the nodal forces solve the LCP

    G lambda + (g0 - d) >= 0,  lambda >= 0,  complementary,

g0 = R - sqrt(R^2 - r^2) the sphere's height above a node at radius r (frictionless,
vertical displacements, as tests/test_hertz_static.py). Hertz (Johnson 1985, eq. 4.22-4.23):
F = 4/3 E* sqrt(R) d^(3/2), E* = E / (1 - nu^2).

Measured at d = 8, 12, 15.5 um (Hertz contact radius a = 0.28-0.39 mm, the last the peak of
the sphere_block impact; a / h = 1.9-2.6 with h = 0.15 mm the face's node spacing):
- every face node (the facet set read_mesh gives now): F / F_Hertz = 1.033-1.039;
- the corner nodes only (the facet set before, the 6-node faces' corners): 0.65-0.72.
tet4 at the same node spacing (0.15 mm elements) measured 1.10 (stiff constant-strain cells).
The tolerance, F / F_Hertz in [0.99, 1.06]: the block is clamped 30 mm below the contact,
stiffer than a half-space by ~F / (pi E* 30 mm) in d, +0.5 % on F; node-to-surface contact
adds rings of nodes one at a time (a staircase about Hertz's curve, tests/test_hertz_static.py:
up to +6 % for a / h < 2); below 0.99 would be a soft face, which is what corners alone give.
About 5 s (one sparse factorization of 11,748 DOF, 57 solves, the imports).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flexmvm.fe.assembly import assemble
from flexmvm.fe.solvers.cholesky import ldl_factor
from flexmvm.integrate.moreau_jean.lcp import solve_checked
from flexmvm.materials import ALUMINIUM
from flexmvm.mesh import read_mesh

BLOCK = Path(__file__).resolve().parents[1] / "scenarios" / "meshes" / "block_60x60x30.msh"

R = 0.01  # sphere radius [m]
DEPTHS = np.array([8.0, 12.0, 15.5]) * 1e-6  # indentation [m]
REACH = 0.6e-3  # candidate nodes within this radius [m]


@pytest.fixture(scope="module")
def indentation():
    """F(d) [N] with every face node of ``top`` as candidate, and with its corner nodes only."""
    mesh = read_mesh(BLOCK)
    K = assemble(mesh, ALUMINIUM).K
    clamped = np.zeros(mesh.n_dof, dtype=bool)
    for k in mesh.node_set("bottom"):
        clamped[3 * k : 3 * k + 3] = True
    free = np.flatnonzero(~clamped)
    solve = ldl_factor(K[free][:, free])
    x = mesh.nodes
    top = mesh.facet_set("top").nodes
    top = top[np.hypot(x[top, 0], x[top, 1]) < REACH]
    corners = np.intersect1d(top, np.unique(mesh.cells[0].connectivity[:, :4]))
    out = {}
    for name, nodes in (("all", top), ("corners", corners)):
        rows = np.searchsorted(free, 3 * nodes + 2)
        P = np.zeros((len(free), len(rows)))
        P[rows, np.arange(len(rows))] = 1.0
        G = solve(P)[rows]
        G = 0.5 * (G + G.T)
        r = np.hypot(x[nodes, 0], x[nodes, 1])
        g0 = R - np.sqrt(R**2 - r**2)
        forces = []
        for d in DEPTHS:
            lam, _ = solve_checked(G, g0 - d, 0, where=f" (static Hertz, d = {d:.2e} m)")
            assert not np.any(lam[r > 0.9 * REACH] > 0.0)  # the contact stays inside
            forces.append(lam.sum())
        out[name] = np.array(forces)
    return out


def _hertz(d: np.ndarray) -> np.ndarray:
    e_star = ALUMINIUM.E / (1.0 - ALUMINIUM.nu**2)
    return 4.0 / 3.0 * e_star * np.sqrt(R) * d**1.5


def test_tet10_face_with_midside_nodes_follows_hertz(indentation):
    ratio = indentation["all"] / _hertz(DEPTHS)
    assert np.all((ratio > 0.99) & (ratio < 1.06)), ratio


def test_tet10_corners_alone_are_soft(indentation):
    """What the facet sets gave before the split: 28-35 % below Hertz (bound: 20 %)."""
    ratio = indentation["corners"] / _hertz(DEPTHS)
    assert np.all(ratio < 0.80), ratio
