"""The expected first contact point of two placed surfaces and their relative curvature
there, from their meshes alone (studies.region_estimate's steps 2, 3 and the facet size h of step 6):
the point from the nodes' outward normals, the curvature from a polynomial fit of each
surface's height over the tangent plane (Johnson, *Contact Mechanics*, 1985, sect. 4.1).
Lengths in metres, global coordinates.
"""

from __future__ import annotations

import math

import numpy as np

from flexmvm.errors import InputError

__all__ = ["equivalent_radius", "facet_size", "first_contact"]

#: Surface nodes about the contact point fitted for the curvature (>= 6 unknowns of the fit).
NEIGHBOURS = 30
#: Below this curvature x fit radius a surface counts as flat: a deviation from its tangent
#: plane of ~1e-6 of the fitted patch, the round-off of a mesh's coordinates.
FLAT = 1e-6


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _node_normals(x: np.ndarray, fs) -> np.ndarray:
    """Outward unit normals (n, 3) at the nodes of facet set ``fs`` (positions ``x``): the
    area-weighted mean of the normals of the facets at each node (zero off the surface)."""
    acc = np.zeros_like(x)
    for f in (fs.tris, fs.quads):
        if not len(f):
            continue
        if f.shape[1] == 3:
            nf = np.cross(x[f[:, 1]] - x[f[:, 0]], x[f[:, 2]] - x[f[:, 0]])
        else:
            nf = np.cross(x[f[:, 2]] - x[f[:, 0]], x[f[:, 3]] - x[f[:, 1]])
        for corner in f.T:
            np.add.at(acc, corner, nf)
    norm = np.linalg.norm(acc, axis=1)
    return np.divide(acc, norm[:, None], out=np.zeros_like(acc), where=norm[:, None] > 0)


