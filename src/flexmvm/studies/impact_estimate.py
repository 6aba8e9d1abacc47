"""The expected impact of a contact, from the scenario alone (studies.region's steps 4 and 5):
the closing speed at the contact point from the bodies' initial motions, and the Hertz impact
of the two bodies with what each body brings to it (its modulus, its mass, its impedance).

- The closing speed: each body's velocity field at t = 0 from its placement (velocity and
  angular velocity of its frame, or its ``rigid_motion`` about a point or a joint's pivot);
  a body at rest there takes the largest rate over the run of a drive on its revolute joint
  to the ground (about the joint's point and axis: the speed a driven link strikes with, an
  upper bound), or the velocity of a prescribed joint's point.
- E*: 1/E* = (1 - nu^2)/E of the elastic bodies only: a rigid body (kind "rigid") does not
  deform, its E is infinite (Johnson, *Contact Mechanics*, 1985, eq. 4.22 with E2 -> inf).
- The masses: a body held to the ground (a support other than a spring bed that fixes its
  frame, or a joint to the ground other than a distance joint) does not recoil (infinite
  mass); it takes the struck point's impedance instead, the infinite-plate value
  8 sqrt(D rho h) of its thickness h through the contact point (theory/plate_impact.py,
  Zener 1941): a clamped plate is not rigid, its bending waves carry energy away and lower the
  force (4 mm clamped plate: 381 N rigid, 233 N Zener, 230 N full FE). A thick body's Z (~h^2)
  is large and leaves Hertz's rigid target. A free body recoils with its whole mass (its
  impedance is left out: the former estimate, measured on the free sphere-on-beam case).
"""

from __future__ import annotations

import math

import numpy as np

from flexmvm.errors import InputError
from flexmvm.scenarios import Scenario
from flexmvm.theory.hertz import HertzImpact
from flexmvm.theory.plate_impact import plate_impact, plate_impedance

__all__ = ["body_thickness", "closing_speed", "expected_impact", "held", "is_rigid"]

#: Samples of a drive's rate over the run (its largest is the striking rate).
DRIVE_SAMPLES = 2001
#: A node at depth d below the contact point counts for the thickness if it is within
#: CONE x d (plus the facet size) of the normal line through the point.
CONE = 0.3


def is_rigid(cfg) -> bool:
    """Whether body ``cfg`` is modelled rigid (infinite modulus in E*)."""
    return cfg.model.kind.value == "rigid"


def held(sc: Scenario, body: str) -> bool:
    """Whether ``body`` is held to the ground (module doc): a support other than a spring bed
    with its frame fixed, or a joint to the ground other than a distance joint."""
    from flexmvm.constraints.joints import JointType
    from flexmvm.scenarios.support_schema import SupportType

    if any(
        s.body == body and s.type is not SupportType.SPRING_BED and s.ground_frame
        for s in sc.supports
    ):
        return True
    return any(
        j.body == body and j.body2 is None and j.type is not JointType.DISTANCE for j in sc.joints
    )


def _pivot(cfg, j, mesh) -> np.ndarray:
    """Global position [m] at t = 0 of joint ``j``'s point on body ``cfg`` (its ``point_m``,
    its ``ground_m``, or the centroid of its node set)."""
    from flexmvm.studies.region import _placed

    if j.point_m is not None:
        return cfg.placement.to_global(j.point_m)
    if j.ground_m is not None:
        return np.asarray(j.ground_m, float)
    return _placed(cfg, mesh.nodes[mesh.node_set(j.node_set)])[0].mean(axis=0)


def _drive_rate(j, t_end: float) -> float:
    """The largest |rate| [rad/s] of joint j's drive over [0, t_end]."""
    t = np.linspace(0.0, t_end, DRIVE_SAMPLES)
    if j.drive.angular_velocity_radps is not None:
        f = j.drive.angular_velocity_radps.function()
        return float(max(abs(f.value(float(s))) for s in t))
    angle = np.array([j.drive.angle_rad.function().value(float(s)) for s in t])
    return float(np.max(np.abs(np.gradient(angle, t))))


