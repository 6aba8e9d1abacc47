"""The Timoshenko beam + Hertz solution of a sphere-on-beam scenario, in the history format
of a simulation run (flexmvm.theory.beam_impact for the model).

The mapping from a scenario (its only contact, or the one of ``body``):

- the two bodies are mesh bodies: the *sphere* one whose skin nodes lie on a sphere (radius
  spread below 1e-3 of R about the least-squares centre), the *beam* the other, a
  rectangular prism (skin volume = bounding-box volume within 1e-6) at least 5 times longer
  than its section is wide, neither rigid; its length along its longest local axis;
- the impact is the sphere's velocity relative to the beam, which must be at rest (no
  angular velocity either) and be normal to one of the beam's long faces (within 1e-6 rad):
  the bending plane is that face's normal and the axis, the depth h the beam's extent along
  the normal, the width b the other one;
- the contact point x_c is the sphere centre's position along the axis; it must lie over
  the face;
- the sphere's mass is rho times the volume inside its skin (what a rigid mesh body weighs,
  slightly below 4/3 pi R^3 for a faceted sphere); E* = E_beam / (1 - nu_beam^2) for a rigid
  sphere, theory.hertz.effective_modulus of both materials otherwise;
- the first touch is at t0 = g0 / v, g0 the distance from the face to the nearest skin node
  of the sphere (a faceted sphere first touches at a vertex); before it nothing moves;
- a probe on the beam reports the global x component of w_t n - eta psi_t e (n the impact
  normal, e the axis, eta the probe's offset from the beam's mid-plane along n: plane
  sections, Timoshenko kinematics); a probe on the sphere its velocity's x component.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexmvm.errors import InputError
from flexmvm.theory.beam_impact import SphereOnBeam
from flexmvm.theory.hertz import effective_modulus
from flexmvm.theory.timoshenko import TimoshenkoBeam

LAW = "timoshenko-hertz"
_SPHERE_TOL = 1e-3  # radius spread of a sphere's skin nodes, relative
_PRISM_TOL = 1e-6  # skin volume against the bounding box's, relative
_ANGLE_TOL = 1e-6  # impact direction against the face normal [rad]
_SLENDER = 5.0  # length / largest section side of a beam


@dataclass(frozen=True)
class SphereBeamCase:
    """A scenario as the beam theory sees it (module doc): names, the impact, the first
    touch t0 [s], and per probe (name, 'beam' | 'sphere', x [m] along the axis, eta [m],
    global x component of n and of e)."""

    sphere: str
    beam: str
    impact: SphereOnBeam
    t_first_touch_s: float
    probes: tuple[tuple[str, str, float, float, float, float], ...]


def _skin_volume(mesh) -> float:
    """Volume inside the outward-oriented skin [m^3]: 1/3 sum over facets of x . n A
    (divergence theorem; exact for flat facets)."""
    skin = mesh.facet_set("surface")
    tris = [skin.tris] + [skin.quads[:, [0, 1, 2]], skin.quads[:, [0, 2, 3]]]
    x = mesh.nodes
    vol = 0.0
    for t in tris:
        a, b, c = x[t[:, 0]], x[t[:, 1]], x[t[:, 2]]
        vol += float(np.sum(np.einsum("ij,ij->i", a, np.cross(b, c)))) / 6.0
    return vol


def _sphere_of(mesh) -> tuple[np.ndarray, float] | None:
    """(centre, R) of a mesh whose skin nodes lie on a sphere, else None. The centre is the
    least-squares fit of |x|^2 = 2 c . x + (R^2 - |c|^2) (linear in c)."""
    pts = mesh.nodes[mesh.node_set("surface")]
    a = np.hstack([2.0 * pts, np.ones((len(pts), 1))])
    centre = np.linalg.lstsq(a, np.sum(pts**2, axis=1), rcond=None)[0][:3]
    r = np.linalg.norm(pts - centre, axis=1)
    return (centre, float(r.max())) if r.min() >= (1.0 - _SPHERE_TOL) * r.max() else None


@functools.lru_cache(maxsize=4)
def _read(path: str, mtime_ns: int, size: int):
    from flexmvm.mesh.io import read_mesh

    return read_mesh(path)


def _mesh(path: Path):
    """read_mesh, kept for the file's unchanged (mtime, size): a beam mesh takes seconds."""
    st = Path(path).stat()
    return _read(str(path), st.st_mtime_ns, st.st_size)


