"""What the compiled search (contact.search) reads and keeps, as typed tuples of arrays.

Three named tuples, built once on the Python side and passed whole to the kernels (numba
types a NamedTuple of arrays as a struct; its fields are read by name in the kernels):

- :class:`FacetSurface`: the facets searched, fixed for a contact: undeformed centroids and
  circumradii, connectivity, adjacency, the bounding box, a uniform grid of the facets
  (:func:`facet_grid`) and the projection tolerances.
- :class:`SearchState`: what the search keeps per node between calls (its candidate superset
  and last facet) and its work arrays.
- :class:`MemoArrays`: the projections kept at the current node positions
  (:class:`ProjectionMemo`).

Units: metres. Facets are in the body frame of the body that carries them; node ids in conn
are local (indices into that body's ContactNodes).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from flexmvm.contact.geometry import BroadPhase, MasterSurface, facet_adjacency
from flexmvm.contact.nodes import ContactNodes
from flexmvm.contact.projection import REC_LEN, projection_params

#: Cells of a facet grid per facet, at most (the cell edge grows until it holds).
GRID_CELLS_PER_FACET = 2.0
#: Candidate supersets longer than this fall back to a scan of all facets.
LIST_CAP = 256


class FacetGrid(NamedTuple):
    """A uniform grid over the facet centroids (:func:`facet_grid`)."""

    meta: np.ndarray  # (5,) origin xyz [m], cell edge [m], largest circumradius [m]
    dims: np.ndarray  # (3,) int64 cells per axis
    start: np.ndarray  # (n_cells + 1,) int64: cell c holds facets[start[c]:start[c + 1]]
    facets: np.ndarray  # (nf,) int64 facet ids, by cell, increasing within a cell


class FacetSurface(NamedTuple):
    """The facets of one contact surface as the search reads them (fixed for a contact)."""

    geo: np.ndarray  # (nf, 4) undeformed centroid [m] and circumradius [m], body frame
    conn: np.ndarray  # (nf, 4) int64 local node ids (a triangle repeats its last node)
    n_quads: int  # facets 0..n_quads-1 are bilinear quads, the rest triangles
    adj_ptr: np.ndarray  # (nf + 1,) int64 facet adjacency (CSR, geometry.facet_adjacency)
    adj_idx: np.ndarray  # int64
    box: np.ndarray  # (2, 3) lower / upper corner of the surface nodes, body frame [m]
    rho: float  # extra radius of the cached candidate supersets [m]
    params: np.ndarray  # (7,) projection tolerances (projection.projection_params)
    grid: FacetGrid
    plane: np.ndarray  # (nf, 4) unit normal and half-thickness [m] (facet_planes), body frame
    edges: np.ndarray  # (nf, 3, 4) a triangle's edge half-planes (facet_edges), body frame


class SearchState(NamedTuple):
    """Search state of n nodes against nf facets: kept between calls, per node, its candidate
    superset (lists: count first, -1 when it overflowed, then facet ids; ref: the position
    and radius it was built for), its last facet (prev, -1: none) and the certificate that
    it still wins (cert, contact.certificate); work arrays mark, counter (1,), cand, lb."""

    lists: np.ndarray  # (n, min(nf, cap) + 1) int64
    ref: np.ndarray  # (n, 4) position [m] and radius [m]; radius < 0: none yet
    prev: np.ndarray  # (n,) int64
    mark: np.ndarray  # (nf,) int64
    counter: np.ndarray  # (1,) int64
    cand: np.ndarray  # (nf,) int64
    lb: np.ndarray  # (nf,) lower bounds of the candidates' distances [m]
    cert: np.ndarray  # (n, 6) the warm start's certificate (contact.certificate.certify)

    @classmethod
    def empty(cls, n: int, nf: int, cap: int = LIST_CAP) -> SearchState:
        """A state with no node searched yet."""
        return cls(
            np.zeros((n, min(nf, cap) + 1), dtype=np.int64),
            np.full((n, 4), -1.0),
            np.full(n, -1, dtype=np.int64),
            np.zeros(nf, dtype=np.int64),
            np.zeros(1, dtype=np.int64),
            np.zeros(nf, dtype=np.int64),
            np.zeros(nf),
            np.full((n, 6), -np.inf),
        )


class MemoArrays(NamedTuple):
    """Projections kept at the positions of versions node_version[0], facet_version[0] of the
    two node sets (ContactNodes.version); see ProjectionMemo."""

    facets: np.ndarray  # (n, k) int64 facet of each kept projection
    count: np.ndarray  # type: ignore[assignment]  # (n,) int64 projections kept per node (the name shadows tuple.count; the kernels read it)
    records: np.ndarray  # (n, k, REC_LEN) the projections (projection.REC_*)
    versions: np.ndarray  # (2,) int64 the versions they were made at
    node_version: np.ndarray  # (1,) int64, the nodes' ContactNodes.version
    facet_version: np.ndarray  # (1,) int64, the facet nodes' ContactNodes.version


def facet_surface(
    X: np.ndarray, surface: MasterSurface, conn: np.ndarray, broad: BroadPhase, search_radius: float
) -> FacetSurface:
    """The search's view of `surface` of a body with nodes X (n, 3) [m]: conn (nf, 4) its
    connectivity in local node ids, broad its broad phase (centroids, circumradii), and the
    supersets' extra radius rho = max(search_radius, half the median circumradius) [m]."""
    Xs = X[surface.nodes()]
    box = np.vstack([Xs.min(axis=0), Xs.max(axis=0)]).astype(np.float64)
    geo = np.column_stack([broad.centroids, broad.circumradius])
    rho = max(search_radius, 0.5 * float(np.median(broad.circumradius)))
    corners = np.asarray(X, dtype=np.float64)[surface.connectivity]
    return FacetSurface(
        geo,
        np.asarray(conn, dtype=np.int64),
        surface.n_quads,
        *facet_adjacency(surface.connectivity),
        box,
        rho,
        projection_params(),
        facet_grid(geo),
        facet_planes(corners, surface.n_quads, geo[:, :3]),
        facet_edges(corners, surface.n_quads),
    )


