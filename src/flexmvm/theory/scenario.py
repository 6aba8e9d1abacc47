"""The 1D wave solution of a two-rod scenario, in the history format of a simulation run.

One mapping from a scenario to the 1D theory (:func:`rod_impact`), used by every caller (the
main job's comparison, ``flexmvm theory``, the validation report and the a-priori estimate of
the selection study):

- the contact: the scenario's only contact, or the one of ``body`` when a body is named;
  both of its bodies must be rods ([bodies.rod]);
- the striker is the body moving faster (speed of its placement velocity), the target the
  other; the contact end of each rod is the end its contact surface names (``end_a`` or
  ``end_b``; a ``side`` surface is not an end impact: InputError);
- the impact axis is the outward normal of the striker's contact end (-x local for end A, +x
  for end B), and the impact speed the relative velocity along it; it must be > 0;
- the law: Hertz when a contact end is a hemisphere (sphere radius = that rod's radius; two
  hemispheres: R = R1 R2 / (R1 + R2)), St Venant (rigid) when both are flat;
- probes must sit at the centre of a rod end (node sets ``end_a_centre`` / ``end_b_centre``):
  the contact end's centre is the near end, the other the far end.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError
from flexmvm.mesh.rod import EndShape
from flexmvm.metrics.ncc import contact_intervals
from flexmvm.theory.wave import ContactLaw, Rod1D, WaveSolution, hertz_stiffness, two_rod_impact

_OUTWARD = {"end_a": -1.0, "end_b": 1.0}  # local x of an end's outward normal


@dataclass(frozen=True)
class RodImpact:
    """A two-rod scenario as the 1D theory sees it (module doc)."""

    striker: str  # body names
    target: str
    rod1: Rod1D  # striker
    rod2: Rod1D  # target
    v0_mps: float  # impact speed along the axis [m/s]
    axis: np.ndarray  # (3,) impact direction, global
    law: ContactLaw
    sphere_radius_m: float | None  # Hertz radius [m] (None: St Venant)
    ends: dict  # body name -> its contact end ("end_a" / "end_b")

    def solve(self, t_end_s: float, dt: float | None = None) -> WaveSolution:
        return two_rod_impact(
            self.rod1,
            self.rod2,
            self.v0_mps,
            t_end_s,
            self.law,
            sphere_radius_m=self.sphere_radius_m,
            dt=dt,
        )


def _contact_of(sc, body: str | None):
    if body is None:
        if len(sc.contacts) != 1:
            raise InputError(
                f"theory: needs exactly one contact between two rods, got {len(sc.contacts)}"
            )
        return sc.contacts[0]
    for c in sc.contacts:
        if body in (c.slave_body, c.master_body):
            return c
    raise InputError(f"theory: body {body!r} is in no contact of the scenario")


def rod_impact(sc, body: str | None = None) -> RodImpact:
    """The 1D view of scenario ``sc`` (module doc); ``body`` picks the contact of that body."""
    c = _contact_of(sc, body)
    ends = {c.slave_body: c.slave_surface, c.master_body: c.master_surface}
    a, b = sc.body(c.slave_body), sc.body(c.master_body)
    for cfg in (a, b):
        if cfg.rod is None:
            raise InputError(f"theory: body {cfg.name!r} is not a rod ([bodies.rod])")
        if ends[cfg.name] not in _OUTWARD:
            raise InputError(
                f"theory: the contact surface of {cfg.name!r} is "
                f"{ends[cfg.name]!r}, not a rod end (end_a or end_b)"
            )
    speed = lambda cfg: float(np.linalg.norm(cfg.placement.velocity_mps))
    striker, target = (a, b) if speed(a) > speed(b) else (b, a)
    local = np.array([_OUTWARD[ends[striker.name]], 0.0, 0.0])
    axis = striker.placement.rotation.matrix() @ local
    v0 = float(
        axis
        @ (np.asarray(striker.placement.velocity_mps) - np.asarray(target.placement.velocity_mps))
    )
    if not v0 > 0:
        raise InputError(
            f"theory: the striker {striker.name!r} does not approach the target "
            f"(relative axial velocity {v0:.4g} m/s)"
        )
    shape = lambda cfg: cfg.rod.end_a if ends[cfg.name] == "end_a" else cfg.rod.end_b
    radii = [cfg.rod.radius_m for cfg in (striker, target) if shape(cfg) is EndShape.HEMISPHERE]
    sphere = 1.0 / sum(1.0 / r for r in radii) if radii else None
    return RodImpact(
        striker=striker.name,
        target=target.name,
        rod1=Rod1D.from_material(
            striker.material_obj(), striker.rod.length_m, striker.rod.radius_m
        ),
        rod2=Rod1D.from_material(target.material_obj(), target.rod.length_m, target.rod.radius_m),
        v0_mps=v0,
        axis=axis,
        law=ContactLaw.HERTZ if radii else ContactLaw.RIGID,
        sphere_radius_m=sphere,
        ends=ends,
    )


def theory_histories(
    sc, dt: float | None = None
) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], dict]:
    """(t, contact_force, {probe: velocity along global x}, info) of the theory of scenario
    sc over its end time: the 1D wave solution of two rods (module doc: the mapping), or for
    two mesh bodies the Timoshenko beam + Hertz solution of a sphere on a beam
    (flexmvm.theory.sphere_beam). InputError where neither applies."""
    kinds = {
        sc.body(b).rod is not None for c in sc.contacts[:1] for b in (c.slave_body, c.master_body)
    }
    if kinds == {False}:
        from flexmvm.theory.sphere_beam import sphere_beam_histories

        return sphere_beam_histories(sc, dt)
    if kinds == {True, False}:
        raise InputError(
            "theory: a rod against a mesh body; theory covers two rods or a sphere on a beam"
        )
    return _rod_histories(sc, dt)


def _rod_histories(sc, dt: float | None):
    imp = rod_impact(sc)
    sol = imp.solve(sc.time.t_end_s, dt=dt)
    probes = {}
    for p in sc.probes:
        end = (p.node_set or "").removesuffix("_centre")
        if (
            end not in _OUTWARD
            or not p.node_set.endswith("_centre")
            or p.body not in (imp.striker, imp.target)
        ):
            raise InputError(
                f"theory: probe {p.name!r} is not at the centre of a rod end "
                "(node_set end_a_centre or end_b_centre)"
            )
        rod = "1" if p.body == imp.striker else "2"
        where = "near" if end == imp.ends[p.body] else "far"
        v = getattr(sol, f"v{rod}_{where}")
        # 1D velocities are along the impact axis; the probes report the global x component
        probes[p.name] = v * float(imp.axis[0] if abs(imp.axis[0]) > 0.5 else 1.0)
    info = {
        "law": imp.law.value,
        "v0_mps": imp.v0_mps,
        "striker": imp.striker,
        "target": imp.target,
    }
    return sol.t, sol.contact_force, probes, info


def theory_pulse(sc, body: str | None) -> dict:
    """The 1D force pulse of the contact of ``body``: contact duration T_c [s] (first
    interval above 1 % of the peak, solved over at least four round trips of either rod),
    peak force [N] overall and within the scenario's end time, law, impact speed and the
    Hertz contact radius a = (3 F R / 4 E*)^(1/3) [m] at the window's peak (0 for St Venant)."""
    imp = rod_impact(sc, body)
    t_end = max(4.0 * max(imp.rod1.round_trip_s, imp.rod2.round_trip_s), sc.time.t_end_s)
    sol = imp.solve(t_end)
    f = sol.contact_force
    fmax = float(f.max())
    first = contact_intervals(sol.t, f, 0.01 * fmax)[0]
    fwin = float(f[sol.t <= sc.time.t_end_s].max())
    a = 0.0
    if imp.sphere_radius_m is not None:
        radius = imp.sphere_radius_m
        e_star = 3.0 * hertz_stiffness(imp.rod1, imp.rod2, radius) / (4.0 * math.sqrt(radius))
        a = (3.0 * fwin * radius / (4.0 * e_star)) ** (1.0 / 3.0)
    return {
        "law": imp.law.value,
        "v0_mps": imp.v0_mps,
        "contact_duration_s": first[1] - first[0],
        "peak_force_N": fmax,
        "peak_force_window_N": fwin,
        "contact_radius_m": a,
        "sphere_radius_m": imp.sphere_radius_m,
    }