def _contact(sc, body: str | None):
    if body is None:
        if len(sc.contacts) != 1:
            raise InputError(f"theory: needs exactly one contact, got {len(sc.contacts)}")
        return sc.contacts[0]
    for c in sc.contacts:
        if body in (c.slave_body, c.master_body):
            return c
    raise InputError(f"theory: body {body!r} is in no contact of the scenario")


def _bodies(sc, c):
    """(sphere cfg, its mesh, centre, R, beam cfg, its mesh) of contact c, or InputError."""
    cfgs = [sc.body(c.slave_body), sc.body(c.master_body)]
    if any(cfg.mesh_file is None for cfg in cfgs):
        raise InputError(
            "theory: a sphere-on-beam impact needs two mesh_file bodies, got "
            + ", ".join(f"{cfg.name!r}" for cfg in cfgs if cfg.mesh_file is None)
            + " without one"
        )
    meshes = [_mesh(cfg.mesh_file) for cfg in cfgs]
    spheres = [_sphere_of(m) for m in meshes]
    if sum(s is not None for s in spheres) != 1:
        raise InputError(
            f"theory: expected one sphere among {cfgs[0].name!r} and "
            f"{cfgs[1].name!r}, got {sum(s is not None for s in spheres)}"
        )
    i = 0 if spheres[0] is not None else 1
    centre, radius = spheres[i]
    return cfgs[i], meshes[i], centre, radius, cfgs[1 - i], meshes[1 - i]


def _beam_frame(cfg, mesh):
    """(lo, hi, axis index) of a prismatic beam's local bounding box, or InputError."""
    lo, hi = mesh.nodes.min(axis=0), mesh.nodes.max(axis=0)
    ext = hi - lo
    if abs(_skin_volume(mesh) / float(np.prod(ext)) - 1.0) > _PRISM_TOL:
        raise InputError(
            f"theory: body {cfg.name!r} is not a rectangular prism (its volume "
            "differs from its bounding box's)"
        )
    axis = int(np.argmax(ext))
    if ext[axis] < _SLENDER * np.delete(ext, axis).max():
        ratio = ext[axis] / np.delete(ext, axis).max()
        raise InputError(
            f"theory: body {cfg.name!r} is not a beam: its length is {ratio:.3g} "
            f"times its largest section side, beam theory needs >= {_SLENDER:g}"
        )
    return lo, hi, axis


def _impact_direction(s_cfg, rb: np.ndarray, axis: int) -> tuple[float, int, float]:
    """(speed [m/s], index of the beam-frame axis it is along, its sign) of the sphere s_cfg
    at t = 0 (beam rotation rb); InputError unless it moves normal to a long face (not along
    the beam axis ``axis``)."""
    v_loc = rb.T @ np.asarray(s_cfg.placement.velocity_mps, dtype=float)
    speed = float(np.linalg.norm(v_loc))
    if speed == 0.0:
        raise InputError(f"theory: the sphere {s_cfg.name!r} does not move")
    normal_idx = int(np.argmax(np.abs(v_loc)))
    if normal_idx == axis or abs(v_loc[normal_idx]) < math.cos(_ANGLE_TOL) * speed:
        raise InputError(
            f"theory: the sphere's velocity (beam frame {v_loc.tolist()} m/s) is "
            "not normal to a long face of the beam"
        )
    return speed, normal_idx, 1.0 if v_loc[normal_idx] > 0 else -1.0