def facet_planes(corners: np.ndarray, n_quads: int, centroids: np.ndarray) -> np.ndarray:
    """Per facet (nf, 4): a unit normal n (the cross product of the diagonals of a quad, of
    two edges of a triangle) and the half-thickness t = max_a |n . (X_a - c)| [m] of its
    corners X_a (corners (nf, 4, 3), undeformed, body frame; c the centroid) about the plane
    through c. The facet (a bilinear quad or a triangle: inside the convex hull of its
    corners) lies in the slab |n . (x - c)| <= t and in the ball |x - c| <= R (R its
    circumradius): certificate.slab_bound's lower bound of a point's distance to it. A facet with
    no normal (zero cross product) gets n = 0, t = 0 (the bound is then the ball's)."""
    corners = np.asarray(corners, dtype=np.float64)
    nf = len(corners)
    quad = (np.arange(nf) < n_quads)[:, None]
    a = np.where(quad, corners[:, 2] - corners[:, 0], corners[:, 1] - corners[:, 0])
    b = np.where(quad, corners[:, 3] - corners[:, 1], corners[:, 2] - corners[:, 0])
    n = np.cross(a, b)
    norm = np.linalg.norm(n, axis=1)
    ok = norm > 0.0
    n[ok] /= norm[ok, None]
    n[~ok] = 0.0
    t = np.abs(np.einsum("fi,fai->fa", n, corners - centroids[:, None])).max(axis=1)
    return np.ascontiguousarray(np.column_stack([n, t]).reshape(nf, 4))


def facet_edges(corners: np.ndarray, n_quads: int) -> np.ndarray:
    """Per facet (nf, 3, 4): the three edges of a triangle as half-planes m . x <= o of its
    plane, m (3,) the unit in-plane normal of the edge pointing away from the third corner
    and o [m] (corners (nf, 4, 3) undeformed, body frame): the triangle is their intersection
    with its plane, so max(0, max_e m_e . p - o_e) is a lower bound of p's lateral distance
    to it (certificate.triangle_bound). Quads (possibly warped) and degenerate triangles get
    m = 0, o = inf (no lateral bound)."""
    corners = np.asarray(corners, dtype=np.float64)
    nf = len(corners)
    out = np.zeros((nf, 3, 4))
    out[:, :, 3] = np.inf
    tri = corners[n_quads:, :3]
    if len(tri):
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        for e in range(3):
            a, b, c = tri[:, e], tri[:, (e + 1) % 3], tri[:, (e + 2) % 3]
            m = np.cross(b - a, n)
            norm = np.linalg.norm(m, axis=1)
            ok = norm > 0.0
            m[ok] /= norm[ok, None]
            m[~ok] = 0.0
            m[np.einsum("fi,fi->f", m, c - a) > 0.0] *= -1.0
            o = np.where(ok, np.einsum("fi,fi->f", m, a), np.inf)
            out[n_quads:, e, :3], out[n_quads:, e, 3] = m, o
    return out


