"""Contact geometry: closest-point projection onto master facets and the broad phase.

Every test states the exact answer and its tolerance.
"""

from __future__ import annotations

import time
import warnings

import numpy as np
import pytest

from flexmvm.contact.geometry import (
    BroadPhase,
    MasterSurface,
    closest_facets,
    project_points,
)
from flexmvm.errors import InputError, SolverError
from flexmvm.mesh.mesh import FacetSet


def plate(n: int = 4, size: float = 1.0) -> tuple[np.ndarray, MasterSurface]:
    """n x n quads on [0, size]^2 in z = 0, counter-clockwise seen from +z (normal +z)."""
    g = np.linspace(0.0, size, n + 1)
    X, Y = np.meshgrid(g, g, indexing="xy")
    nodes = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    k = lambda i, j: j * (n + 1) + i
    quads = [
        [k(i, j), k(i + 1, j), k(i + 1, j + 1), k(i, j + 1)] for j in range(n) for i in range(n)
    ]
    return nodes, MasterSurface.from_facet_set(FacetSet(quads=quads))


def cylinder(n_theta: int = 16, n_z: int = 4, radius: float = 1.0, length: float = 1.0):
    """Side quads of a cylinder about z: facet (i, j) spans theta_i..theta_{i+1}, z_j..z_{j+1};
    node order (theta, z) increasing gives e_theta x e_z = e_r, outward."""
    th = 2 * np.pi * np.arange(n_theta) / n_theta
    z = np.linspace(0.0, length, n_z + 1)
    T, Z = np.meshgrid(th, z, indexing="xy")
    nodes = np.column_stack([radius * np.cos(T.ravel()), radius * np.sin(T.ravel()), Z.ravel()])
    k = lambda i, j: j * n_theta + i % n_theta
    quads = [
        [k(i, j), k(i + 1, j), k(i + 1, j + 1), k(i, j + 1)]
        for j in range(n_z)
        for i in range(n_theta)
    ]
    return nodes, MasterSurface(quads=np.array(quads), tris=np.zeros((0, 3))), th


def all_pairs(n_points: int, n_facets: int) -> tuple[np.ndarray, np.ndarray]:
    p, f = np.meshgrid(np.arange(n_points), np.arange(n_facets), indexing="ij")
    return p.ravel(), f.ravel()


def test_flat_plate_gap_weights_and_coordinates():
    """Plate z = 0, normal +z: the point (x, y, h) projects to (x, y, 0) with gap = h (1e-12),
    in facet (floor(4x), floor(4y)), weights summing to 1 and reproducing (x, y, 0)."""
    nodes, surf = plate()
    rng = np.random.default_rng(1)
    xy = rng.uniform(0.01, 0.99, size=(50, 2))
    h = rng.uniform(-0.2, 0.3, size=50)
    xs = np.column_stack([xy, h])
    c = closest_facets(project_points(xs, nodes, surf, all_pairs(50, surf.n_facets)))
    assert np.array_equal(c.point, np.arange(50))
    assert c.inside.all()
    np.testing.assert_allclose(c.gap, h, atol=1e-12, rtol=0)
    np.testing.assert_allclose(c.normal, np.tile([0.0, 0.0, 1.0], (50, 1)), atol=1e-15)
    np.testing.assert_allclose(c.weights.sum(1), 1.0, atol=1e-14)
    x_c = np.einsum("ma,mai->mi", c.weights, nodes[c.nodes])
    np.testing.assert_allclose(x_c, np.column_stack([xy, np.zeros(50)]), atol=1e-14)
    assert np.abs(c.xi).max() <= 1.0
    cell = np.floor(4 * xy).astype(int)
    assert np.array_equal(c.facet, cell[:, 1] * 4 + cell[:, 0])
    np.testing.assert_allclose(c.xi, 8 * xy - 2 * cell - 1, atol=1e-13)
    assert np.all(c.gap[h < 0] < 0)