def _gap_and_contact_x(s_cfg, s_mesh, s_centre, radius, pb, lo, hi, axis, n_loc):
    """(gap [m] from the sphere's skin to the struck face along n_loc (beam frame, the
    sphere's direction), contact position along the beam axis [m] from its end lo); the beam
    placed at pb, box (lo, hi). InputError unless the sphere is in front of the face."""
    normal_idx = int(np.argmax(np.abs(n_loc)))
    sign = float(n_loc[normal_idx])
    width_idx = 3 - axis - normal_idx
    rb = pb.rotation.matrix()
    c_loc = rb.T @ (s_cfg.placement.to_global(s_centre) - np.asarray(pb.position_m))
    face = lo[normal_idx] if sign > 0 else hi[normal_idx]
    skin = s_mesh.nodes[s_mesh.node_set("surface")]
    s_rot = s_cfg.placement.rotation.matrix()
    skin_loc = (
        rb.T
        @ (
            np.asarray(s_cfg.placement.position_m)[:, None]
            + s_rot @ skin.T
            - np.asarray(pb.position_m)[:, None]
        )
    ).T
    gap = float(np.min(sign * (face - skin_loc[:, normal_idx])))
    x_c = float(c_loc[axis] - lo[axis])
    over = lo[width_idx] < c_loc[width_idx] < hi[width_idx]
    if gap < -1e-9 * radius or not (0.0 < x_c < hi[axis] - lo[axis]) or not over:
        raise InputError(
            f"theory: the sphere {s_cfg.name!r} is not in front of the beam's "
            f"face (gap {gap:.3g} m, contact at {x_c:.4g} m along the axis)"
        )
    return gap, x_c


def _case_probes(sc, s_cfg, s_mesh, b_cfg, b_mesh, lo, hi, axis, n_loc, n_glob, e_glob):
    """SphereBeamCase.probes of the scenario's probes: (name, "sphere" or "beam", position
    along the beam [m] from its end lo, offset from the mid-plane along n_loc [m], global x
    components of the impact direction n_glob and of the beam axis e_glob); InputError for a
    probe on another body."""
    mid = 0.5 * (lo + hi)
    length = float(hi[axis] - lo[axis])
    probes = []
    for p in sc.probes:
        if p.body not in (s_cfg.name, b_cfg.name):
            raise InputError(
                f"theory: probe {p.name!r} is on {p.body!r}, neither the sphere nor the beam"
            )
        mesh = b_mesh if p.body == b_cfg.name else s_mesh
        loc = (
            np.asarray(p.point_m)
            if p.point_m is not None
            else mesh.nodes[mesh.node_set(p.node_set)].mean(axis=0)
        )
        if p.body == s_cfg.name:
            probes.append((p.name, "sphere", 0.0, 0.0, float(n_glob[0]), 0.0))
        else:
            probes.append(
                (
                    p.name,
                    "beam",
                    float(np.clip(loc[axis] - lo[axis], 0.0, length)),
                    float((loc - mid) @ n_loc),
                    float(n_glob[0]),
                    float(e_glob[0]),
                )
            )
    return tuple(probes)


