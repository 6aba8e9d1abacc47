"""Static 3D Hertz check: a rigid sphere pressed onto the flat end of an elastic rod.

Hertz (1882; Johnson, Contact Mechanics, 1985, eq. 4.22-4.23): a rigid sphere of radius R
pressed by d into an elastic half-space of E* = E / (1 - nu^2) carries

    F = 4/3 E* sqrt(R) d^(3/2),   contact radius a = sqrt(R d).

The body is the aluminium test rod of src/flexmvm/mesh/rod.py (radius b = 10 mm, 20 mm long,
flat end A, hex27), clamped on its end-B face. The static contact problem is solved with the
package's FE stiffness (fe.assembly, factored by fe.cholesky) and its LCP solver
(integrate.moreau_jean.lcp.solve_checked): with P selecting the axial DOFs of the end-A face nodes
near the axis and G = P K^-1 P^T (the face's axial compliance), the nodal contact forces lambda
solve

    G lambda + (r^2 / (2 R) - d) >= 0,  lambda >= 0,  complementary,

node-to-rigid-surface contact with Hertz's own linearisation (the paraboloid r^2 / (2 R) for
the sphere, axial displacements only, frictionless); F = sum lambda.

A finite body is not a half-space: its far field adds a displacement linear in F (the rod's
bar compliance L / (E A), the clamped face's restraint, the end's Saint-Venant zone), of the
order of F / (E b) = 1.4e-9 m/N x F here: d = d_H(F) + C F. C is the one unknown besides what
Hertz fixes; it is fitted by least squares with the Hertz coefficient held, and checked two
ways: it is of a finite body's order (|C| < 1 / (E b)), and it moves with the rod's length as
the bar compliance does (measured: C = -5.84e-10 m/N at L = 20 mm, +3.27e-10 at 40 mm, a
difference of 9.1e-10 against 20 mm / (E A) = 8.76e-10, with F / F_Hertz the same to 0.4 %).
F is then compared with Hertz at d - C F.

Tolerance 2 % where the contact radius spans at least two node spacings h of the face
(a / h >= 2): node-to-surface contact adds rings of nodes one at a time, so F(d) is a
staircase about Hertz's curve whose steps shrink with h / a. Measured on the refined mesh
(first element 0.15 mm, 4 core elements: h = 0.075 mm at the axis; the contact zone of the
validation's fine mesh, docs/validation.md) at a = 0.15-0.30 mm (a / h = 2-4, a / b <= 0.03,
13-57 nodes in contact): F / F_Hertz = 0.984-1.007 at L = 20 mm, 0.986-1.008 at 40 mm
(without C: 1.003-1.032 and 0.974-1.000); below a / h = 2 the staircase reaches +6 %. The
default rod mesh (h = 0.15 mm in a core of half-width 0.3 mm, beyond which the face's node
spacing is 0.33 mm) cannot hold a = 2 h inside its core: at a / h = 1.3-2 (9-13 nodes in
contact) it measured F / F_Hertz = 0.970-1.035 (C = -1.15e-9 m/N; without C 1.006-1.084), so
2 % needs the refined mesh and the default one is held to 5 %. About 25 s on one core.
"""

from __future__ import annotations

import numpy as np

from flexmvm.fe.assembly import assemble
from flexmvm.fe.solvers.cholesky import ldl_factor
from flexmvm.integrate.moreau_jean.lcp import solve_checked
from flexmvm.materials import ALUMINIUM
from flexmvm.mesh.rod import RodSpec, rod_mesh

SPHERE_R = 0.01  # m: the seed striker's cap radius
ROD_B = 0.01  # m: rod radius
ROD_L = 0.02  # m