def test_point_on_edge_and_vertex_gives_one_inside_entry():
    """(0.5, 0.3, 0.1) lies over the edge x = 0.5 of two facets, (0.5, 0.5, -0.05) over a vertex
    of four: each gets exactly one entry, inside, gap 0.1 and -0.05 (1e-14)."""
    nodes, surf = plate()
    xs = np.array([[0.5, 0.3, 0.1], [0.5, 0.5, -0.05]])
    proj = project_points(xs, nodes, surf, all_pairs(2, surf.n_facets))
    assert proj.inside[proj.point == 0].sum() == 2
    assert proj.inside[proj.point == 1].sum() == 4
    c = closest_facets(proj)
    assert len(c) == 2 and c.inside.all()
    np.testing.assert_allclose(c.gap, [0.1, -0.05], atol=1e-14)


def _bilinear(P, e, h):
    S = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
    N = 0.25 * (1 + np.multiply.outer(e, S[:, 0])) * (1 + np.multiply.outer(h, S[:, 1]))
    return N @ P


WARPED = np.array([[0.0, 0.0, 0.0], [1.0, 0.1, 0.35], [1.2, 1.0, -0.15], [-0.1, 0.9, 0.45]])


@pytest.mark.parametrize(
    "xs", [[0.4, 0.6, 0.5], [0.7, 0.2, -0.4], [0.55, 0.45, 0.02], [0.6, 0.5, 0.7]]
)
def test_warped_quad_tangency_and_brute_force(xs):
    """Non-planar quad: (x_S - x) . dx/dxi_i = 0 to 1e-10 relative, and (xi, eta) and the
    distance agree with the minimum over a 2001 x 2001 grid (grid step 1e-3: xi to 2e-3,
    distance from above by at most 1e-6)."""
    xs = np.array([xs])
    surf = MasterSurface(quads=[[0, 1, 2, 3]], tris=np.zeros((0, 3)))
    p = project_points(xs, WARPED, surf, (np.array([0]), np.array([0])))
    e, h = p.xi[0]
    x_c = _bilinear(WARPED, np.array(e), np.array(h))
    # the bilinear map is linear in each coordinate: exact tangents from the edge midlines
    t1 = (
        _bilinear(WARPED, np.array(1.0), np.array(h))
        - _bilinear(WARPED, np.array(-1.0), np.array(h))
    ) / 2
    t2 = (
        _bilinear(WARPED, np.array(e), np.array(1.0))
        - _bilinear(WARPED, np.array(e), np.array(-1.0))
    ) / 2
    r = xs[0] - x_c
    for t in (t1, t2):
        assert abs(r @ t) <= 1e-10 * np.linalg.norm(r) * np.linalg.norm(t)
    np.testing.assert_allclose(np.einsum("a,ai->i", p.weights[0], WARPED), x_c, atol=1e-14)
    assert p.inside[0]
    assert abs(abs(p.gap[0]) - np.linalg.norm(r)) <= 1e-12
    g = np.linspace(-1, 1, 2001)
    E, H = np.meshgrid(g, g, indexing="ij")
    dist = np.linalg.norm(_bilinear(WARPED, E, H) - xs[0], axis=-1)
    k = np.unravel_index(np.argmin(dist), dist.shape)
    assert abs(g[k[0]] - e) <= 2e-3 and abs(g[k[1]] - h) <= 2e-3
    assert 0.0 <= dist[k] - np.linalg.norm(r) <= 1e-6
    n_ref = np.cross(t1, t2) / np.linalg.norm(np.cross(t1, t2))
    np.testing.assert_allclose(p.normal[0], n_ref, atol=1e-14)


@pytest.mark.parametrize("xs", [[1.9, 0.4, 0.3], [0.6, 0.5, 1.2]])
def test_quad_outside_distance_is_clamped_brute_force(xs):
    """Beyond the warped quad's edge, and far above it where Newton's interior stationary
    point (xi ~ (-0.29, 0.31), distance 1.038) is farther than the edge eta = -1 (1.019):
    inside=False and `distance` equals the minimum over a 2001 x 2001 grid of the facet
    (from below by at most 1e-6)."""
    xs = np.array([xs])
    surf = MasterSurface(quads=[[0, 1, 2, 3]], tris=np.zeros((0, 3)))
    p = project_points(xs, WARPED, surf, (np.array([0]), np.array([0])))
    assert not p.inside[0]
    g = np.linspace(-1, 1, 2001)
    E, H = np.meshgrid(g, g, indexing="ij")
    d_min = np.linalg.norm(_bilinear(WARPED, E, H) - xs[0], axis=-1).min()
    assert 0.0 <= d_min - p.distance[0] <= 1e-6