def sphere_beam_case(
    sc, body: str | None = None, *, n_modes: int = 40, n_elements: int = 200
) -> SphereBeamCase:
    """The beam-theory view of scenario ``sc`` (module doc), InputError where it does not
    apply."""
    c = _contact(sc, body)
    s_cfg, s_mesh, s_centre, radius, b_cfg, b_mesh = _bodies(sc, c)
    if not b_cfg.model.kind.spec.has_basis:
        raise InputError(f"theory: the beam {b_cfg.name!r} is rigid; expected a flexible beam")
    lo, hi, axis = _beam_frame(b_cfg, b_mesh)
    pb = b_cfg.placement
    if np.any(np.asarray(pb.velocity_mps)) or np.any(np.asarray(pb.angular_velocity_radps)):
        raise InputError(f"theory: the beam {b_cfg.name!r} must be at rest at t = 0")
    rb = pb.rotation.matrix()
    speed, normal_idx, sign = _impact_direction(s_cfg, rb, axis)
    n_loc = sign * np.eye(3)[normal_idx]
    width_idx = 3 - axis - normal_idx
    gap, x_c = _gap_and_contact_x(s_cfg, s_mesh, s_centre, radius, pb, lo, hi, axis, n_loc)
    mb, ms = b_cfg.material_obj(), s_cfg.material_obj()
    e_star = (
        mb.E / (1.0 - mb.nu**2)
        if not s_cfg.model.kind.spec.has_basis
        else effective_modulus(ms.E, ms.nu, mb.E, mb.nu)
    )
    beam = TimoshenkoBeam(
        float(hi[axis] - lo[axis]),
        float(hi[width_idx] - lo[width_idx]),
        float(hi[normal_idx] - lo[normal_idx]),
        mb.E,
        mb.nu,
        mb.rho,
    )
    impact = SphereOnBeam(
        beam,
        x_c,
        radius,
        ms.rho * _skin_volume(s_mesh),
        e_star,
        speed,
        n_modes=n_modes,
        n_elements=n_elements,
    )
    n_glob, e_glob = rb @ n_loc, rb @ np.eye(3)[axis]
    probes = _case_probes(sc, s_cfg, s_mesh, b_cfg, b_mesh, lo, hi, axis, n_loc, n_glob, e_glob)
    return SphereBeamCase(s_cfg.name, b_cfg.name, impact, max(gap, 0.0) / speed, probes)


def sphere_beam_histories(
    sc, dt: float | None = None
) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], dict]:
    """(t, contact force, {probe: global x velocity}, info) of the beam theory of scenario sc
    over its end time, sampled every dt [s] (default 0.25 us) from the first touch on."""
    return case_histories(sphere_beam_case(sc), sc.time.t_end_s, dt)


def case_histories(
    case: SphereBeamCase, t_end: float, dt: float | None = None
) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], dict]:
    """sphere_beam_histories of a case (one whose impact may be changed, e.g. its beam's
    modulus or its local law) up to t_end [s]."""
    dt = 0.25e-6 if dt is None else float(dt)
    t0 = case.t_first_touch_s
    if not t0 < t_end:
        raise InputError(
            f"theory: the sphere touches the beam at {t0:.4g} s, after the end time {t_end:.4g} s"
        )
    beam_x = tuple(x for _, where, x, *_ in case.probes if where == "beam")
    sol = case.impact.solve(t_end - t0, dt, probes_x_m=beam_x)
    before = np.arange(math.ceil(t0 / dt)) * dt
    before = before[before < t0]
    t = np.concatenate([before, t0 + sol.t])
    pad = np.zeros(len(before))
    probes, k = {}, 0
    for name, where, _, eta, n_x, e_x in case.probes:
        if where == "sphere":
            v = np.concatenate([pad + case.impact.speed_mps, sol.sphere_velocity]) * n_x
        else:
            v = np.concatenate([pad, sol.probe_w_t[:, k] * n_x - eta * sol.probe_psi_t[:, k] * e_x])
            k += 1
        probes[name] = v + 0.0  # no -0.0 in the history
    info = {
        "law": LAW,
        "v0_mps": case.impact.speed_mps,
        "striker": case.sphere,
        "target": case.beam,
        "t_first_touch_s": t0,
        "contacts_s": [(t0 + a, t0 + b) for a, b in sol.contacts],
        "n_modes": case.impact.n_modes,
        "sphere_mass_kg": case.impact.sphere_mass_kg,
    }
    return t, np.concatenate([pad, sol.force]), probes, info


__all__ = ["LAW", "SphereBeamCase", "case_histories", "sphere_beam_case", "sphere_beam_histories"]
