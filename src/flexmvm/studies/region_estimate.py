"""The retained region a contact needs, estimated before any run: a ball about the expected
first contact point whose radius is the Hertz contact radius of the expected impact plus the
size of the body's contact facets there, and what that region costs on the body's mesh (DESIGN.md "Sizing a reduced region").

Steps (all at the scenario's initial placements, in SI units):

1. The contact: the body's first contact in the scenario (or ``contact``), its partner body
   and the two facet sets.
2. The expected first contact point: the partner's surface node of smallest normal gap to
   the body's surface (measured from its nearest body surface node along that node's outward
   normal, the area-weighted mean of its facets' normals), moved to the nearest point of the
   body's facets (a sphere's pole above a flat face gives the point below it, not the nearest
   face node; at an edge or a corner the point stays on the body, where a projection onto
   the averaged normal's plane left it); of tied nodes (flat on flat) the one nearest their
   middle. ``n`` is that outward normal.
3. The relative curvature: each surface's nodes nearest that point (NEIGHBOURS of them) are
   fitted by a height over the tangent plane, h = c0 + c1 u + c2 v - (k_uu u^2 + 2 k_uv u v
   + k_vv v^2) / 2 + higher terms (convex positive: the curvatures k); the two curvature
   tensors are added (Johnson, *Contact Mechanics*, 1985, sect. 4.1: A + B) and the sum's
   principal curvatures 1/R', 1/R'' give
   the equivalent radius R_e = sqrt(R' R'') (Johnson eq. 4.29, the circular contact of the
   same area). A sum without curvature (flat on flat, a cylinder's line contact, conforming
   surfaces) has no Hertz point contact: the estimate then needs ``radius_m``.
4. The closing speed: the normal component of the relative velocity of the two bodies'
   material points at the contact point (placements' velocity and angular velocity, a
   ``rigid_motion``, or the largest rate of a drive on the body's joint to the ground:
   studies/impact_estimate.py); none (bodies at rest or separating) needs ``speed_mps``.
5. Hertz (theory/hertz.py, Johnson eq. 11.24) with E* of the elastic bodies (a rigid body's
   modulus is infinite) and the bodies' masses (a held body does not recoil, a swung link
   recoils with J / l^2), in series with a thin body's point impedance, the infinite-plate
   8 sqrt(D rho h) of its thickness there (Zener 1941, theory/plate_impact.py;
   studies/impact_estimate.py), gives the contact radius a.
6. The region: the ball of radius ``a + h`` about the contact point (body-local coordinates),
   h the largest diameter of the body's contact facets that the circle of radius a about the
   point touches (``facet_size_m``; the linear sub-facets of a quadratic mesh, whose nodes all
   carry contact), or ``factor x a`` if a factor is given; its nodes, its DOF 3 x nodes +
   modes (the free-free modes below 3 / contact duration unless given:
   studies/mode_estimate.py) and its memory (assembly/cost.py).

The rule a + h. The ball must hold every node of the facets the contact circle touches (a node
outside the region moves only as the basis lets it: held stiff, the contact force comes out
high). Such a node is at most a (the circle) + h (its facet's diameter) from the point, so
a + h holds them all, on any mesh; a fixed multiple of a cannot (the former default 2 a
assumed elements of about a). On the sphere-on-beam showcase, MVM against full FE, a + h is
where the peak force no longer depends on the mode count, and a smaller ball leaves part of
the contact impulse on nodes held stiff (measurements: docs/notes/2026-11-27-select-on-meshes.md).

The estimate is a starting point: `flexmvm select` finds the smallest model that reaches an
accuracy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from flexmvm.assembly.cost import BodyCost, reduced_cost
from flexmvm.errors import InputError, MeshError
from flexmvm.scenarios import Scenario
from flexmvm.studies.contact_point import equivalent_radius, facet_size, first_contact
from flexmvm.studies.impact_estimate import (
    body_thickness,
    closing_speed,
    expected_impact,
    lateral_extent,
)
from flexmvm.studies.mode_estimate import estimated_modes
from flexmvm.theory.hertz import HertzImpact

__all__ = ["ContactGeometry", "RegionEstimate", "contact_geometry", "estimate_region"]


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
    #: the thin bodies whose point impedance the impact took (None: none), the first one's
    #: thickness through the contact point [m] and the impedance in series [N s/m]
    impedance_body: str | None = None
    thickness_m: float = math.nan
    impedance_nspm: float = math.inf
    #: where the mode count comes from: "given", "model" or "criterion" (f_max_hz [Hz])
    modes_from: str = "given"
    f_max_hz: float = math.nan
    modes_capped: bool = False

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
            "modes_from": self.modes_from,
            "modes_f_max_hz": None if math.isnan(self.f_max_hz) else self.f_max_hz,
            "modes_capped": self.modes_capped,
            "impedance_body": self.impedance_body,
            "thickness_m": None if math.isnan(self.thickness_m) else self.thickness_m,
            "impedance_nspm": None if math.isinf(self.impedance_nspm) else self.impedance_nspm,
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
        held = (
            ""
            if self.impedance_body is None
            else f" ({self.impedance_body} thin: point impedance 8 sqrt(D rho h) "
            f"{self.impedance_nspm:.4g} N s/m at thickness {self.thickness_m * mm:.4g} mm, "
            "Zener 1941)"
        )
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
                f"duration {h.duration_s * 1e6:.4g} us{held}"
            ),
            (
                f"region: ball of {self._rule()} = {self.radius_m * mm:.4g} mm: {self.nodes} "
                f"nodes, {self.dof} DOF with {self.modes} modes ({self._modes_line()})"
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

    def _modes_line(self) -> str:
        if self.modes_from != "criterion":
            return self.modes_from
        cap = ", capped" if self.modes_capped else ""
        return (
            f"the free-free modes below 3 / duration = {self.f_max_hz / 1e3:.4g} kHz{cap}: "
            "studies/mode_estimate.py"
        )

    def _rule(self) -> str:
        mm = 1e3
        if self.factor is not None:
            return f"{self.factor:g} a"
        return (
            f"a + h (h {self.facet_size_m * mm:.4g} mm: the largest contact facet within "
            f"a) = {self.radius_m / self.contact_radius_m:.3g} a"
        )


def placed_nodes(cfg, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(global node positions (n, 3), rotation A (3, 3), frame origin (3,)) at placement."""
    A = cfg.placement.rotation.matrix()
    r = np.asarray(cfg.placement.position_m, float)
    return r + nodes @ A.T, A, r


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