def test_far_point_over_folding_quad_extension_stays_finite():
    """Trapezoid (-1,-1), (1,-1), (0.5,1), (-0.5,1) in z = 0: its bilinear extension folds at
    eta = 3 (t_xi = 0). The point (0, 8, 0.1) projects outside, with finite xi, gap and weights,
    at distance sqrt(7^2 + 0.1^2) from the top edge (1e-13), without a warning."""
    P = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.5, 1.0, 0.0], [-0.5, 1.0, 0.0]])
    surf = MasterSurface(quads=[[0, 1, 2, 3]], tris=np.zeros((0, 3)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p = project_points(np.array([[0.0, 8.0, 0.1]]), P, surf, (np.array([0]), np.array([0])))
    assert not p.inside[0]
    assert np.all(np.isfinite(p.xi)) and np.isfinite(p.gap[0]) and np.all(np.isfinite(p.weights))
    assert abs(p.distance[0] - np.hypot(7.0, 0.1)) <= 1e-13


def test_triangle_barycentric_projection_exact():
    """x_S = x0 + a e1 + b e2 + g n projects to area coordinates (a, b) with gap g (1e-13);
    weights (1-a-b, a, b, 0), the fourth node id repeating the third."""
    P = np.array([[0.2, -0.1, 0.3], [1.4, 0.2, 0.1], [0.5, 1.1, 0.8]])
    n = np.cross(P[1] - P[0], P[2] - P[0])
    n /= np.linalg.norm(n)
    ab = np.array([[0.2, 0.3], [0.6, 0.1], [0.0, 0.0], [0.5, 0.5], [0.7, 0.6], [-0.2, 0.4]])
    g = np.array([0.1, -0.05, 0.0, 0.2, 0.03, -0.3])
    xs = P[0] + ab[:, :1] * (P[1] - P[0]) + ab[:, 1:] * (P[2] - P[0]) + g[:, None] * n
    surf = MasterSurface(quads=np.zeros((0, 4)), tris=[[0, 1, 2]])
    p = project_points(xs, P, surf, (np.arange(6), np.zeros(6, dtype=int)))
    np.testing.assert_allclose(p.xi, ab, atol=1e-13)
    np.testing.assert_allclose(p.gap, g, atol=1e-13)
    np.testing.assert_allclose(p.normal, np.tile(n, (6, 1)), atol=1e-14)
    w_ref = np.column_stack([1 - ab.sum(1), ab, np.zeros(6)])
    np.testing.assert_allclose(p.weights, w_ref, atol=1e-13)
    assert np.array_equal(p.nodes, np.tile([0, 1, 2, 2], (6, 1)))
    assert p.inside.tolist() == [True, True, True, True, False, False]
    np.testing.assert_allclose(p.distance[:4], np.abs(g[:4]), atol=1e-13)
    s = np.linspace(0, 1, 1001)
    A, B = np.meshgrid(s, s, indexing="ij")
    ok = A + B <= 1
    pts = P[0] + A[ok, None] * (P[1] - P[0]) + B[ok, None] * (P[2] - P[0])
    for i in (4, 5):
        d_min = np.linalg.norm(pts - xs[i], axis=1).min()
        assert 0.0 <= d_min - p.distance[i] <= 1e-5


def test_mixed_surface_facet_numbering():
    """Quads first, then tris: with one quad and one tri, a point over the tri gets facet 1."""
    nodes = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]], dtype=float)
    surf = MasterSurface(quads=[[0, 1, 2, 3]], tris=[[1, 4, 2]])
    assert np.array_equal(surf.nodes(), np.arange(5))
    xs = np.array([[1.3, 0.2, 0.4], [0.5, 0.5, -0.1]])
    c = closest_facets(project_points(xs, nodes, surf, all_pairs(2, 2)))
    assert c.facet.tolist() == [1, 0] and c.inside.all()
    np.testing.assert_allclose(c.gap, [0.4, -0.1], atol=1e-14)
    assert c.nodes[0].tolist() == [1, 4, 2, 2] and c.weights[0, 3] == 0.0


