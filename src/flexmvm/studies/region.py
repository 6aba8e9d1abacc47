"""The retained region a contact needs, estimated before any run: a ball about the expected
first contact point whose radius is the Hertz contact radius of the expected impact plus the
size of the body's contact facets there, and what that region costs on the body's mesh (DESIGN.md "Sizing a reduced region").

Steps (all at the scenario's initial placements, in SI units):

1. The contact: the body's first contact in the scenario (or ``contact``), its partner body
   and the two facet sets.
2. The expected first contact point: the partner's surface node of smallest normal gap to
   the body's surface (measured from its nearest body surface node along that node's outward
   normal, the area-weighted mean of its facets' normals), projected onto the body's tangent
   plane there (a sphere's pole above a flat face gives the point below it, not the nearest
   face node); of tied nodes (flat on flat) the one nearest their middle. ``n`` is that
   outward normal.
3. The relative curvature: each surface's nodes nearest that point (NEIGHBOURS of them) are
   fitted by a height over the tangent plane, h = c0 + c1 u + c2 v - (k_uu u^2 + 2 k_uv u v
   + k_vv v^2) / 2 + higher terms (convex positive: the curvatures k); the two curvature
   tensors are added (Johnson, *Contact Mechanics*, 1985, sect. 4.1: A + B) and the sum's
   principal curvatures 1/R', 1/R'' give
   the equivalent radius R_e = sqrt(R' R'') (Johnson eq. 4.29, the circular contact of the
   same area). A sum without curvature (flat on flat, a cylinder's line contact, conforming
   surfaces) has no Hertz point contact: the estimate then needs ``radius_m``.
4. The closing speed: the normal component of the relative velocity of the two bodies'
   material points at the contact point (placements' velocity and angular velocity); none
   (bodies at rest or separating) needs ``speed_mps``.
5. Hertz (theory/hertz.py, Johnson eq. 11.24) with E* of the two materials and the bodies'
   masses (a body on a joint to the ground other than a distance joint does not recoil:
   infinite mass, which overestimates the force and the radius) gives the contact radius a.
6. The region: the ball of radius ``a + h`` about the contact point (body-local coordinates),
   h the largest diameter of the body's contact facets that the circle of radius a about the
   point touches (``facet_size_m``; the linear sub-facets of a quadratic mesh, whose nodes all
   carry contact), or ``factor x a`` if a factor is given; its nodes, its DOF 3 x nodes +
   modes and its memory (scenarios/cost.py).

The rule a + h. The ball must hold every node of the facets the contact circle touches (a node
outside the region moves only as the basis lets it: held stiff, the contact force comes out
high). Such a node is at most a (the circle) + h (its facet's diameter) from the point, so
a + h holds them all, on any mesh; a fixed multiple of a cannot (the former default 2 a
assumed elements of about a). Measured over 1 ms on the sphere-on-beam showcase, MVM against
full FE (docs/notes/2026-11-27-select-on-meshes.md; Hertz a = 0.379 mm, an upper bound: the
free beam's peak is 258 N against the half-space's 438 N, its contact radius ~0.30 mm):

- tet10 beam refined for the contact (0.2 mm elements, sub-facets h = 0.115 mm), the beam's
  top as slave: a + h = 0.49 mm (1.30 a, 256 nodes, 798 DOF with 30 modes). Peak error with
  20 / 30 modes by ball radius: 0.25 mm (0.66 a, 18-20 % of the contact impulse outside the
  region) +20 / +17 %; 0.3 mm (0.79 a) +3.1 / +0.05 %; 0.4 mm +1.0 / -0.08 %; 0.5 mm (~a + h) +0.09
  / -0.01 %; 0.6 mm +4.7 / +0.8 % (more interface, the same modes). Force NCC >= 0.99999
  from 0.3 to 0.5 mm with 30 modes. a + h is where the peak no longer depends on the modes;
  2 a (0.76 mm) kept 624 nodes, 1,902 DOF.
- tet4 beam with 0.4 mm elements at the contact (h = 0.41 mm), the sphere's pole the only
  slave: a + h = 0.78 mm (2.07 a, the former 2 a); from 1.06 a (4 nodes) on, the radius no
  longer mattered and the modes did (NCC 0.999998 at 60 modes); 0.66 a (2 nodes) left a third
  of the contact outside (0.977 / 0.966 with 30 / 60 modes).

The estimate is a starting point: `flexmvm select` finds the smallest model that reaches an
accuracy (here 0.3 mm + 20 modes, 221 DOF, for force NCC >= 0.999, its peak +3.1 %).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError, MeshError
from flexmvm.scenarios import Scenario
from flexmvm.scenarios.cost import BodyCost, reduced_cost
from flexmvm.theory.hertz import HertzImpact, effective_modulus, hertz_impact

__all__ = ["RegionEstimate", "estimate_region"]

#: Surface nodes about the contact point fitted for the curvature (>= 6 unknowns of the fit).
NEIGHBOURS = 30
#: Below this curvature x fit radius a surface counts as flat: a deviation from its tangent
#: plane of ~1e-6 of the fitted patch, the round-off of a mesh's coordinates.
FLAT = 1e-6
#: Mode count of the estimated model when the body's model gives none.
DEFAULT_MODES = 30


@dataclass(frozen=True)
class RegionEstimate:
    """The estimated region of body ``body`` for its contact ``contact`` with ``partner``
    (module doc). Lengths [m], speed [m/s]; ``centre_m`` in the body's own coordinates,
    ``contact_point_m`` and ``normal`` global; ``dof`` = 3 x ``nodes`` + ``modes`` (elastic
    coordinates); ``cost`` the memory of that reduced body against its full-FE body."""

    body: str
    contact: int
    partner: str
    surface: str
    centre_m: tuple[float, float, float]
    contact_point_m: tuple[float, float, float]
    normal: tuple[float, float, float]
    closing_speed_mps: float
    speed_given: bool
    curvature_radius_m: float
    principal_radii_m: tuple[float, float]
    radius_given: bool
    hertz: HertzImpact
    factor: float | None
    facet_size_m: float
    radius_m: float
    nodes: int
    modes: int
    dof: int
    cost: BodyCost

    @property
    def contact_radius_m(self) -> float:
        return self.hertz.contact_radius_m

    def region(self) -> dict:
        """The scenario's ``region`` of this estimate: ``{"ball": {centre_m, radius_m}}``."""
        return {"ball": {"centre_m": list(self.centre_m), "radius_m": self.radius_m}}

    def as_dict(self) -> dict:
        h = self.hertz
        return {
            "body": self.body,
            "contact": self.contact,
            "partner": self.partner,
            "surface": self.surface,
            "centre_m": list(self.centre_m),
            "contact_point_m": list(self.contact_point_m),
            "normal": list(self.normal),
            "closing_speed_mps": self.closing_speed_mps,
            "speed_given": self.speed_given,
            "curvature_radius_m": self.curvature_radius_m,
            "principal_radii_m": list(self.principal_radii_m),
            "radius_given": self.radius_given,
            "e_star_pa": h.e_star_pa,
            "m_star_kg": h.m_star_kg,
            "hertz_force_max_n": h.force_max_n,
            "hertz_duration_s": h.duration_s,
            "contact_radius_m": h.contact_radius_m,
            "factor": self.factor,
            "facet_size_m": self.facet_size_m,
            "rule": "a + h" if self.factor is None else "factor x a",
            "radius_m": self.radius_m,
            "nodes": self.nodes,
            "modes": self.modes,
            "dof": self.dof,
            "dof_total": self.cost.dof,
            "memory_MB": self.cost.bytes / 1e6,
            "full_fe_dof": self.cost.full_dof,
            "full_fe_memory_MB": self.cost.full_bytes / 1e6,
            "costs_more_than_full_fe": self.cost.bytes > self.cost.full_bytes,
            "region": self.region(),
        }

    def lines(self) -> list[str]:
        """The console lines of the estimate."""
        h, mm = self.hertz, 1e3
        c = ", ".join(f"{v * mm:.4g}" for v in self.centre_m)
        rs = (
            "given"
            if self.radius_given
            else "fitted, principal "
            + ", ".join(f"{r * mm:.4g}" for r in self.principal_radii_m)
            + " mm"
        )
        given = " (given)" if self.speed_given else ""
        lines = [
            (
                f"contacts[{self.contact}]: {self.body}.{self.surface} against {self.partner}; "
                f"expected first contact at ({c}) mm in {self.body}'s coordinates"
            ),
            (
                f"Hertz impact: closing speed {self.closing_speed_mps:.4g} m/s{given}, curvature "
                f"radius {self.curvature_radius_m * mm:.4g} mm ({rs}), E* "
                f"{h.e_star_pa / 1e9:.4g} GPa, m* {h.m_star_kg:.4g} kg: peak "
                f"{h.force_max_n:.4g} N, contact radius a {h.contact_radius_m * mm:.4g} mm, "
                f"duration {h.duration_s * 1e6:.4g} us"
            ),
            (
                f"region: ball of {self._rule()} = {self.radius_m * mm:.4g} mm: {self.nodes} "
                f"nodes, {self.dof} DOF with {self.modes} modes"
            ),
            self.cost.line(),
        ]
        if self.nodes == 0:
            lines.append(
                "the ball holds no node of the mesh: its elements are coarser than "
                "the contact (elements of about a resolve the force); refine the mesh "
                "about the contact point or raise the factor (or leave it out: a + h)"
            )
        if self.cost.bytes > self.cost.full_bytes:
            lines.append(
                "this region costs more than full FE: a smaller region (or a coarser "
                "mesh about the contact), or kind 'full'"
            )
        return lines

    def _rule(self) -> str:
        mm = 1e3
        if self.factor is not None:
            return f"{self.factor:g} a"
        return (
            f"a + h (h {self.facet_size_m * mm:.4g} mm: the largest contact facet within "
            f"a) = {self.radius_m / self.contact_radius_m:.3g} a"
        )


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _placed(cfg, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(global node positions (n, 3), rotation A (3, 3), frame origin (3,)) at placement."""
    A = cfg.placement.rotation.matrix()
    r = np.asarray(cfg.placement.position_m, float)
    return r + nodes @ A.T, A, r


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


def _triangle_distance(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Distances [m] from point ``p`` (3,) to the triangles ``tri`` (n, 3 corners, 3): to the
    foot of ``p`` in the plane where it falls inside, else to the nearest edge."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    nrm = np.cross(b - a, c - a)
    nn = np.einsum("ij,ij->i", nrm, nrm)
    foot = p - (np.einsum("ij,ij->i", p - a, nrm) / nn)[:, None] * nrm
    # barycentric signs: the foot inside when it is on the inner side of all three edges
    inside = np.ones(len(tri), bool)
    for u, v in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ij,ij->i", np.cross(v - u, foot - u), nrm) >= 0.0
    d = np.where(inside, np.linalg.norm(p - foot, axis=1), np.inf)
    for u, v in ((a, b), (b, c), (c, a)):
        e = v - u
        t = np.clip(np.einsum("ij,ij->i", p - u, e) / np.einsum("ij,ij->i", e, e), 0.0, 1.0)
        d = np.minimum(d, np.linalg.norm(p - (u + t[:, None] * e), axis=1))
    return d


def _facet_size(nodes: np.ndarray, fs, point: np.ndarray, a: float) -> float:
    """h of the rule a + h [m] (module doc, step 6): the largest diameter (largest node-to-node
    distance) of the facets of ``fs`` (node positions ``nodes``) that the ball of radius ``a``
    about ``point`` meets; the facet nearest the point if none (a mesh coarser than a)."""
    diam, dist = [], []
    for f in (fs.tris, fs.quads):
        if not len(f):
            continue
        xf = nodes[f]  # (n, k, 3)
        diam.append(np.max(np.linalg.norm(xf[:, :, None] - xf[:, None, :], axis=3), axis=(1, 2)))
        parts = [(0, 1, 2)] if f.shape[1] == 3 else [(0, 1, 2), (0, 2, 3)]
        dist.append(np.min([_triangle_distance(point, xf[:, list(t)]) for t in parts], axis=0))
    diam, dist = np.concatenate(diam), np.concatenate(dist)
    touched = dist <= a
    return float(diam[touched].max() if touched.any() else diam[np.argmin(dist)])


def _curvature(points: np.ndarray, x0: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, float]:
    """(curvature tensor (3, 3) in the tangent plane of ``n``, convex positive [1/m]; radius of
    the fitted patch [m]) of the surface nodes ``points`` nearest ``x0`` (module doc, step 3).
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


def _contact_of(sc: Scenario, body: str, contact: int | None) -> int:
    mine = [k for k, c in enumerate(sc.contacts) if body in (c.slave_body, c.master_body)]
    if not mine:
        raise InputError(
            f"body {body!r} is in no contact of the scenario; the region estimate needs its contact"
        )
    if contact is None:
        return mine[0]
    if contact not in mine:
        raise InputError(
            f"contact {contact}: body {body!r} is in contacts {mine}; expected one of them"
        )
    return contact


def _held(sc: Scenario, body: str) -> bool:
    """Whether ``body`` is on a joint to the ground that holds it (not a distance joint)."""
    from flexmvm.constraints.joints import JointType

    return any(
        j.body == body and j.body2 is None and j.type is not JointType.DISTANCE for j in sc.joints
    )


def _mass(sc: Scenario, cfg) -> float:
    """The body's mass [kg] (inf if held: module doc, step 5)."""
    from flexmvm.scenarios.setup import default_setup

    if _held(sc, cfg.name):
        return math.inf
    return float(default_setup().free_modes_source(cfg)[0].M_scalar.sum())


def _point_velocity(cfg, x: np.ndarray) -> np.ndarray:
    p = cfg.placement
    return np.asarray(p.velocity_mps, float) + np.cross(
        np.asarray(p.angular_velocity_radps, float), x - np.asarray(p.position_m, float)
    )


def _first_contact(x: np.ndarray, fs, px: np.ndarray, pfs) -> tuple[np.ndarray, np.ndarray]:
    """(expected first contact point (3,), the body's outward unit normal there (3,)), global,
    from the body's nodes ``x`` and surface ``fs`` and the partner's ``px``, ``pfs`` (module
    doc, step 2)."""
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
    n = normals[node]
    return px[pnode] - float((px[pnode] - x[node]) @ n) * n, n


def _equivalent_radius(
    body_points: np.ndarray, partner_points: np.ndarray, point: np.ndarray, n: np.ndarray, what: str
) -> tuple[float, tuple[float, float]]:
    """(R_e [m], principal radii (R', R'') [m]) of the two surfaces' summed curvature at
    ``point`` (module doc, step 3); InputError naming ``what`` without curvature."""
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


def _positive_or_none(name: str, value: float | None) -> float | None:
    if value is not None and not (math.isfinite(value) and value > 0):
        raise InputError(f"{name}: expected a number > 0, got {value!r}")
    return None if value is None else float(value)


def estimate_region(
    sc: Scenario,
    body: str,
    *,
    factor: float | None = None,
    radius_m: float | None = None,
    speed_mps: float | None = None,
    modes: int | None = None,
    contact: int | None = None,
) -> RegionEstimate:
    """The region body ``body`` of scenario ``sc`` needs for its contact (module doc).

    Args:
        sc, body: the scenario and the body to reduce (a mesh or rod body in a contact).
        factor: region radius per Hertz contact radius (> 0); None (default): the radius
            a + h, h the size of the contact facets the contact circle touches (module doc).
        radius_m: the equivalent curvature radius R_e [m] of the two surfaces, instead of the
            fit (needed for flat-on-flat, line or conforming contacts).
        speed_mps: the closing speed [m/s] instead of the placements' (needed when the
            bodies start at rest, e.g. a drop under gravity or a driven joint).
        modes: mode count of the costed model (default: the body's model's, else 30).
        contact: index of the contact in ``sc.contacts`` (default: the body's first).

    Raises:
        InputError: a non-positive factor, radius or speed; no contact of ``body``; surfaces
            without curvature or bodies without closing speed, each saying what to give.
    """
    from flexmvm.scenarios.setup import default_setup

    _positive_or_none("factor", factor)
    radius_m = _positive_or_none("radius_m", radius_m)
    speed_mps = _positive_or_none("speed_mps", speed_mps)
    if modes is not None and int(modes) < 0:
        raise InputError(f"modes: expected an integer >= 0, got {modes!r}")
    k = _contact_of(sc, body, contact)
    c, where = sc.contacts[k], f"contacts[{k}]"
    mine = c.slave_body == body
    surface, partner, other_surface = (
        (c.slave_surface, c.master_body, c.master_surface)
        if mine
        else (c.master_surface, c.slave_body, c.slave_surface)
    )
    cfg, pcfg = sc.body(body), sc.body(partner)
    setup = default_setup()
    fe, pfe = setup.free_modes_source(cfg)[0], setup.free_modes_source(pcfg)[0]
    try:
        fs, pfs = fe.mesh.facet_set(surface), pfe.mesh.facet_set(other_surface)
    except MeshError as exc:  # an unknown or empty surface, said in one line
        raise InputError(f"{where}: {exc}") from None
    x, A, r = _placed(cfg, fe.mesh.nodes)
    px = _placed(pcfg, pfe.mesh.nodes)[0]
    point, n = _first_contact(x, fs, px, pfs)
    if radius_m is None:
        R, principal = _equivalent_radius(
            x[fs.nodes],
            px[pfs.nodes],
            point,
            n,
            f"{where}: {body}.{surface} and {partner}.{other_surface}",
        )
    else:
        R, principal = radius_m, (radius_m, radius_m)
    v = speed_mps
    if v is None:
        v = float((_point_velocity(cfg, point) - _point_velocity(pcfg, point)) @ n)
        if not v > 0:
            raise InputError(
                f"{where}: {body} and {partner} do not close at the expected contact point "
                f"(normal relative speed {-v:.3g} m/s at their placements); give the closing "
                "speed (speed_mps, --speed)"
            )
    m_body, m_partner = _mass(sc, cfg), _mass(sc, pcfg)
    if math.isinf(m_body) and math.isinf(m_partner):
        raise InputError(
            f"{where}: {body} and {partner} are both held to the ground; the "
            "Hertz impact needs a moving mass"
        )
    ma, mb = (m_partner, m_body) if math.isfinite(m_partner) else (m_body, m_partner)
    mat, pmat = cfg.material_obj(), pcfg.material_obj()
    hertz = hertz_impact(R, v, effective_modulus(mat.E, mat.nu, pmat.E, pmat.nu), ma, mb)
    centre = np.round(A.T @ (point - r), 12) + 0.0  # placement round-off, no -0
    a = hertz.contact_radius_m
    h = _facet_size(fe.mesh.nodes, fs, centre, a)
    radius = a + h if factor is None else factor * a
    n_nodes = int(np.count_nonzero(np.linalg.norm(fe.mesh.nodes - centre, axis=1) <= radius))
    m = int(modes) if modes is not None else (cfg.model.modes or DEFAULT_MODES)
    cost = reduced_cost(body, fe.mesh.n_nodes, 3 * n_nodes + m, fe.K.nnz)
    return RegionEstimate(
        body,
        k,
        partner,
        surface,
        tuple(float(c) for c in centre),
        tuple(float(c) for c in point),
        tuple(float(c) for c in n),
        v,
        speed_mps is not None,
        R,
        tuple(float(r) for r in principal),
        radius_m is not None,
        hertz,
        None if factor is None else float(factor),
        h,
        radius,
        n_nodes,
        m,
        3 * n_nodes + m,
        cost,
    )
