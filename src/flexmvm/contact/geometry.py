"""Contact geometry: master surface, broad phase, closest-point projection (seed eq. 7-8).

A slave point S of one body is paired with a facet of the master body's surface; the contact
point is the closest point of the facet, x_C = sum_P N^P(xi) x^P, with the facet's shape
functions N^P (bilinear for a quad, linear for a triangle). The normal gap is
g = n . (x_S - x_C) [m], negative when S penetrates the master body.

Facet numbering: quads first, then triangles (facet f >= n_quads is triangle f - n_quads).
Every facet is stored with four node ids; a triangle repeats its last node and gives that
fourth entry the weight 0, so the constraint rows have one shape for both kinds.

Quad local coordinates (xi, eta) in [-1, 1]^2 with nodes at (-1,-1), (1,-1), (1,1), (-1,1) in
the facet's node order; triangle local coordinates (xi, eta) are the area coordinates of nodes
1 and 2: x = (1 - xi - eta) x0 + xi x1 + eta x2.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from flexmvm.errors import InputError, SolverError
from flexmvm.mesh.mesh import FacetSet

#: closest_facets' tie margin of an outside projection's distance (relative, absolute [m]):
#: an inside projection wins a tie to round-off.
TIE_REL, TIE_ABS = 1e-9, 1e-15

NEWTON_MAX_ITER = 20  # quadratic convergence from the centre takes ~4; the rest fold outside
LINE_SEARCH_HALVINGS = 12
FAR_CHECK_ITER, FAR_XI = 4, 2.0  # after 4 iterations, |xi| > 2 is far outside the facet
NEWTON_TOL = 1e-12  # on the local coordinates, which are O(1): a relative tolerance
XI_BOUND = 4.0  # Newton iterates kept in [-4, 4]^2: far outside the facet, still finite
_QUAD_SIGNS = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])


@dataclass(frozen=True)
class MasterSurface:
    """Facets of the master body's contact surface, in that body's node numbering.

    quads (n_q, 4) and tris (n_t, 3) node ids, ordered so that the right-hand rule gives the
    outward normal. ``connectivity`` (n_q + n_t, 4) lists quads then triangles, a triangle
    with its last node repeated. Raises InputError on negative ids or an empty surface.
    """

    quads: np.ndarray
    tris: np.ndarray
    connectivity: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        quads = np.asarray(self.quads, dtype=np.int64).reshape(-1, 4)
        tris = np.asarray(self.tris, dtype=np.int64).reshape(-1, 3)
        if len(quads) + len(tris) == 0:
            raise InputError("master surface has no facets; expected at least one quad or tri")
        conn = np.concatenate([quads, np.concatenate([tris, tris[:, 2:]], axis=1)])
        if conn.min() < 0:
            raise InputError(f"master surface node ids must be >= 0, got {int(conn.min())}")
        object.__setattr__(self, "quads", quads)
        object.__setattr__(self, "tris", tris)
        object.__setattr__(self, "connectivity", conn)

    @classmethod
    def from_facet_set(cls, fs: FacetSet) -> MasterSurface:
        return cls(quads=fs.quads, tris=fs.tris)

    @property
    def n_quads(self) -> int:
        return len(self.quads)

    @property
    def n_facets(self) -> int:
        return len(self.connectivity)

    def nodes(self) -> np.ndarray:
        """Sorted unique master node ids of the surface."""
        return np.unique(self.connectivity)


def _as_points(x: np.ndarray, name: str) -> np.ndarray:
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 3:
        raise InputError(f"{name} must have shape (n, 3), got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise InputError(f"{name} contains NaN or infinite coordinates")
    return x


def _check_nodes_cover(x_nodes: np.ndarray, surface: MasterSurface, name: str) -> None:
    top = int(surface.connectivity.max())
    if top >= len(x_nodes):
        raise InputError(
            f"{name} has {len(x_nodes)} nodes, the master surface refers to node {top}"
        )


class BroadPhase:
    """Candidate (point, facet) pairs from a KD-tree over the master facet centroids.

    The tree is built once over the centroids of the facets in the master body's UNDEFORMED
    body-frame coordinates X_master (n_nodes, 3) [m], indexed by master node id. A facet is a
    candidate for a point p when |p - c_f| <= radius + R_f, with c_f the facet centroid and
    R_f its circumradius (largest centroid-to-node distance): every facet with a point within
    ``radius`` of p is then returned. Elastic deformation of the master body is not seen here;
    the caller adds its magnitude to ``radius``.
    """

    def __init__(self, X_master: np.ndarray, surface: MasterSurface) -> None:
        X = _as_points(X_master, "X_master")
        _check_nodes_cover(X, surface, "X_master")
        corners = X[surface.connectivity]  # (nf, 4, 3); a tri's 4th corner repeats its 3rd
        w = np.full((surface.n_facets, 4), 0.25)
        w[surface.n_quads :] = [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 0.0]
        self.surface = surface
        self.centroids = np.einsum("fa,fai->fi", w, corners)
        self.circumradius = np.linalg.norm(corners - self.centroids[:, None], axis=2).max(axis=1)
        from scipy.spatial import cKDTree  # here: scipy.spatial is slow to import

        self._tree = cKDTree(self.centroids)

    def query(self, points_local: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
        """Candidate pairs for points_local (m, 3) [m] in the master body frame.

        Returns (point index, facet index), int64 arrays of equal length, sorted by point then
        facet. Raises InputError on a negative or non-finite radius or badly shaped points.
        """
        p = _as_points(points_local, "points_local")
        if not np.isfinite(radius) or radius < 0.0:
            raise InputError(f"broad-phase radius must be finite and >= 0, got {radius}")
        if len(p) == 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        reach = radius + float(self.circumradius.max())
        from scipy.spatial import cKDTree

        found = cKDTree(p).sparse_distance_matrix(self._tree, reach, output_type="ndarray")
        point = found["i"].astype(np.int64)
        facet = found["j"].astype(np.int64)
        keep = found["v"] <= radius + self.circumradius[facet]
        point, facet = point[keep], facet[keep]
        order = np.lexsort((facet, point))
        return point[order], facet[order]


@dataclass(frozen=True)
class Projection:
    """Closest-point projections of slave points onto master facets, one row per pair.

    point (m,) slave point index; facet (m,) facet index (quads first, then tris);
    nodes (m, 4) master node ids (tri: last id repeated, weight 0); weights (m, 4) shape
    functions N^P at the contact point (sum to 1); xi (m, 2) local coordinates; normal (m, 3)
    unit outward facet normal at the contact point (deformed, global); gap (m,) [m] signed
    normal gap n . (x_S - x_C), negative = penetration; inside (m,) projection inside the
    facet within the tolerance; distance (m,) [m] distance from the slave point to the
    closest point of the facet itself (clamped to its edges; equals |gap| when inside).
    For a pair that is not inside, xi, weights and gap belong to the facet's extended
    surface, not to the facet.
    """

    point: np.ndarray
    facet: np.ndarray
    nodes: np.ndarray
    weights: np.ndarray
    xi: np.ndarray
    normal: np.ndarray
    gap: np.ndarray
    inside: np.ndarray
    distance: np.ndarray

    def __len__(self) -> int:
        return len(self.point)

    def take(self, rows: np.ndarray) -> Projection:
        """The projections at the given rows (index or boolean mask)."""
        return Projection(**{k: getattr(self, k)[rows] for k in self.__dataclass_fields__})


def _quad_newton(xs: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Local coordinates (m, 2) of the closest points of xs (m, 3) on bilinear quads P (m,4,3).

    Minimises f = |x_S - x(xi)|^2 / 2: Newton on the tangency conditions
    (x_S - x) . dx/dxi_i = 0, Gauss-Newton where the Hessian is not positive definite, steps
    capped at 1 in each coordinate and halved until f does not grow. Returns (xi, converged).
    """
    c0 = P.sum(axis=1) / 4.0
    c1 = np.einsum("a,mai->mi", _QUAD_SIGNS[:, 0], P) / 4.0
    c2 = np.einsum("a,mai->mi", _QUAD_SIGNS[:, 1], P) / 4.0
    c3 = np.einsum("a,mai->mi", _QUAD_SIGNS[:, 0] * _QUAD_SIGNS[:, 1], P) / 4.0
    area = np.linalg.norm(np.cross(c1, c2), axis=1)
    flat = area <= 1e-12 * ((c1 * c1).sum(1) + (c2 * c2).sum(1))
    if flat.any():
        raise SolverError(
            f"{int(flat.sum())} quad facet(s) degenerate (zero area at the centre) when deformed"
        )

    def residual(xi: np.ndarray) -> np.ndarray:
        e, h = xi[:, :1], xi[:, 1:]
        return xs - (c0 + c1 * e + c2 * h + c3 * e * h)

    xi = np.zeros((len(xs), 2))
    done = np.zeros(len(xs), dtype=bool)
    stuck = np.zeros(len(xs), dtype=bool)
    r = residual(xi)
    for it in range(NEWTON_MAX_ITER):
        if it == FAR_CHECK_ITER:  # clearly outside the facet: stop (reported outside)
            stuck |= ~done & (np.abs(xi).max(axis=1) > FAR_XI)
        t1, t2 = c1 + c3 * xi[:, 1:], c2 + c3 * xi[:, :1]
        a11, a22, a12 = (t1 * t1).sum(1), (t2 * t2).sum(1), (t1 * t2).sum(1)
        rc = (r * c3).sum(1)
        F1, F2 = (r * t1).sum(1), (r * t2).sum(1)
        h12 = a12 - rc
        det = a11 * a22 - h12 * h12
        indefinite = det <= 1e-12 * a11 * a22
        h12 = np.where(indefinite, a12, h12)
        det = np.where(indefinite, a11 * a22 - a12 * a12, det)
        # the extended map can fold outside the facet (tangents parallel): stop such pairs there
        stuck |= det <= 1e-24 * (a11 + a22) ** 2
        safe = np.where(stuck, 1.0, det)
        step = np.stack([a22 * F1 - h12 * F2, a11 * F2 - h12 * F1], axis=1) / safe[:, None]
        step /= np.maximum(1.0, np.abs(step).max(axis=1))[:, None]
        step[done | stuck] = 0.0
        # tolerance widened where the distance dwarfs the facet, so round-off cannot stall it
        f0 = (r * r).sum(1)
        scale = np.sqrt(f0 / np.maximum(np.minimum(a11, a22), 1e-300))
        done |= ~stuck & (np.abs(step).max(axis=1) <= NEWTON_TOL + 64 * np.finfo(float).eps * scale)
        for _ in range(LINE_SEARCH_HALVINGS):
            trial = np.clip(xi + step, -XI_BOUND, XI_BOUND)
            r_trial = residual(trial)
            # growth beyond round-off of f, on pairs still iterating
            worse = ((r_trial * r_trial).sum(1) > f0 * (1.0 + 1e-9) + 1e-30) & ~(done | stuck)
            tiny = worse & (np.abs(step).max(axis=1) <= NEWTON_TOL)
            if tiny.any():  # no descent left within the tolerance: converged as far as it goes
                done |= tiny
                step[tiny] = 0.0
                worse &= ~tiny
            if not worse.any():
                break
            step[worse] *= 0.5
        xi, r = trial, r_trial
        if (done | stuck).all():
            break
    return xi, done


