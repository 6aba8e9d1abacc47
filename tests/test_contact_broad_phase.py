"""The search's pruning by the facets' slabs (contact.search._slab_bound): a lower bound of
a node's distance to a facet, so that the closest facet is the brute force's, with fewer
projections than the ball bound alone made (it left every facet within the node's gap)."""

from __future__ import annotations

import numpy as np

from flexmvm.contact.geometry import BroadPhase, MasterSurface
from flexmvm.contact.projection import REC_DIST, REC_GAP, REC_IN, REC_LEN, project_pair
from flexmvm.contact.search import scan_nodes
from flexmvm.contact.search_state import MemoArrays, SearchState, facet_surface

R_SPHERE = 10e-3  # sphere radius [m], as scenarios/sphere_block.toml's ball
H = 0.1e-3  # facet size [m], as its fine cap
REACH = 0.2e-3  # the scenario's search radius [m]


def _cap(n: int = 21, rng=None):
    """Nodes (n*n, 3) of a sphere cap about its pole (0, 0, -R), triangulated on an n x n
    grid of spacing H (outward normal -z), optionally jittered by 0.2 H in plane."""
    g = (np.arange(n) - (n - 1) / 2) * H
    x, y = (a.ravel() for a in np.meshgrid(g, g, indexing="ij"))
    if rng is not None:
        x, y = x + rng.uniform(-0.2, 0.2, x.size) * H, y + rng.uniform(-0.2, 0.2, y.size) * H
    X = np.column_stack([x, y, -np.sqrt(R_SPHERE**2 - x**2 - y**2)])
    tris = []
    for i in range(n - 1):
        for j in range(n - 1):
            a, b, c, d = i * n + j, (i + 1) * n + j, (i + 1) * n + j + 1, i * n + j + 1
            tris += [[a, d, b], [b, d, c]]  # right-handed about -z
    return X, MasterSurface(np.zeros((0, 4), dtype=np.int64), np.array(tris))


def _nodes(rng, m: int = 300):
    """m nodes below the cap's central part, at gaps 0 to REACH [m] along -z."""
    xy = rng.uniform(-0.6e-3, 0.6e-3, (m, 2))
    z = -np.sqrt(R_SPHERE**2 - (xy**2).sum(axis=1)) - rng.uniform(0.0, REACH, m)
    return np.column_stack([xy, z])


def _scan_args(X, surf, xs, state=None, keep=64):
    """The arguments of scan_nodes for xs against the cap (frame at rest), from the search
    state `state` (default: none searched yet), with a memo that keeps up to `keep`
    projections a node (64: it counts every projection of these scans)."""
    conn = np.asarray(surf.connectivity, dtype=np.int64)
    fs = facet_surface(X, surf, conn, BroadPhase(X, surf), REACH)
    n, nf = len(xs), surf.n_facets
    state = SearchState.empty(n, nf) if state is None else state
    memo = MemoArrays(
        np.zeros((n, keep), np.int64),
        np.zeros(n, np.int64),
        np.zeros((n, keep, REC_LEN)),
        np.full(2, -1, np.int64),
        np.ones(1, np.int64),
        np.ones(1, np.int64),
    )
    facet, out = np.full(n, -1, np.int64), np.zeros((n, 11))
    z3 = np.zeros(3)
    return (
        xs,
        np.zeros_like(xs),
        X,
        np.zeros_like(X),
        z3,
        np.eye(3),
        REACH,
        0.0,
        fs,
        state,
        memo,
        facet,
        out,
        np.inf,  # need: every node searched
        np.zeros(n, np.int64),
    )


def _scan(X, surf, xs, state=None):
    """scan_nodes of xs against the cap (_scan_args); returns (facet, out, projections
    made, the state)."""
    args = _scan_args(X, surf, xs, state)
    status, _, _ = scan_nodes(*args)
    assert status == 0
    memo = args[10]
    assert memo.count.max() < 64  # every projection counted
    return args[11], args[12], int(memo.count.sum()), args[9]