def _sides(c, body: str) -> tuple[str, str, str]:
    """(body's surface, partner body, partner's surface) of contact c, seen from ``body``."""
    if c.slave_body == body:
        return c.slave_surface, c.master_body, c.master_surface
    return c.master_surface, c.slave_body, c.slave_surface


def _facet_sets(cfg, pcfg, surface: str, other_surface: str, where: str):
    """(fe, facet set) of body cfg's ``surface`` and of the partner pcfg's ``other_surface``,
    from the setup cache's full-FE bodies; InputError for an unknown or empty surface."""
    from flexmvm.assembly.build_cache import default_setup

    setup = default_setup()
    fe, pfe = setup.free_modes_source(cfg)[0], setup.free_modes_source(pcfg)[0]
    try:
        fs, pfs = fe.mesh.facet_set(surface), pfe.mesh.facet_set(other_surface)
    except MeshError as exc:  # an unknown or empty surface, said in one line
        raise InputError(f"{where}: {exc}") from None
    return fe, fs, pfe, pfs


def _ball(nodes: np.ndarray, fs, centre: np.ndarray, a: float, factor: float | None):
    """(h, radius, nodes inside) of the region ball about ``centre`` (module doc, step 6):
    radius a + h, h the facet size there, or factor x a."""
    h = facet_size(nodes, fs, centre, a)
    radius = a + h if factor is None else factor * a
    return h, radius, int(np.count_nonzero(np.linalg.norm(nodes - centre, axis=1) <= radius))


def _positive_or_none(name: str, value: float | None) -> float | None:
    if value is not None and not (math.isfinite(value) and value > 0):
        raise InputError(f"{name}: expected a number > 0, got {value!r}")
    return None if value is None else float(value)


def _checked_options(factor, radius_m, speed_mps, modes) -> tuple[float | None, float | None]:
    """(radius_m, speed_mps) as floats or None, the four options of estimate_region checked:
    InputError for a non-positive factor, radius or speed, or a negative mode count."""
    _positive_or_none("factor", factor)
    radius_m = _positive_or_none("radius_m", radius_m)
    speed_mps = _positive_or_none("speed_mps", speed_mps)
    if modes is not None and int(modes) < 0:
        raise InputError(f"modes: expected an integer >= 0, got {modes!r}")
    return radius_m, speed_mps


def _floats(v) -> tuple:
    return tuple(float(c) for c in v)


def _curvature(radius_m, xs, xp, point, n, label) -> tuple[float, tuple[float, float]]:
    """(R_e, principal radii): the fit of the two surfaces (equivalent_radius), or radius_m
    when given."""
    if radius_m is None:
        return equivalent_radius(xs, xp, point, n, label)
    return radius_m, (radius_m, radius_m)


