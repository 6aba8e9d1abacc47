"""The 1D wave solution of a two-rod scenario, in the history format of a simulation run.

The striker is the faster of the contact's two bodies, the target the other. Flat striker end: rigid
contact (St Venant); hemispherical striker end: Hertz law with R = the rod radius. The impact
speed is the relative velocity of the two bodies along the striker's axis. Probes must sit at
the centre of a rod end (node set end_a_centre / end_b_centre): near end = end A (contact end).
"""

from __future__ import annotations

import numpy as np

from flexmvm.errors import InputError
from flexmvm.theory.wave import ContactLaw, Rod1D, two_rod_impact

_END = {"end_a_centre": "near", "end_b_centre": "far"}


def theory_histories(sc, dt: float | None = None) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], dict]:
    """(t, contact_force, {probe: axial velocity}, info) of the 1D solution of scenario sc."""
    if len(sc.contacts) != 1:
        raise InputError(f"theory: needs exactly one contact between two rods, got {len(sc.contacts)}")
    c = sc.contacts[0]
    a, b = sc.body(c.slave_body), sc.body(c.master_body)
    speed = lambda body: float(np.linalg.norm(body.placement.velocity_mps))
    striker, target = (a, b) if speed(a) > speed(b) else (b, a)
    for b in (striker, target):
        if b.rod is None:
            raise InputError(f"theory: body {b.name!r} is not a rod ([bodies.rod])")
    rod1 = Rod1D.from_material(striker.material_obj(), striker.rod.length_m, striker.rod.radius_m)
    rod2 = Rod1D.from_material(target.material_obj(), target.rod.length_m, target.rod.radius_m)
    axis = striker.placement.rotation.matrix() @ np.array([-1.0, 0.0, 0.0])
    v0 = float(axis @ (np.asarray(striker.placement.velocity_mps) - np.asarray(target.placement.velocity_mps)))
    if not v0 > 0:
        raise InputError(f"theory: the striker {striker.name!r} does not approach the target "
                         f"(relative axial velocity {v0:.4g} m/s)")
    hemi = str(getattr(striker.rod.end_a, "value", striker.rod.end_a)) == "hemisphere"
    law = ContactLaw.HERTZ if hemi else ContactLaw.RIGID
    sol = two_rod_impact(rod1, rod2, v0, sc.time.t_end_s, law,
                         sphere_radius_m=striker.rod.radius_m if hemi else None, dt=dt)
    probes = {}
    for p in sc.probes:
        where = _END.get(p.node_set or "")
        if where is None or p.body not in (striker.name, target.name):
            raise InputError(f"theory: probe {p.name!r} is not at the centre of a rod end "
                             "(node_set end_a_centre or end_b_centre)")
        rod = "1" if p.body == striker.name else "2"
        v = getattr(sol, f"v{rod}_{where}")
        # 1D velocities are along the impact axis; the probes report the global x component
        probes[p.name] = v * float(axis[0] if abs(axis[0]) > 0.5 else 1.0)
    info = {"law": law.value, "v0_mps": v0, "striker": striker.name, "target": target.name}
    return sol.t, sol.contact_force, probes, info