def facet_grid(geo: np.ndarray) -> FacetGrid:
    """A uniform grid over facet centroids geo[:, :3] [m] (circumradii geo[:, 3]), so that a
    node's superset is rebuilt from the cells about it, not from every facet: the search's
    cost follows the facets near the nodes, not the surface's size (benchmarks/
    bench_search.py). The cell edge is twice the median circumradius, grown until the grid
    has at most GRID_CELLS_PER_FACET cells per facet; no facets: one empty cell."""
    geo = np.asarray(geo, dtype=np.float64)
    nf = len(geo)
    if nf == 0:
        return FacetGrid(
            np.array([0.0, 0.0, 0.0, 1.0, 0.0]),
            np.ones(3, dtype=np.int64),
            np.zeros(2, dtype=np.int64),
            np.zeros(0, dtype=np.int64),
        )
    c, r = geo[:, :3], geo[:, 3]
    lo, hi = c.min(axis=0), c.max(axis=0)
    span = np.maximum(hi - lo, 0.0)
    edge = max(2.0 * float(np.median(r)), 1e-12 * max(float(span.max()), 1e-300), 1e-300)
    while True:
        dims = np.maximum(np.floor(span / edge).astype(np.int64) + 1, 1)
        if float(np.prod(dims.astype(float))) <= max(GRID_CELLS_PER_FACET * nf, 1.0):
            break
        edge *= 1.5
    ijk = np.minimum(((c - lo) / edge).astype(np.int64), dims - 1)
    cell = (ijk[:, 0] * dims[1] + ijk[:, 1]) * dims[2] + ijk[:, 2]
    order = np.argsort(cell, kind="stable")
    start = np.zeros(int(np.prod(dims)) + 1, dtype=np.int64)
    np.add.at(start, cell + 1, 1)
    np.cumsum(start, out=start)
    meta = np.array([lo[0], lo[1], lo[2], edge, float(r.max())])
    return FacetGrid(meta, dims, start, order.astype(np.int64))


class ProjectionMemo:
    """Closest-point projections of the nodes of `nodes` (ContactNodes, n nodes) on the facets
    conn (nf, 4) (local ids into `facets`, a ContactNodes), with the projection params, up to
    k per node, kept while neither set's positions changed (their versions): search.scan_nodes
    and penetration.penetration_scan read a kept one instead of projecting again
    (search._try). Scans of all of these nodes against these facets with these params may
    share one memo (serves); k = 0 keeps none."""

    def __init__(
        self,
        nodes: ContactNodes,
        facets: ContactNodes,
        conn: np.ndarray,
        params: np.ndarray,
        k: int = 8,
    ):
        n = len(nodes.nodes)
        self.nodes, self.facets = nodes, facets
        self.conn, self.params = np.array(conn, dtype=np.int64), np.array(params, dtype=np.float64)
        self.arrays = MemoArrays(
            np.zeros((n, k), dtype=np.int64),
            np.zeros(n, dtype=np.int64),
            np.zeros((n, k, REC_LEN)),
            np.full(2, -1, dtype=np.int64),
            nodes.version,
            facets.version,
        )

    def serves(
        self, nodes: ContactNodes, facets: ContactNodes, conn: np.ndarray, params: np.ndarray
    ) -> bool:
        """Whether a scan of all nodes of `nodes` against the facets conn over `facets` with
        these params may use this memo."""
        return (
            nodes is self.nodes
            and facets is self.facets
            and self.arrays.facets.shape[1] > 0
            and np.array_equal(conn, self.conn)
            and np.array_equal(params, self.params)
        )