def _brute_force(X, surf, xs):
    """The closest facet of each node over every facet (closest_facets' order: the smaller
    score, |gap| inside, the clamped distance outside raised by its tie margin, then inside,
    then the lower index) and its record."""
    conn = surf.connectivity
    work = (np.empty((4, 3)), np.empty((2, 3)), np.empty(3))
    from flexmvm.contact.projection import projection_params

    params = projection_params()
    best = []
    for p in xs:
        keys = []
        for g in range(surf.n_facets):
            rec = np.empty(REC_LEN)
            assert project_pair(p, X[conn[g]], False, params, *work, rec) == 0
            inside = rec[REC_IN] == 1.0
            score = abs(rec[REC_GAP]) if inside else rec[REC_DIST] * (1 + 1e-9) + 1e-15
            keys.append((score, not inside, g, rec))
        best.append(min(keys, key=lambda k: k[:3]))
    return best


def test_scan_finds_the_brute_force_facet_with_fewer_projections():
    """Nodes below a sphere cap of 0.1 mm facets within a 0.2 mm reach (sphere_block's
    contact), searched a second time 1 um further (a run's next step: warm start from the
    facet found before): the scan's facet and gap are the brute force's (bit for bit: the
    same projection), and it projects at most 6 facets a node. Measured on these 300 nodes:
    13.1 a node with the ball bound alone, 4.2 with the slab bound: the limit sits between,
    with room for a different triangulation's neighbour count."""
    rng = np.random.default_rng(49)
    X, surf = _cap(rng=rng)
    xs = _nodes(rng)
    state = _scan(X, surf, xs)[3]
    xs = xs + np.array([0.3e-6, -0.2e-6, 1e-6])
    facet, out, n_proj, _ = _scan(X, surf, xs, state)
    for i, (_, _, g, rec) in enumerate(_brute_force(X, surf, xs)):
        assert facet[i] == g
        if rec[REC_IN] == 1.0:
            assert out[i, 9] == rec[REC_GAP]
    assert n_proj <= 6 * len(xs), n_proj / len(xs)


def test_slab_bound_never_exceeds_the_distance():
    """_slab_bound <= the distance of a point to a facet (triangles and warped quads, points
    near and far, above and beside): sampled densely, each facet's distance is at least the
    bound less the sampling's reach (the facet's points within 1/400 of its size)."""
    from flexmvm.contact.certificate import slab_bound as _slab_bound
    from flexmvm.contact.search_state import facet_planes

    rng = np.random.default_rng(7)
    s = np.linspace(0.0, 1.0, 401)
    u, v = (a.ravel() for a in np.meshgrid(s, s, indexing="ij"))
    for quad in (False, True):
        for _ in range(20):
            P = rng.normal(size=(4, 3)) * np.array([1.0, 1.0, 0.3])
            if quad:
                pts = np.outer((1 - u) * (1 - v), P[0]) + np.outer(u * (1 - v), P[1])
                pts += np.outer(u * v, P[2]) + np.outer((1 - u) * v, P[3])
                c = P.mean(axis=0)
            else:
                P[3] = P[2]
                keep = u + v <= 1.0
                pts = np.outer(1 - u[keep] - v[keep], P[0]) + np.outer(u[keep], P[1])
                pts += np.outer(v[keep], P[2])
                c = P[:3].mean(axis=0)
            geo = np.array([[*c, np.linalg.norm(P - c, axis=1).max()]])
            plane = facet_planes(P[None], 1 if quad else 0, geo[:, :3])
            size = np.ptp(P, axis=0).max()
            for p in c + rng.normal(size=(30, 3)) * rng.choice([0.3, 1.0, 3.0], (30, 1)):
                d = np.linalg.norm(pts - p, axis=1).min()
                bound = _slab_bound(p, geo, plane, 0)
                assert bound <= d + 2.0 * size / 400, (bound, d)
                assert bound >= np.linalg.norm(p - c) - geo[0, 3] - 1e-12


def test_nodes_outside_the_box_get_no_facet():
    """20,000 nodes 1 m from the cap: a scan tests each against the facets' box and goes on
    (the box test made before the per-node search: 0.42 us a node before, 0.01 us after,
    measured by benchmarks/bench_search.py, not asserted here: a test asserts no wall time).
    Every one is left without a facet and the scan reports no pair."""
    X, surf = _cap()
    xs = _nodes(np.random.default_rng(3), 20_000) + np.array([0.0, 0.0, -1.0])
    args = _scan_args(X, surf, xs, keep=1)
    status, _, n_pairs = scan_nodes(*args)
    assert status == 0 and n_pairs == 0
    assert (args[11] == -1).all()