@dataclass(frozen=True)
class ContactGeometry:
    """A body's contact at the initial placements (module doc, steps 1 to 3): its index,
    partner and surface, the two bodies' configs, full-FE models and facet sets, their placed
    nodes (global), the expected first contact point and outward normal (global), and the
    equivalent curvature radius R_e and principal radii [m]."""

    contact: int
    partner: str
    surface: str
    cfg: Any
    pcfg: Any
    fe: Any
    fs: Any
    pfe: Any
    pfs: Any
    x: np.ndarray
    px: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    radius_m: float
    principal_radii_m: tuple[float, float]


def contact_geometry(
    sc: Scenario, body: str, contact: int | None, radius_m: float | None
) -> ContactGeometry:
    """The ContactGeometry of body ``body``'s contact ``contact`` (default: its first), R_e
    fitted or ``radius_m`` when given; InputError as estimate_region."""
    k = _contact_of(sc, body, contact)
    where = f"contacts[{k}]"
    surface, partner, other_surface = _sides(sc.contacts[k], body)
    cfg, pcfg = sc.body(body), sc.body(partner)
    fe, fs, pfe, pfs = _facet_sets(cfg, pcfg, surface, other_surface, where)
    x = placed_nodes(cfg, fe.mesh.nodes)[0]
    px = placed_nodes(pcfg, pfe.mesh.nodes)[0]
    point, n = first_contact(x, fs, px, pfs)
    label = f"{where}: {body}.{surface} and {partner}.{other_surface}"
    R, principal = _curvature(radius_m, x[fs.nodes], px[pfs.nodes], point, n, label)
    return ContactGeometry(
        k, partner, surface, cfg, pcfg, fe, fs, pfe, pfs, x, px, point, n, R, principal
    )


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
        speed_mps: the closing speed [m/s] instead of the initial motions' (needed when the
            bodies start at rest without a drive, e.g. a drop under gravity or a motor).
        modes: mode count of the costed model (default: the body's model's if its kind uses
            modes, else the free-free modes below 3 / contact duration:
            studies/mode_estimate.py).
        contact: index of the contact in ``sc.contacts`` (default: the body's first).

    Raises:
        InputError: a non-positive factor, radius or speed; no contact of ``body``; surfaces
            without curvature or bodies without closing speed, each saying what to give.
    """
    radius_m, speed_mps = _checked_options(factor, radius_m, speed_mps, modes)
    g = contact_geometry(sc, body, contact, radius_m)
    k, partner, surface, cfg, pcfg = g.contact, g.partner, g.surface, g.cfg, g.pcfg
    fe, fs, pfe, pfs, x, px = g.fe, g.fs, g.pfe, g.pfs, g.x, g.px
    point, n, R, principal = g.point, g.normal, g.radius_m, g.principal_radii_m
    A, r = placed_nodes(cfg, fe.mesh.nodes)[1:]
    where = f"contacts[{k}]"
    v = speed_mps
    who = f"{where}: {body} and {partner}"
    if v is None:
        v = closing_speed(sc, cfg, pcfg, fe.mesh, pfe.mesh, point, n, who)

    def geometry(name: str) -> tuple[float, float]:
        xs, inward, fset = (x, -n, fs) if name == body else (px, n, pfs)
        h = body_thickness(xs, point, inward, facet_size(xs, fset, point, 0.0))
        return h, lateral_extent(xs, n)

    contact_at = (point, n, fe.mesh, pfe.mesh)
    hertz, struck, t_m, Z = expected_impact(sc, cfg, pcfg, R, v, contact_at, geometry, who)
    centre = np.round(A.T @ (point - r), 12) + 0.0  # placement round-off, no -0
    a = hertz.contact_radius_m
    h, radius, n_nodes = _ball(fe.mesh.nodes, fs, centre, a, factor)
    m, source, f_max, capped = estimated_modes(cfg, modes, hertz.duration_s)
    cost = reduced_cost(body, fe.mesh.n_nodes, 3 * n_nodes + m, fe.K.nnz)
    at = (body, k, partner, surface, _floats(centre), _floats(point), _floats(n))
    impact = (v, speed_mps is not None, R, _floats(principal), radius_m is not None, hertz)
    size = (None if factor is None else float(factor), h, radius, n_nodes, m, 3 * n_nodes + m)
    return RegionEstimate(*at, *impact, *size, cost, struck, t_m, Z, source, f_max, capped)
