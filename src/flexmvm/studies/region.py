"""The retained region a contact needs, estimated before any run: a ball about the expected
first contact point whose radius is a multiple of the Hertz contact radius of the expected
impact, and what that region costs on the body's mesh (DESIGN.md "Sizing a reduced region").

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
6. The region: the ball of radius ``factor x a`` about the contact point (body-local
   coordinates), its nodes, its DOF 3 x nodes + modes and its memory (scenarios/cost.py).

The factor. The ball must hold every node of the facets the contact circle touches: they
reach about one element beyond a, and a mesh sized for the contact has elements of about a
(docs/your_own_part.md), hence DEFAULT_FACTOR = 2. Measured on the sphere-on-beam showcase over
1 ms, force NCC of MVM against full FE by ball radius (docs/notes/2026-11-27-select-on-meshes.md;
a = 0.379 mm here): 0.66 a (2 nodes) has a third of the contact outside its region and stays
at NCC 0.977 / 0.966 with 30 / 60 modes; from 1.06 a (4 nodes) up, the radius no longer
matters (0.9969-0.9988 at 30 modes for 1.06 to 4.2 a; 0.999998 and 0.999996 at 60 modes for
1.06 a and 3.2 a): the modes do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError, MeshError
from flexmvm.scenarios import Scenario
from flexmvm.scenarios.cost import BodyCost, reduced_cost
from flexmvm.theory.hertz import HertzImpact, effective_modulus, hertz_impact

__all__ = ["DEFAULT_FACTOR", "RegionEstimate", "estimate_region"]

#: Region radius per Hertz contact radius (module doc: measured on the sphere-on-beam case).
DEFAULT_FACTOR = 2.0
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
    factor: float
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
        return {"body": self.body, "contact": self.contact, "partner": self.partner,
                "surface": self.surface, "centre_m": list(self.centre_m),
                "contact_point_m": list(self.contact_point_m), "normal": list(self.normal),
                "closing_speed_mps": self.closing_speed_mps, "speed_given": self.speed_given,
                "curvature_radius_m": self.curvature_radius_m,
                "principal_radii_m": list(self.principal_radii_m),
                "radius_given": self.radius_given, "e_star_pa": h.e_star_pa,
                "m_star_kg": h.m_star_kg, "hertz_force_max_n": h.force_max_n,
                "hertz_duration_s": h.duration_s, "contact_radius_m": h.contact_radius_m,
                "factor": self.factor, "radius_m": self.radius_m, "nodes": self.nodes,
                "modes": self.modes, "dof": self.dof,
                "dof_total": self.cost.dof, "memory_MB": self.cost.bytes / 1e6,
                "full_fe_dof": self.cost.full_dof, "full_fe_memory_MB": self.cost.full_bytes / 1e6,
                "costs_more_than_full_fe": self.cost.bytes > self.cost.full_bytes,
                "region": self.region()}

    def lines(self) -> list[str]:
        """The console lines of the estimate."""
        h, mm = self.hertz, 1e3
        c = ", ".join(f"{v * mm:.4g}" for v in self.centre_m)
        rs = ("given" if self.radius_given else
              "fitted, principal " + ", ".join(f"{r * mm:.4g}" for r in self.principal_radii_m)
              + " mm")
        given = " (given)" if self.speed_given else ""
        lines = [
            (f"contacts[{self.contact}]: {self.body}.{self.surface} against {self.partner}; "
             f"expected first contact at ({c}) mm in {self.body}'s coordinates"),
            (f"Hertz impact: closing speed {self.closing_speed_mps:.4g} m/s{given}, curvature "
             f"radius {self.curvature_radius_m * mm:.4g} mm ({rs}), E* "
             f"{h.e_star_pa / 1e9:.4g} GPa, m* {h.m_star_kg:.4g} kg: peak "
             f"{h.force_max_n:.4g} N, contact radius a {h.contact_radius_m * mm:.4g} mm, "
             f"duration {h.duration_s * 1e6:.4g} us"),
            (f"region: ball of {self.factor:g} a = {self.radius_m * mm:.4g} mm: {self.nodes} "
             f"nodes, {self.dof} DOF with {self.modes} modes"),
            self.cost.line(),
        ]
        if self.nodes == 0:
            lines.append("the ball holds no node of the mesh: its elements are coarser than "
                         "the contact (elements of about a resolve the force); refine the mesh "
                         "about the contact point or raise the factor")
        if self.cost.bytes > self.cost.full_bytes:
            lines.append("this region costs more than full FE: a smaller factor (or a coarser "
                         "mesh about the contact), or kind 'full'")
        return lines


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
        raise InputError(f"{len(near)} surface nodes about the contact point; the curvature "
                         "fit needs at least 6: give radius_m")
    t1 = _unit(np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0]))
    t2 = np.cross(n, t1)
    rel = near - x0
    rho = float(np.max(np.hypot(rel @ t1, rel @ t2)))
    u, v, h = rel @ t1 / rho, rel @ t2 / rho, rel @ n / rho   # scaled to the patch
    degree = 4 if len(near) >= 15 else 2
    terms = [u**i * v**(k - i) for k in range(degree + 1) for i in range(k, -1, -1)]
    c = np.linalg.lstsq(np.column_stack(terms), h, rcond=None)[0]
    # c[3], c[4], c[5]: the u^2, u v, v^2 coefficients (of the scaled height)
    k2 = -np.array([[2 * c[3], c[4]], [c[4], 2 * c[5]]]) / rho
    T = np.column_stack([t1, t2])
    return T @ k2 @ T.T, rho


def _contact_of(sc: Scenario, body: str, contact: int | None) -> int:
    mine = [k for k, c in enumerate(sc.contacts) if body in (c.slave_body, c.master_body)]
    if not mine:
        raise InputError(f"body {body!r} is in no contact of the scenario; the region estimate "
                         "needs its contact")
    if contact is None:
        return mine[0]
    if contact not in mine:
        raise InputError(f"contact {contact}: body {body!r} is in contacts {mine}; expected one "
                         "of them")
    return contact


def _held(sc: Scenario, body: str) -> bool:
    """Whether ``body`` is on a joint to the ground that holds it (not a distance joint)."""
    from flexmvm.constraints.joints import JointType

    return any(j.body == body and j.body2 is None and j.type is not JointType.DISTANCE
               for j in sc.joints)


def _mass(sc: Scenario, cfg) -> float:
    """The body's mass [kg] (inf if held: module doc, step 5)."""
    from flexmvm.scenarios.setup import default_setup

    if _held(sc, cfg.name):
        return math.inf
    return float(default_setup().free_modes_source(cfg)[0].M_scalar.sum())