def _quad_tangents(P: np.ndarray, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tangents dx/dxi, dx/deta (m, 3) of bilinear quads P (m, 4, 3) at xi (m, 2)."""
    Sx, Sy = _QUAD_SIGNS[:, 0], _QUAD_SIGNS[:, 1]
    dN1 = 0.25 * Sx * (1.0 + xi[:, 1:] * Sy)
    dN2 = 0.25 * Sy * (1.0 + xi[:, :1] * Sx)
    return np.einsum("ma,mai->mi", dN1, P), np.einsum("ma,mai->mi", dN2, P)


def _project_tris(
    xs: np.ndarray, P: np.ndarray, facet: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Area coordinates (m, 2) of nodes 1, 2 of the projections of xs on triangles P (m, 4, 3),
    and the edge vectors e1 = x1 - x0, e2 = x2 - x0: the exact linear projection."""
    e1, e2, d = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0], xs - P[:, 0]
    a11, a22, a12 = (e1 * e1).sum(1), (e2 * e2).sum(1), (e1 * e2).sum(1)
    b1, b2 = (d * e1).sum(1), (d * e2).sum(1)
    det = a11 * a22 - a12 * a12
    if np.any(det <= 1e-24 * a11 * a22):
        bad = int(facet[np.argmin(det / np.maximum(a11 * a22, 1e-300))])
        raise SolverError(f"triangle facet {bad} has zero area in the deformed state")
    xt = np.stack([a22 * b1 - a12 * b2, a11 * b2 - a12 * b1], axis=1) / det[:, None]
    return xt, e1, e2