def test_cylinder_normals_point_away_from_axis():
    """On the flat facets of a 16-sided cylinder of radius 1 the normal is
    (cos theta_mid, sin theta_mid, 0) (1e-14), and gap = r cos(theta - theta_mid) - cos(pi/16)
    (1e-13) for a point at radius r in [0.9, 1.1] and angle theta within 0.7 of the half-angle
    pi/16 of a facet's mid-angle theta_mid."""
    nodes, surf, th = cylinder()
    rng = np.random.default_rng(2)
    theta = th[rng.integers(0, 16, 40)] + np.pi / 16 * (1 + rng.uniform(-0.7, 0.7, 40))
    r = rng.uniform(0.9, 1.1, 40)
    xs = np.column_stack([r * np.cos(theta), r * np.sin(theta), rng.uniform(0.05, 0.95, 40)])
    c = closest_facets(project_points(xs, nodes, surf, all_pairs(40, surf.n_facets)))
    assert c.inside.all()
    i = c.facet % 16
    mid = th[i] + np.pi / 16
    np.testing.assert_allclose(
        c.normal, np.column_stack([np.cos(mid), np.sin(mid), 0 * mid]), atol=1e-14
    )
    np.testing.assert_allclose(c.gap, r * np.cos(theta - mid) - np.cos(np.pi / 16), atol=1e-13)


@pytest.mark.parametrize("r", [0.98, 1.02])
def test_curved_mesh_edge_picks_the_neighbour(r):
    """Just past the edge theta_1 = pi/8 of facet 0 (by pi/64, at z = 0.1), the point is
    outside facet 0 and inside facet 1, which closest_facets must pick."""
    nodes, surf, th = cylinder()
    theta = th[1] + np.pi / 64
    xs = np.array([[r * np.cos(theta), r * np.sin(theta), 0.1]])
    p = project_points(xs, nodes, surf, (np.zeros(2, dtype=int), np.array([0, 1])))
    assert p.inside.tolist() == [False, True]
    c = closest_facets(p)
    assert c.facet.tolist() == [1] and c.inside.tolist() == [True]
    mid = th[1] + np.pi / 16
    assert abs(c.gap[0] - (r * np.cos(theta - mid) - np.cos(np.pi / 16))) <= 1e-13


def test_points_beyond_surface_boundary_are_outside():
    """Above the top rim z = 1 of the cylinder by 0.2, and beyond the plate's edge: inside=False,
    distance to the rim edge exact (1e-13)."""
    nodes, surf, _ = cylinder()
    xs = np.array([[1.0, 0.0, 1.2]])
    c = closest_facets(project_points(xs, nodes, surf, all_pairs(1, surf.n_facets)))
    assert c.inside.tolist() == [False]
    assert abs(c.distance[0] - 0.2) <= 1e-13
    pn, ps = plate()
    c = closest_facets(project_points(np.array([[1.3, 0.5, 0.4]]), pn, ps, all_pairs(1, 16)))
    assert c.inside.tolist() == [False] and abs(c.distance[0] - 0.5) <= 1e-13