def _motion(sc: Scenario, cfg, mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(v_P, w, P): body cfg's rigid velocity field at t = 0, v(x) = v_P + w x (x - P)
    (module doc)."""
    p = cfg.placement
    if p.rigid_motion is not None:
        m = p.rigid_motion
        about = np.asarray(p.position_m, float)
        if m.about_m is not None:
            about = np.asarray(m.about_m, float)
        elif m.about_joint is not None:
            j = next(j for j in sc.joints if j.name == m.about_joint)
            about = _pivot(cfg, j, mesh)
        v, w = np.asarray(m.velocity_mps, float), np.asarray(m.angular_velocity_radps, float)
        return v, w, about
    v, w = np.asarray(p.velocity_mps, float), np.asarray(p.angular_velocity_radps, float)
    if np.any(v) or np.any(w):
        return v, w, np.asarray(p.position_m, float)
    for j in sc.joints:
        if j.body != cfg.name or j.body2 is not None:
            continue
        if j.drive is not None and j.axis is not None:
            axis = np.asarray(j.axis, float) / np.linalg.norm(j.axis)
            rate = _drive_rate(j, sc.time.t_end_s)
            return np.zeros(3), rate * axis, _pivot(cfg, j, mesh)
        if j.velocity_mps is not None:
            return np.asarray(j.velocity_mps, float), np.zeros(3), np.zeros(3)
    return v, w, np.asarray(p.position_m, float)


def closing_speed(sc, cfg, pcfg, mesh, pmesh, point, n, where: str) -> float:
    """Normal closing speed [m/s] of bodies cfg (mesh ``mesh``) and pcfg at ``point``
    (normal n out of cfg's surface), from their initial motions (module doc); InputError
    when they do not close there."""
    v = 0.0
    for c, m, sign in ((cfg, mesh, 1.0), (pcfg, pmesh, -1.0)):
        vp, w, about = _motion(sc, c, m)
        v += sign * float((vp + np.cross(w, point - about)) @ n)
    if not v > 0:
        raise InputError(
            f"{where} do not close at the expected contact point "
            f"(normal relative speed {-v:.3g} m/s at their placements and drives); give the "
            "closing speed (speed_mps, --speed)"
        )
    return v


def body_thickness(x: np.ndarray, point: np.ndarray, inward: np.ndarray, h: float) -> float:
    """Thickness [m] of a body (global node positions ``x``) through ``point`` along the unit
    ``inward`` normal: the largest depth (x - point) . inward of the nodes within CONE x depth
    + h of that line (h the facet size there: the nodes of a mesh coarse away from the point)."""
    rel = x - point
    depth = rel @ inward
    lateral = np.linalg.norm(rel - depth[:, None] * inward, axis=1)
    inside = (depth > 0) & (lateral <= CONE * depth + h)
    return float(depth[inside].max()) if inside.any() else h


def _mass(sc: Scenario, cfg) -> float:
    """The body's mass [kg], inf if held (module doc)."""
    from flexmvm.scenarios.setup import default_setup

    if held(sc, cfg.name):
        return math.inf
    return float(default_setup().free_modes_source(cfg)[0].M_scalar.sum())


def e_star(cfg, pcfg, where: str) -> float:
    """E* [Pa] of bodies cfg and pcfg, a rigid one's modulus infinite (module doc)."""
    inv = sum(
        (1.0 - c.material_obj().nu ** 2) / c.material_obj().E
        for c in (cfg, pcfg)
        if not is_rigid(c)
    )
    if inv == 0.0:
        raise InputError(f"{where} are both rigid; the Hertz impact needs an elastic body")
    return 1.0 / inv


def expected_impact(sc, cfg, pcfg, R: float, v: float, thickness, where: str):
    """(the Hertz impact, the struck body's name or None, its thickness [m], its impedance
    [N s/m]) of bodies cfg and pcfg at equivalent radius R [m] and closing speed v [m/s]
    (module doc); ``thickness(name)`` gives a held body's thickness through the contact
    point. InputError when both are held to the ground."""
    m_body, m_partner = _mass(sc, cfg), _mass(sc, pcfg)
    if math.isinf(m_body) and math.isinf(m_partner):
        raise InputError(
            f"{where} are both held to the ground; the Hertz impact needs a moving mass"
        )
    (ma, mb), target = (
        ((m_partner, m_body), cfg) if math.isfinite(m_partner) else ((m_body, m_partner), pcfg)
    )
    E = e_star(cfg, pcfg, where)
    if math.isfinite(mb) or is_rigid(target):
        return _plain(R, v, E, ma, mb), None, math.nan, math.inf
    h = thickness(target.name)
    mat = target.material_obj()
    Z = plate_impedance(mat.E, mat.nu, mat.rho, h)
    return plate_impact(R, v, E, ma, mb, Z), target.name, h, Z


def _plain(R: float, v: float, E: float, ma: float, mb: float) -> HertzImpact:
    from flexmvm.theory.hertz import hertz_impact

    return hertz_impact(R, v, E, ma, mb)
