"""The expected impact of a contact, from the scenario alone (studies.region_estimate's steps 4 and 5):
the closing speed at the contact point from the bodies' initial motions, and the Hertz impact
of the two bodies with what each body brings to it (its modulus, its mass, its impedance).

- The closing speed: each body's velocity field at t = 0 from its placement (velocity and
  angular velocity of its frame, or its ``rigid_motion`` about a point or a joint's pivot);
  a body at rest there takes the largest rate over the run of a drive on its revolute joint
  to the ground (about the joint's point and axis: the speed a driven link strikes with, an
  upper bound), or the velocity of a prescribed joint's point.
- E*: 1/E* = (1 - nu^2)/E of the elastic bodies only: a rigid body (kind "rigid") does not
  deform, its E is infinite (Johnson, *Contact Mechanics*, 1985, eq. 4.22 with E2 -> inf).
- The masses: a free body recoils with its whole mass; a body that turns about one undriven
  revolute joint to the ground (a swung link) with J / l^2 (J its moment of inertia about
  the axis, l the lever of the contact normal); a body held otherwise (a support other than a
  spring bed that fixes its frame, a driven joint, another joint to the ground) does not
  recoil (infinite mass).
- The impedance: a thin body (a plate or a beam struck on its face: lateral extent >= THIN x
  its thickness h through the contact point) answers, in series with Hertz, with the
  infinite-plate point impedance 8 sqrt(D rho h) (theory/plate_impact.py, Zener 1941): its
  bending waves carry energy away and lower the force. On a 100 x 100 x 4 mm clamped
  aluminium plate struck by a rigid ball: 381 N without, 230.1 N with it, 230.0 N full FE;
  on sphere_beam's free 200 x 10 x 10 mm beam 495 N without, 394 N with it, 297 N full FE (a
  beam is more compliant than a plate of its height: an upper bound). A thick body (a block,
  a sphere, a rod struck at its end) takes none: Hertz's half-space.
"""

from __future__ import annotations

import math

import numpy as np

from flexmvm.errors import InputError
from flexmvm.scenarios import Scenario
from flexmvm.scenarios.joint_schema import JointConfig
from flexmvm.theory.hertz import HertzImpact
from flexmvm.theory.plate_impact import plate_impact, plate_impedance

__all__ = [
    "body_thickness",
    "closing_speed",
    "expected_impact",
    "held",
    "is_rigid",
    "lateral_extent",
]

#: Samples of a drive's rate over the run (its largest is the striking rate).
DRIVE_SAMPLES = 2001
#: A node at depth d below the contact point counts for the thickness if it is within
#: CONE x d (plus the facet size) of the normal line through the point.
CONE = 0.3
#: A body is thin at the contact (a plate or a beam struck on its face) if its lateral extent
#: is at least THIN x its thickness there: it then answers with its point impedance.
THIN = 3.0


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
    from flexmvm.studies.region_estimate import placed_nodes

    if j.point_m is not None:
        return cfg.placement.to_global(j.point_m)
    if j.ground_m is not None:
        return np.asarray(j.ground_m, float)
    return placed_nodes(cfg, mesh.nodes[mesh.node_set(j.node_set)])[0].mean(axis=0)


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
            axis = _unit(j.axis)
            rate = _drive_rate(j, sc.time.t_end_s)
            return np.zeros(3), rate * axis, _pivot(cfg, j, mesh)
        if j.velocity_mps is not None:
            return np.asarray(j.velocity_mps, float), np.zeros(3), np.zeros(3)
    for k, j in _motored(sc, cfg.name):
        axis = _unit(j.axis)
        pivot = _pivot(cfg, j, mesh)
        rate = _motor_rate(sc, k, _axis_inertia(cfg, pivot, axis))
        return np.zeros(3), rate * axis, pivot
    return v, w, np.asarray(p.position_m, float)


def _unit(axis: tuple[float, float, float] | None) -> np.ndarray:
    """The unit vector along a joint's axis (the callers take joints that have one)."""
    a = np.asarray(axis, float)
    return a / np.linalg.norm(a)


def _motored(sc: Scenario, body: str) -> list[tuple[int, JointConfig]]:
    """(index, joint) of the undriven revolute joints of ``body`` to the ground that a motor
    load turns."""
    from flexmvm.constraints.joints import JointType
    from flexmvm.scenarios.load_schema import LoadType

    motors = {ld.joint for ld in sc.loads if ld.type is LoadType.MOTOR}
    return [
        (k, j)
        for k, j in enumerate(sc.joints)
        if k in motors
        and j.body == body
        and j.body2 is None
        and j.type is JointType.REVOLUTE
        and j.drive is None
        and j.axis is not None
    ]