def _unit_normal(
    t1: np.ndarray,
    t2: np.ndarray,
    P: np.ndarray,
    xi: np.ndarray,
    quad_out: np.ndarray,
    facet: np.ndarray,
) -> np.ndarray:
    """t1 x t2 / |t1 x t2| (m, 3). Where a quad's extended map folds at a projection outside
    the facet (quad_out), the normal at the nearest point of [-1, 1]^2 instead; SolverError
    where the facet itself is degenerate."""
    n = np.cross(t1, t2)
    n_len = np.linalg.norm(n, axis=1)
    folded = n_len <= 1e-12 * np.sqrt((t1 * t1).sum(1) * (t2 * t2).sum(1))
    f = folded & quad_out
    if f.any():
        n[f] = np.cross(*_quad_tangents(P[f], np.clip(xi[f], -1.0, 1.0)))
        n_len[f] = np.linalg.norm(n[f], axis=1)
        folded[f] = n_len[f] == 0.0
    if folded.any():
        bad = int(facet[np.argmax(folded)])
        raise SolverError(f"facet {bad} is degenerate at the contact point (tangents parallel)")
    return n / n_len[:, None]


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance (m,) from points p to segments [a, b] (all (m, 3)); a == b allowed."""
    ab = b - a
    L2 = (ab * ab).sum(1)
    t = np.clip(((p - a) * ab).sum(1) / np.where(L2 > 0.0, L2, 1.0), 0.0, 1.0)
    return np.linalg.norm(p - a - t[:, None] * ab, axis=1)


def _check_pairs(
    pairs: tuple[np.ndarray, np.ndarray], n_points: int, n_facets: int
) -> tuple[np.ndarray, np.ndarray]:
    point = np.asarray(pairs[0], dtype=np.int64).ravel()
    facet = np.asarray(pairs[1], dtype=np.int64).ravel()
    if point.shape != facet.shape:
        raise InputError(
            f"pairs must be two arrays of equal length, got {point.shape} and {facet.shape}"
        )
    for name, idx, n in (("point", point, n_points), ("facet", facet, n_facets)):
        if idx.size and (idx.min() < 0 or idx.max() >= n):
            raise InputError(
                f"pair {name} indices span {idx.min()}..{idx.max()}, expected 0..{n - 1}"
            )
    return point, facet


def project_points(
    x_slave: np.ndarray,
    x_master_nodes: np.ndarray,
    surface: MasterSurface,
    pairs: tuple[np.ndarray, np.ndarray],
    inside_tol: float = 1e-6,
) -> Projection:
    """Closest-point projection of every candidate pair (seed eq. 7-8), vectorised over pairs.

    x_slave (n_points, 3) [m] global deformed slave positions; x_master_nodes (n_nodes, 3) [m]
    global deformed master positions indexed by master node id; pairs (point idx, facet idx).
    Quads: Newton on the tangency conditions of the bilinear map from the facet centre, to
    1e-12 in (xi, eta); tris: exact linear projection (barycentric coordinates). The normal is
    t_xi x t_eta / |.|, outward by the facet's node order. A pair is inside when
    |xi|, |eta| <= 1 + inside_tol (quad) or all area coordinates >= -inside_tol (tri), and no
    edge of the facet is closer than the projection (far from a warped quad the stationary
    point Newton finds need not be the closest point of the facet).

    Raises InputError on bad shapes or indices, SolverError on a degenerate deformed facet. A
    pair whose Newton iteration does not converge is reported with inside=False.
    """
    xs_all = _as_points(x_slave, "x_slave")
    xm = _as_points(x_master_nodes, "x_master_nodes")
    _check_nodes_cover(xm, surface, "x_master_nodes")
    point, facet = _check_pairs(pairs, len(xs_all), surface.n_facets)
    nodes = surface.connectivity[facet]
    P, xs = xm[nodes], xs_all[point]
    m = len(point)
    xi, weights = np.zeros((m, 2)), np.zeros((m, 4))
    t1, t2, inside = np.zeros((m, 3)), np.zeros((m, 3)), np.zeros(m, dtype=bool)

    q = facet < surface.n_quads
    if q.any():
        xq, conv = _quad_newton(xs[q], P[q])
        # a pair whose Newton did not converge is reported outside its facet: the caller
        # falls back to the clamped closest point (a long run must not stop on one pair)
        inside_q = (np.abs(xq).max(axis=1) <= 1.0 + inside_tol) & conv
        Sx, Sy = _QUAD_SIGNS[:, 0], _QUAD_SIGNS[:, 1]
        weights[q] = 0.25 * (1.0 + xq[:, :1] * Sx) * (1.0 + xq[:, 1:] * Sy)
        t1[q], t2[q] = _quad_tangents(P[q], xq)
        xi[q], inside[q] = xq, inside_q

    t = ~q
    if t.any():
        xt, t1[t], t2[t] = _project_tris(xs[t], P[t], facet[t])
        weights[t, :3] = np.column_stack([1.0 - xt.sum(1), xt])
        xi[t], inside[t] = xt, weights[t, :3].min(axis=1) >= -inside_tol

    n = _unit_normal(t1, t2, P, xi, q & ~inside, facet)
    x_c = np.einsum("ma,mai->mi", weights, P)
    gap = ((xs - x_c) * n).sum(1)
    dist = np.linalg.norm(xs - x_c, axis=1)
    edge = np.min([_segment_distance(xs, P[:, k], P[:, (k + 1) % 4]) for k in range(4)], axis=0)
    # a warped quad can hold an interior stationary point farther than its own edge
    inside &= dist <= edge + 1e-12 * (edge + np.linalg.norm(P[:, 2] - P[:, 0], axis=1))
    dist = np.where(inside, dist, edge)
    return Projection(point, facet, nodes, weights, xi, n, gap, inside, dist)


def closest_facets(proj: Projection) -> Projection:
    """One pair per slave point: the closest facet, its distance |gap| for an inside
    projection and the distance to the clamped facet for an outside one (reported with
    inside=False); a tie to round-off (TIE_REL, TIE_ABS) goes to the inside pair.

    The true closest point, not "inside first": off a convex surface (a sphere) the prisms of
    the near facets leave gaps where a point projects inside none of them, while it projects
    inside facets on the far side, behind it, with a large negative gap. A point just outside
    one facet's edge and inside its neighbour gets the neighbour (it is closer).
    Returns the filtered Projection, sorted by point index.
    """
    score = np.where(proj.inside, np.abs(proj.gap), proj.distance * (1.0 + TIE_REL) + TIE_ABS)
    order = np.lexsort((~proj.inside, score, proj.point))
    _, first = np.unique(proj.point[order], return_index=True)
    return proj.take(order[first])


def facet_adjacency(connectivity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Facets sharing a node with each facet (itself excluded), CSR (indptr, indices)."""
    nf = len(connectivity)
    inc = sp.csr_matrix(
        (np.ones(connectivity.size), (np.repeat(np.arange(nf), 4), connectivity.ravel()))
    )
    adj = (inc @ inc.T).tocsr()
    adj.setdiag(0)
    adj.eliminate_zeros()
    adj.sort_indices()
    return adj.indptr.astype(np.int64), adj.indices.astype(np.int64)