def test_broad_phase_matches_brute_force():
    """Random points within 0.1 of a cylinder: the candidates are exactly the pairs with
    |p - c_f| <= 0.1 + R_f (brute force over all facets), they contain the true closest facet
    (smallest clamped distance over all facets). The node (1, 0, 0) on the bottom rim with
    radius 0.05 (reach 0.05 + R_f = 0.195) gets exactly its two bottom-row facets 0 and 23: the
    next centroids, up (0.229) or around (0.39), are beyond reach."""
    nodes, surf, _ = cylinder(n_theta=24, n_z=8)
    bp = BroadPhase(nodes, surf)
    rng = np.random.default_rng(3)
    m = 300
    theta, z = rng.uniform(0, 2 * np.pi, m), rng.uniform(-0.05, 1.05, m)
    r = 1 + rng.uniform(-0.09, 0.09, m)
    xs = np.column_stack([r * np.cos(theta), r * np.sin(theta), z])
    pt, fc = bp.query(xs, 0.1)
    corners = nodes[surf.connectivity]
    cen = corners.mean(axis=1)
    R = np.linalg.norm(corners - cen[:, None], axis=2).max(1)
    dc = np.linalg.norm(xs[:, None] - cen[None], axis=2)
    bi, bf = np.nonzero(dc <= 0.1 + R)
    assert np.array_equal(pt, bi) and np.array_equal(fc, bf)
    full = project_points(xs, nodes, surf, all_pairs(m, surf.n_facets))
    dist = full.distance.reshape(m, surf.n_facets)
    best = np.argmin(dist, axis=1)
    near = dist[np.arange(m), best] <= 0.1
    cand = set(zip(pt.tolist(), fc.tolist()))
    assert near.sum() > 250
    assert all((i, int(best[i])) in cand for i in np.flatnonzero(near))
    _, fc0 = bp.query(np.array([[1.0, 0.0, 0.0]]), 0.05)
    assert fc0.tolist() == [0, 23]
    # a point exactly at a centroid (distance 0, which a sparse matrix could drop) keeps its facet
    assert 5 in bp.query(bp.centroids[5:6], 0.0)[1].tolist()


def test_projection_speed_2000_pairs():
    """2000 (point, quad) pairs on a cylinder project in one vectorised call; the time is
    printed, and the result must equal the per-pair projections."""
    nodes, surf, _ = cylinder(n_theta=40, n_z=10)
    rng = np.random.default_rng(4)
    theta, z = rng.uniform(0, 2 * np.pi, 2000), rng.uniform(0, 1, 2000)
    xs = np.column_stack([1.01 * np.cos(theta), 1.01 * np.sin(theta), z])
    bp = BroadPhase(nodes, surf)
    pt, fc = bp.query(xs, 0.02)
    pt, fc = pt[:2000], fc[:2000]
    project_points(xs, nodes, surf, (pt, fc))
    t0 = time.perf_counter()
    p = project_points(xs, nodes, surf, (pt, fc))
    dt = time.perf_counter() - t0
    print(f"project_points: {len(pt)} pairs in {dt * 1e3:.2f} ms")
    for k in range(0, len(pt), 97):
        one = project_points(xs, nodes, surf, (pt[k : k + 1], fc[k : k + 1]))
        np.testing.assert_allclose(one.xi[0], p.xi[k], atol=1e-13)


def test_bad_input_and_degenerate_facet():
    """Wrong shapes and out-of-range indices raise InputError; a collapsed quad SolverError."""
    nodes, surf = plate()
    with pytest.raises(InputError):
        project_points(np.zeros((2, 2)), nodes, surf, (np.array([0]), np.array([0])))
    with pytest.raises(InputError):
        project_points(np.zeros((2, 3)), nodes, surf, (np.array([2]), np.array([0])))
    with pytest.raises(InputError):
        project_points(np.zeros((2, 3)), nodes, surf, (np.array([0]), np.array([16])))
    with pytest.raises(InputError):
        project_points(np.zeros((2, 3)), nodes[:5], surf, (np.array([0]), np.array([0])))
    with pytest.raises(InputError):
        BroadPhase(nodes, surf).query(np.zeros((1, 3)), -1.0)
    flat = nodes.copy()
    flat[:, 1] = 0.0
    with pytest.raises(SolverError):
        project_points(np.array([[0.1, 0.0, 0.1]]), flat, surf, (np.array([0]), np.array([0])))
    empty = project_points(np.zeros((1, 3)), nodes, surf, (np.zeros(0, int), np.zeros(0, int)))
    assert empty.nodes.shape == (0, 4) and len(closest_facets(empty)) == 0
