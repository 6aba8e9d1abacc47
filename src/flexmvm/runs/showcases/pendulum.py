"""The pendulum release (scenarios/pendulum_release.toml, issue 14): what the whole event is
measured by. Histories for the figure (string angles, the gap of the contact surfaces, the
force), the impact phase against the free seed case (rod_impact.toml) aligned at first contact,
and the momenta after the separation against a rigid pendulum swinging on from the separation.
"""

from __future__ import annotations

import math

import numpy as np

from flexmvm.constraints.joints import BodyPoint, DistanceJoint
from flexmvm.contact.pairs import PointToSurfaceContact
from flexmvm.errors import InputError
from flexmvm.integrate.state import BodyState
from flexmvm.metrics.ncc import compare_force, contact_intervals, ncc

ONSET_FRACTION = 0.01  # the contact starts when the force reaches this fraction of its peak


def _states_at(res, k: int, bodies) -> list[BodyState]:
    if res.field_index is not None:  # q kept at the field outputs only (TimeGrid)
        raise InputError(
            "the pendulum's event histories need q at every output; expected no "
            "[time] field_output_dt_s in its scenario"
        )
    return [
        BodyState(res.frame_r[k, b], res.frame_A[k, b], res.q[b][k], np.zeros(body.nv))
        for b, body in enumerate(bodies)
    ]


def strings(system) -> list[DistanceJoint]:
    """The distance joints to the ground (the strings)."""
    return [
        j for j in system.joints if isinstance(j, DistanceJoint) and not isinstance(j.p2, BodyPoint)
    ]


def attachment_positions(built, res) -> np.ndarray:
    """(n_out, n_strings, 3) global positions of the strings' body points at every output [m]
    (strings in the order of strings(system))."""
    bodies = built.system.bodies
    js = strings(built.system)
    out = np.empty((len(res.t), len(js), 3))
    for k in range(len(res.t)):
        states = _states_at(res, k, bodies)
        for i, j in enumerate(js):
            out[k, i] = j.p1.position(bodies, states)
    return out


def event_histories(built, res) -> dict:
    """At every output: the signed angle of each string from the vertical in the x-z plane
    [rad] ({"<body>.<k>": array}, atan2 of the attachment's x and -z offsets from its ground
    point) and the closest distance between a node of the first contact's slave surface and a
    node of its master surface [m] (the gap, up to the surfaces' node spacing; ~0 in contact)."""
    system = built.system
    bodies = system.bodies
    angles: dict[str, np.ndarray] = {}
    count: dict[int, int] = {}
    per_body = []
    for j in strings(system):
        b = j.p1.body
        count[b] = count.get(b, 0) + 1
        per_body.append((f"{bodies[b].name}.{count[b]}", j))
    n = len(res.t)
    for name, _ in per_body:
        angles[name] = np.empty(n)
    gap = np.full(n, np.nan)
    pair = next((c for c in system.contacts if isinstance(c, PointToSurfaceContact)), None)
    for k in range(n):
        states = _states_at(res, k, bodies)
        for name, j in per_body:
            d = j.p1.position(bodies, states) - np.asarray(j.p2, float)
            angles[name][k] = math.atan2(d[0], -d[2])
        if pair is not None:
            s, m = states[pair.slave], states[pair.master]
            xs = bodies[pair.slave].node_positions(pair.slave_nodes, s.r, s.A, s.q)
            xm = bodies[pair.master].node_positions(pair.master_nodes, m.r, m.A, m.q)
            from scipy.spatial import cKDTree  # here: scipy.spatial is slow to import

            gap[k] = float(cKDTree(xm).query(xs)[0].min())
    return {
        "t_s": res.t,
        "angle_rad": angles,
        "gap_m": gap,
        "force_N": res.contact_force,
        "contact_intervals_s": [tuple(iv) for iv in res.contact_intervals],
    }


def _fine_block(t: np.ndarray, start: float, step: float) -> float:
    """End of the run of outputs spaced `step` (to 1e-9 relative) that contains `start`."""
    i = int(np.searchsorted(t, start - 1e-12))
    while i + 1 < len(t) and abs(t[i + 1] - t[i] - step) <= 1e-9 * max(step, 1e-300) + 1e-15:
        i += 1
    return float(t[i])


def force_onset(t, force, fraction: float = ONSET_FRACTION) -> float:
    """The time the contact force first exceeds `fraction` of its peak, interpolated linearly
    between outputs [s] (metrics.contact_intervals): the first contact, blind to a single-step
    touch just before it and not rounded to the step."""
    f = np.asarray(force, float)
    level = fraction * float(f.max())
    if not level > 0:
        raise InputError("force onset: the contact force is never positive")
    return contact_intervals(t, f, level)[0][0]