def _triangle_closest(p: np.ndarray, tri: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(distances [m] from point ``p`` (3,) to the triangles ``tri`` (n, 3 corners, 3), the
    nearest points (n, 3)): the foot of ``p`` in the plane where it falls inside, else the
    nearest point of the nearest edge."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    nrm = np.cross(b - a, c - a)
    nn = np.einsum("ij,ij->i", nrm, nrm)
    foot = p - (np.einsum("ij,ij->i", p - a, nrm) / nn)[:, None] * nrm
    # barycentric signs: the foot inside when it is on the inner side of all three edges
    inside = np.ones(len(tri), bool)
    for u, v in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ij,ij->i", np.cross(v - u, foot - u), nrm) >= 0.0
    d = np.where(inside, np.linalg.norm(p - foot, axis=1), np.inf)
    q = foot.copy()
    for u, v in ((a, b), (b, c), (c, a)):
        e = v - u
        t = np.clip(np.einsum("ij,ij->i", p - u, e) / np.einsum("ij,ij->i", e, e), 0.0, 1.0)
        on_edge = u + t[:, None] * e
        de = np.linalg.norm(p - on_edge, axis=1)
        nearer = de < d
        d = np.where(nearer, de, d)
        q[nearer] = on_edge[nearer]
    return d, q


def _triangle_distance(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Distances [m] from point ``p`` (3,) to the triangles ``tri`` (n, 3 corners, 3)."""
    return _triangle_closest(p, tri)[0]


def _surface_point(nodes: np.ndarray, fs, p: np.ndarray) -> np.ndarray:
    """The point of the facets of ``fs`` (node positions ``nodes``) nearest ``p`` (3,)."""
    best, where = np.inf, p
    for f in (fs.tris, fs.quads):
        if not len(f):
            continue
        xf = nodes[f]
        for t in [(0, 1, 2)] if f.shape[1] == 3 else [(0, 1, 2), (0, 2, 3)]:
            d, q = _triangle_closest(p, xf[:, list(t)])
            k = int(np.argmin(d))
            if d[k] < best:
                best, where = float(d[k]), q[k]
    return where


def facet_size(nodes: np.ndarray, fs, point: np.ndarray, a: float) -> float:
    """h of the rule a + h [m] (studies.region_estimate module doc, step 6): the largest diameter
    (largest node-to-node distance) of the facets of ``fs`` (node positions ``nodes``) that
    the ball of radius ``a`` about ``point`` meets; the facet nearest the point if none (a
    mesh coarser than a)."""
    diams: list[np.ndarray] = []
    dists: list[np.ndarray] = []
    for f in (fs.tris, fs.quads):
        if not len(f):
            continue
        xf = nodes[f]  # (n, k, 3)
        diams.append(np.max(np.linalg.norm(xf[:, :, None] - xf[:, None, :], axis=3), axis=(1, 2)))
        parts = [(0, 1, 2)] if f.shape[1] == 3 else [(0, 1, 2), (0, 2, 3)]
        dists.append(np.min([_triangle_distance(point, xf[:, list(t)]) for t in parts], axis=0))
    diam, dist = np.concatenate(diams), np.concatenate(dists)
    touched = dist <= a
    return float(diam[touched].max() if touched.any() else diam[np.argmin(dist)])


def _curvature(points: np.ndarray, x0: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, float]:
    """(curvature tensor (3, 3) in the tangent plane of ``n``, convex positive [1/m]; radius of
    the fitted patch [m]) of the surface nodes ``points`` nearest ``x0`` (studies.region_estimate
    module doc, step 3).
    The height is fitted by a polynomial of degree 4 in (u, v) (2 with fewer than 15 nodes),
    so that the quartic fall-off of a sphere over a patch of a few elements (r^4 / 8 R^3) is
    not read as curvature: on a sphere meshed at R / 4 the quadratic fit alone gives R 10 %
    small."""
    d = np.linalg.norm(points - x0, axis=1)
    near = points[np.argsort(d)[:NEIGHBOURS]]
    if len(near) < 6:
        raise InputError(
            f"{len(near)} surface nodes about the contact point; the curvature "
            "fit needs at least 6: give radius_m"
        )
    t1 = _unit(np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0]))
    t2 = np.cross(n, t1)
    rel = near - x0
    rho = float(np.max(np.hypot(rel @ t1, rel @ t2)))
    u, v, h = rel @ t1 / rho, rel @ t2 / rho, rel @ n / rho  # scaled to the patch
    degree = 4 if len(near) >= 15 else 2
    terms = [u**i * v ** (k - i) for k in range(degree + 1) for i in range(k, -1, -1)]
    c = np.linalg.lstsq(np.column_stack(terms), h, rcond=None)[0]
    # c[3], c[4], c[5]: the u^2, u v, v^2 coefficients (of the scaled height)
    k2 = -np.array([[2 * c[3], c[4]], [c[4], 2 * c[5]]]) / rho
    T = np.column_stack([t1, t2])
    return T @ k2 @ T.T, rho


def first_contact(x: np.ndarray, fs, px: np.ndarray, pfs) -> tuple[np.ndarray, np.ndarray]:
    """(expected first contact point (3,), the body's outward unit normal there (3,)), global,
    from the body's nodes ``x`` and surface ``fs`` and the partner's ``px``, ``pfs`` (studies.region_estimate
    module doc, step 2). The point is the point of the body's facets nearest the partner's
    first node: on the body, also at an edge or a corner, where the projection onto the
    tangent plane of a node's averaged normal left the body."""
    from scipy.spatial import cKDTree

    mine, theirs = fs.nodes, pfs.nodes
    normals = _node_normals(x, fs)
    nearest = mine[cKDTree(x[mine]).query(px[theirs])[1]]
    gap = np.einsum("ij,ij->i", px[theirs] - x[nearest], normals[nearest])
    # ties (a flat face on a flat face): the tied node nearest the middle of the tied ones
    tied = np.flatnonzero(gap <= gap.min() + 1e-9 * np.ptp(px[theirs], axis=0).max())
    mid = px[theirs[tied]].mean(axis=0)
    j = int(tied[np.argmin(np.linalg.norm(px[theirs[tied]] - mid, axis=1))])
    node, pnode = int(nearest[j]), int(theirs[j])
    return _surface_point(x, fs, px[pnode]), normals[node]


def equivalent_radius(
    body_points: np.ndarray, partner_points: np.ndarray, point: np.ndarray, n: np.ndarray, what: str
) -> tuple[float, tuple[float, float]]:
    """(R_e [m], principal radii (R', R'') [m]) of the two surfaces' summed curvature at
    ``point`` (studies.region_estimate module doc, step 3); InputError naming ``what`` without
    curvature."""
    curv_b, rho_b = _curvature(body_points, point, n)
    curv_p, rho_p = _curvature(partner_points, point, -n)
    T = np.linalg.svd(np.eye(3) - np.outer(n, n))[0][:, :2]
    kappa = np.linalg.eigvalsh(T.T @ (curv_b + curv_p) @ T)
    if kappa[0] * max(rho_b, rho_p) < FLAT:
        raise InputError(
            f"{what} have no relative curvature at the expected contact point (principal "
            f"curvatures {kappa[0]:.3g}, {kappa[1]:.3g} 1/m: a flat, line or conforming "
            "contact); give the equivalent curvature radius (radius_m, --radius-mm)"
        )
    principal = (1.0 / kappa[1], 1.0 / kappa[0])
    return math.sqrt(principal[0] * principal[1]), principal