def indentation_forces(spec: RodSpec, depths: np.ndarray, reach_m: float):
    """Total force F (k,) [N] and nodes in contact (k,) of the rigid sphere SPHERE_R pressed by
    each of depths (k,) [m] into end A of the rod spec (aluminium, end-B face clamped); end-A
    face nodes within reach_m of the axis are the candidates."""
    mesh = rod_mesh(spec).mesh
    K = assemble(mesh, ALUMINIUM).K
    n = len(mesh.nodes)
    clamped = np.zeros(3 * n, dtype=bool)
    for k in mesh.node_sets["end_b"]:
        clamped[3 * k : 3 * k + 3] = True
    free = np.flatnonzero(~clamped)
    solve = ldl_factor(K[free][:, free])
    face = mesh.node_sets["end_a"]
    r = np.hypot(mesh.nodes[face, 1], mesh.nodes[face, 2])
    near = r < reach_m
    rows = np.searchsorted(free, 3 * face[near])  # axial DOF of each candidate
    P = np.zeros((len(free), len(rows)))
    P[rows, np.arange(len(rows))] = 1.0
    G = solve(P)[rows]
    G = 0.5 * (G + G.T)
    gap0 = r[near] ** 2 / (2.0 * SPHERE_R)
    forces, active = [], []
    for d in depths:
        lam, _ = solve_checked(G, gap0 - d, 0, where=f" (static Hertz, d = {d:.3e} m)")
        if lam[-1] > 0.0 or np.any(lam[r[near] > 0.9 * reach_m] > 0.0):
            raise AssertionError(f"contact reached the candidates' edge at d = {d:.3e} m")
        forces.append(lam.sum())
        active.append(int(np.count_nonzero(lam > 0.0)))
    return np.array(forces), np.array(active)


def hertz_ratio(depths: np.ndarray, forces: np.ndarray) -> tuple[np.ndarray, float]:
    """F / F_Hertz(d - C F) per load and the fitted linear compliance C [m/N] (module doc)."""
    e_star = ALUMINIUM.E / (1.0 - ALUMINIUM.nu**2)
    k = 4.0 / 3.0 * e_star * np.sqrt(SPHERE_R)
    c = float(np.sum((depths - (forces / k) ** (2.0 / 3.0)) * forces) / np.sum(forces**2))
    return forces / (k * (depths - c * forces) ** 1.5), c


REFINED = {"core_elements": 4, "first_element_m": 0.15e-3}


def _check(spec: RodSpec, h_node: float, a_min: float, tol: float) -> float:
    """Six loads with a = a_min .. 0.3 mm (the refined core's half-width): F / F_Hertz within
    tol, C of a finite body's order, the nodes in contact growing with a; returns C."""
    radii = np.geomspace(a_min * h_node, 0.3e-3, 6)
    depths = radii**2 / SPHERE_R
    forces, active = indentation_forces(spec, depths, reach_m=0.6e-3)
    ratio, c = hertz_ratio(depths, forces)
    assert np.all(np.abs(ratio - 1.0) < tol), (ratio, c)
    assert abs(c) < 1.0 / (ALUMINIUM.E * ROD_B), c
    assert np.all(np.diff(active) >= 0) and active[-1] > active[0], active
    return c


def test_sphere_on_refined_rod_end_follows_hertz():
    """Refined mesh, a / h = 2-4: within 2 % of Hertz at L = 20 and 40 mm, and the fitted
    linear compliance C differs between the two by the bar compliance of the added 20 mm,
    20 mm / (E A), within 10 % (measured 4 %: the rest of C, the ends' share, is the same for
    both lengths to that accuracy)."""
    c20 = _check(RodSpec(radius_m=ROD_B, length_m=ROD_L, **REFINED), 0.075e-3, 2.0, 0.02)
    c40 = _check(RodSpec(radius_m=ROD_B, length_m=2 * ROD_L, **REFINED), 0.075e-3, 2.0, 0.02)
    bar = ROD_L / (ALUMINIUM.E * np.pi * ROD_B**2)
    assert abs((c40 - c20) / bar - 1.0) < 0.10, (c20, c40, bar)


def test_sphere_on_default_rod_end_follows_hertz_to_5_percent():
    """The default rod mesh, a / h = 1.3-2 (the module doc: 2 % is out of its reach)."""
    _check(RodSpec(radius_m=ROD_B, length_m=ROD_L), 0.15e-3, 1.3, 0.05)