def _point_velocity(cfg, x: np.ndarray) -> np.ndarray:
    p = cfg.placement
    return np.asarray(p.velocity_mps, float) + np.cross(
        np.asarray(p.angular_velocity_radps, float), x - np.asarray(p.position_m, float))


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


def _equivalent_radius(body_points: np.ndarray, partner_points: np.ndarray,
                       point: np.ndarray, n: np.ndarray, what: str
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
            "contact); give the equivalent curvature radius (radius_m, --radius-mm)")
    principal = (1.0 / kappa[1], 1.0 / kappa[0])
    return math.sqrt(principal[0] * principal[1]), principal


def _positive_or_none(name: str, value: float | None) -> float | None:
    if value is not None and not (math.isfinite(value) and value > 0):
        raise InputError(f"{name}: expected a number > 0, got {value!r}")
    return None if value is None else float(value)


def estimate_region(sc: Scenario, body: str, *, factor: float = DEFAULT_FACTOR,
                    radius_m: float | None = None, speed_mps: float | None = None,
                    modes: int | None = None, contact: int | None = None) -> RegionEstimate:
    """The region body ``body`` of scenario ``sc`` needs for its contact (module doc).

    Args:
        sc, body: the scenario and the body to reduce (a mesh or rod body in a contact).
        factor: region radius per Hertz contact radius (> 0; DEFAULT_FACTOR).
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
    surface, partner, other_surface = ((c.slave_surface, c.master_body, c.master_surface) if mine
                                       else (c.master_surface, c.slave_body, c.slave_surface))
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
        R, principal = _equivalent_radius(x[fs.nodes], px[pfs.nodes], point, n,
                                          f"{where}: {body}.{surface} and {partner}."
                                          f"{other_surface}")
    else:
        R, principal = radius_m, (radius_m, radius_m)
    v = speed_mps
    if v is None:
        v = float((_point_velocity(cfg, point) - _point_velocity(pcfg, point)) @ n)
        if not v > 0:
            raise InputError(
                f"{where}: {body} and {partner} do not close at the expected contact point "
                f"(normal relative speed {-v:.3g} m/s at their placements); give the closing "
                "speed (speed_mps, --speed)")
    m_body, m_partner = _mass(sc, cfg), _mass(sc, pcfg)
    if math.isinf(m_body) and math.isinf(m_partner):
        raise InputError(f"{where}: {body} and {partner} are both held to the ground; the "
                         "Hertz impact needs a moving mass")
    ma, mb = (m_partner, m_body) if math.isfinite(m_partner) else (m_body, m_partner)
    mat, pmat = cfg.material_obj(), pcfg.material_obj()
    hertz = hertz_impact(R, v, effective_modulus(mat.E, mat.nu, pmat.E, pmat.nu), ma, mb)
    centre = np.round(A.T @ (point - r), 12) + 0.0   # placement round-off, no -0
    radius = factor * hertz.contact_radius_m
    n_nodes = int(np.count_nonzero(np.linalg.norm(fe.mesh.nodes - centre, axis=1) <= radius))
    m = int(modes) if modes is not None else (cfg.model.modes or DEFAULT_MODES)
    cost = reduced_cost(body, fe.mesh.n_nodes, 3 * n_nodes + m, fe.K.nnz)
    return RegionEstimate(
        body, k, partner, surface, tuple(float(a) for a in centre),
        tuple(float(a) for a in point), tuple(float(a) for a in n), v, speed_mps is not None,
        R, tuple(float(a) for a in principal), radius_m is not None, hertz, float(factor),
        radius, n_nodes, m, 3 * n_nodes + m, cost)