def _axis_inertia(cfg, pivot: np.ndarray, axis: np.ndarray) -> float:
    """Moment of inertia [kg m^2] of body cfg at its placement about the unit ``axis``
    through ``pivot``: sum of its nodes' lumped masses (rows of M) x their squared distance
    from the axis."""
    from flexmvm.assembly.build_cache import default_setup
    from flexmvm.studies.region_estimate import placed_nodes

    fe = default_setup().free_modes_source(cfg)[0]
    rel = placed_nodes(cfg, fe.mesh.nodes)[0] - pivot
    perp = rel - np.outer(rel @ axis, axis)
    m = np.asarray(fe.M_scalar.sum(axis=1)).ravel()
    return float(m @ np.einsum("ij,ij->i", perp, perp))


def _motor_rate(sc: Scenario, k: int, inertia: float) -> float:
    """The largest |rate| [rad/s] over the run of a body turned about joint k by its motor
    loads alone, from rest: |int_0^t torque dt| / J (the joint's friction-free swing)."""
    from flexmvm.scenarios.load_schema import LoadType

    t = np.linspace(0.0, sc.time.t_end_s, DRIVE_SAMPLES)
    tau = np.zeros_like(t)
    for ld in sc.loads:
        if ld.type is LoadType.MOTOR and ld.joint == k:
            tau = tau + np.array([float(ld.history().at(float(s))[0]) for s in t])
    impulse = np.concatenate([[0.0], np.cumsum(0.5 * (tau[1:] + tau[:-1]) * np.diff(t))])
    return float(np.max(np.abs(impulse))) / inertia


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


def lateral_extent(x: np.ndarray, normal: np.ndarray) -> float:
    """The largest extent [m] of the nodes ``x`` across the unit ``normal`` (the larger side
    of their bounding box in two axes of the tangent plane)."""
    t1 = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(normal, t1)
    return float(max(np.ptp(x @ t1), np.ptp(x @ t2)))


def _mass(sc: Scenario, cfg, mesh, point: np.ndarray, n: np.ndarray) -> float:
    """The body's mass [kg] at ``point`` along ``n`` (module doc): its whole mass if free;
    J / ((point - p) x n . a)^2 if it turns about one undriven revolute joint to the ground
    (pivot p, axis a, J its moment of inertia about it); inf if held otherwise."""
    from flexmvm.assembly.build_cache import default_setup

    ground = [j for j in sc.joints if j.body == cfg.name and j.body2 is None]
    swing = [j for _, j in _motored(sc, cfg.name)] or [
        j for j in ground if j.type.value == "revolute" and j.drive is None and j.axis
    ]
    supported = any(s.body == cfg.name for s in sc.supports)
    if len(ground) == 1 and swing and not supported:
        j = swing[0]
        axis = _unit(j.axis)
        pivot = _pivot(cfg, j, mesh)
        lever = float(np.cross(point - pivot, n) @ axis)
        return math.inf if lever == 0.0 else _axis_inertia(cfg, pivot, axis) / lever**2
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


def expected_impact(sc, cfg, pcfg, R: float, v: float, contact, geometry, where: str):
    """(the Hertz impact, the names of the thin bodies whose impedance it took or None, the
    first one's thickness [m], the impedance in series [N s/m]) of bodies cfg and pcfg at
    equivalent radius R [m] and closing speed v [m/s] (module doc); ``contact`` = (point, n,
    the two bodies' meshes), ``geometry(name)`` = (thickness through the contact point,
    lateral extent) [m]. InputError when both are held to the ground."""
    point, n, mesh, pmesh = contact
    m_body, m_partner = _mass(sc, cfg, mesh, point, n), _mass(sc, pcfg, pmesh, point, n)
    if math.isinf(m_body) and math.isinf(m_partner):
        raise InputError(
            f"{where} are both held to the ground; the Hertz impact needs a moving mass"
        )
    ma, mb = (m_partner, m_body) if math.isfinite(m_partner) else (m_body, m_partner)
    E = e_star(cfg, pcfg, where)
    thin: list[str] = []  # the bodies thin enough for the plate model
    first_h, compliance = math.nan, 0.0
    for c in (cfg, pcfg):
        if is_rigid(c):
            continue
        h, extent = geometry(c.name)
        if extent < THIN * h:
            continue
        mat = c.material_obj()
        compliance += 1.0 / plate_impedance(mat.E, mat.nu, mat.rho, h)
        first_h = h if not thin else first_h
        thin.append(c.name)
    Z = math.inf if compliance == 0.0 else 1.0 / compliance
    return plate_impact(R, v, E, ma, mb, Z), ", ".join(thin) or None, first_h, Z


def _plain(R: float, v: float, E: float, ma: float, mb: float) -> HertzImpact:
    from flexmvm.theory.hertz import hertz_impact

    return hertz_impact(R, v, E, ma, mb)