def impact_comparison(res, ref, probes=("b2_impact_end", "b2_free_end")) -> dict:
    """The pendulum's impact phase (res) against the free seed case (ref), both shifted to
    t = 0 at their first contact (force_onset: the force reaches 1 % of its peak): force NCC,
    peak, impulse and duration errors, and the NCC of the axial velocity of each named probe,
    over the pendulum's contiguous block of contact outputs (output_contact_dt_s; the
    reference's output step) from the first contact."""
    if not res.contact_intervals or not ref.contact_intervals:
        raise InputError("impact comparison: a run has no contact (contact_intervals empty)")
    t0, r0 = force_onset(res.t, res.contact_force), force_onset(ref.t, ref.contact_force)
    step = float(np.median(np.diff(ref.t)))
    start = float(res.t[max(int(np.searchsorted(res.t, t0)) - 1, 0)])
    end = _fine_block(res.t, start, step)
    keep = (res.t >= t0 - 1e-12) & (res.t <= end + 1e-12)
    t = res.t[keep] - t0
    tr = ref.t - r0
    k_ref = (tr >= -1e-12) & (tr <= t[-1] + 1e-12)
    c = compare_force(tr[k_ref], ref.contact_force[k_ref], t, res.contact_force[keep])
    out = {
        "window_s": [0.0, float(t[-1])],
        "first_contact_s": float(t0),
        "ncc_force": c.ncc,
        "ncc_force_whole": c.ncc_whole,
        "peak_err": c.peak_err,
        "impulse_err": c.impulse_err,
        "duration_err": c.duration_err,
        "contact_duration_s": float(res.contact_intervals[-1][1] - t0),
        "contact_duration_ref_s": float(ref.contact_intervals[-1][1] - r0),
    }
    for name in probes:
        i, i_ref = res.probe_names.index(name), ref.probe_names.index(name)
        out[f"ncc_{name}"] = ncc(
            tr[k_ref], ref.probe_v[k_ref, i_ref, 0], t, res.probe_v[keep, i, 0]
        )
    return {k: float(v) if isinstance(v, (float, np.floating)) else v for k, v in out.items()}


def momenta_after_separation(built, res, ref=None) -> dict:
    """Each body's linear momentum [kg m/s] at the separation (end of the last contact
    interval, first output after it) and at the end, against a rigid bifilar pendulum of string
    length l (the body's first string) swinging on from the separation: translating on a
    circle, p_x(t) = p_x,sep cos(w tau) - m w x_sep sin(w tau) with w = sqrt(g / l) and x_sep the
    frame's horizontal offset from the bottom (the run's first string vertical). With ref (the
    free seed case, same models) also its momenta after its contact."""
    if not res.contact_intervals:
        raise InputError("momenta after separation: the run has no contact")
    system = built.system
    g = float(np.linalg.norm(system.gravity))
    sep = res.contact_intervals[-1][1]
    k0 = int(np.searchsorted(res.t, sep - 1e-12))
    tau = float(res.t[-1] - res.t[k0])
    out: dict = {
        "t_separation_s": float(sep),
        "t_sep_output_s": float(res.t[k0]),
        "t_end_s": float(res.t[-1]),
    }
    bodies = system.bodies
    states0 = _states_at(res, k0, bodies)
    for b, body in enumerate(bodies):
        js = [j for j in strings(system) if j.p1.body == b]
        m = float(body.inv.mass)
        p0, p1 = res.body_momentum[k0, b], res.body_momentum[-1, b]
        entry = {"mass_kg": m, "p_sep": p0.tolist(), "p_end": p1.tolist()}
        if js and g > 0:
            j = js[0]
            ell = j.length
            w = math.sqrt(g / ell)
            x_off = float(j.p1.position(bodies, states0)[0] - np.asarray(j.p2, float)[0])
            px = p0[0] * math.cos(w * tau) - m * w * x_off * math.sin(w * tau)
            entry.update(
                p_end_rigid_pendulum_x=px,
                p_end_rel_err_x=float((p1[0] - px) / max(abs(px), 1e-300)),
            )
        out[body.name] = entry
    if ref is not None:
        sep_r = ref.contact_intervals[-1][1]
        kr = int(np.searchsorted(ref.t, sep_r - 1e-12))
        for b, body in enumerate(bodies):
            pr = ref.body_momentum[kr, b]
            out[body.name]["p_sep_seed_case"] = pr.tolist()
            out[body.name]["p_sep_rel_err_x_vs_seed_case"] = float(
                (res.body_momentum[k0, b][0] - pr[0]) / max(abs(pr[0]), 1e-300)
            )
    return out


def impact_speed(built, res, body: int = 0) -> dict:
    """Centre-of-mass velocity of `body` (its momentum / mass, blind to the frame's elastic
    wobble) at the last output before the first contact [m/s], and that output's time."""
    if not res.contact_intervals:
        raise InputError("impact speed: the run has no contact")
    k = int(np.searchsorted(res.t, res.contact_intervals[0][0] + 1e-12)) - 1
    v = res.body_momentum[k, body] / float(built.system.bodies[body].inv.mass)
    return {"t_s": float(res.t[k]), "v_mps": float(np.linalg.norm(v)), "v_cm_mps": v.tolist()}


def is_pendulum(built) -> bool:
    """Strings to the ground, gravity and a contact: the event this module measures."""
    sysm = built.system
    return bool(strings(sysm)) and bool(sysm.contacts) and bool(np.any(sysm.gravity))


def event_summary(built, res) -> dict:
    """What a pendulum run reports (summary.json "pendulum"): the striker's (body 0) impact
    speed, the momenta after the separation against the rigid pendulum and the total energy
    at the separation output relative to the start (the swing and the impact, before the
    steps grow again); without contact only {"contact": false}."""
    if not res.contact_intervals:
        return {"contact": False}
    k = int(np.searchsorted(res.t, res.contact_intervals[-1][1] - 1e-12))
    E = res.total_energy
    return {
        "contact": True,
        "impact_speed": impact_speed(built, res),
        "momenta_after_separation": momenta_after_separation(built, res),
        "energy_rel_at_separation": float(E[k] / E[0] - 1.0),
    }
