"""The pendulum release (issue 14, scenarios/pendulum_release.toml): strings attached at their
body points, and a shortened event (b1 started on its swing arc a few mm before the impact)
through approach, impact, separation and the swing after, against the free seed case
(rod_impact.toml) with the same models and against a rigid pendulum.

The whole 0.36 s event is run by `flexmvm run scenarios/pendulum_release.toml` (numbers in
docs/pendulum.md); here its last 17 ms, where every phase of it happens.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm.assembly.build import build_scenario
from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.rotation import axis_angle
from flexmvm.constraints.joints import BodyPoint, DistanceJoint
from flexmvm.constraints.rows import Rows
from flexmvm.errors import InputError
from flexmvm.integrate.state import BodyState
from flexmvm.runs.compare import compare_runs
from flexmvm.runs.run import run_scenario
from flexmvm.runs.showcases.pendulum import (
    attachment_positions,
    force_onset,
    impact_comparison,
    impact_speed,
    momenta_after_separation,
    strings,
)
from flexmvm.scenarios import load_scenario, scenario_from_dict
from flexmvm.theory.scenario import theory_histories

ROOT = Path(__file__).resolve().parents[1]
PENDULUM = ROOT / "scenarios" / "pendulum_release.toml"
SEED = ROOT / "scenarios" / "rod_impact.toml"
V0, ELL, G = 0.21, 0.5, 9.81
GAP_M = 3e-3  # the short event starts with b1's apex this far (along x) before b2
AFTER_S = 2.5e-3  # and runs this long after the seed case's contact time (0.66 ms)


def _data(model: str | None = "mvm") -> dict:
    data = load_scenario(PENDULUM).model_dump(mode="json")
    if model is not None:
        for b in data["bodies"]:
            b["model"]["kind"] = model
    return data


def test_body_point_offset_row_is_the_points_velocity():
    """A point at a body-frame offset from a node of a flexible body: its constraint row times
    v is the time derivative of its position (central difference, h = 1e-6: error ~h^2)."""
    rng = np.random.default_rng(3)
    X = rng.normal(size=(5, 3))
    psi = rng.normal(size=(15, 2))
    body = FlexibleBody.build("b", X, sp.diags(rng.uniform(1, 2, 5)), psi, np.eye(2))
    v = rng.normal(size=body.nv)
    st = BodyState(rng.normal(size=3), axis_angle(rng.normal(size=3), 0.7), rng.normal(size=2), v)
    p = BodyPoint(0, node=2, offset_m=(0.01, -0.02, 0.03))
    d = np.array([0.3, -0.5, 0.8])
    rows = Rows(1)
    p.add_row(rows, 0, d, 1.0, [body], [st])
    rate = float(rows.times([v])[0])

    def at(h):
        w = v[3:6]
        A = st.A @ axis_angle(w, h * np.linalg.norm(w))
        return p.position([body], [BodyState(st.r + h * v[:3], A, st.q + h * v[6:], v)])

    h = 1e-6
    assert rate == pytest.approx(float(d @ (at(h) - at(-h))) / (2 * h), rel=1e-8)
    # the offset moves the point: position = node + A offset
    x_node = BodyPoint(0, node=2).position([body], [st])
    np.testing.assert_allclose(
        p.position([body], [st]) - x_node, st.A @ [0.01, -0.02, 0.03], atol=1e-15
    )
    with pytest.raises(InputError, match="offset_m is measured from a node"):
        BodyPoint(0, local=(0.0, 0.0, 0.0), offset_m=(0.01, 0.0, 0.0))


@pytest.mark.parametrize("model", ["mvm", "rigid"])
def test_strings_attach_at_their_points_and_hang_vertically(model):
    """Every string's body point is where the scenario puts it (0.01 m from the nearest nodes
    at axial stations 0.24/0.26, 0.74/0.76, before issue 14) and 0.5 m from its ground point;
    at the bottom of the swing (b1 shifted back along its arc) every string is vertical. (On
    the undeformed rods; sagged, the frames move by the least change that keeps the strings at
    their lengths: |phi| < 1e-9 m at t = 0, measured 6e-11.)"""
    data = _data(model)
    sagged = build_scenario(scenario_from_dict(data, "pendulum_release.toml"))
    for j in sagged.system.joints:
        assert abs(j.evaluate(sagged.system.bodies, sagged.states, 0.0)[0][0]) < 1e-9
    for b in data["bodies"]:
        b["placement"]["sagged"] = False
    sc = scenario_from_dict(data, "pendulum_release.toml")
    built = build_scenario(sc)
    js = strings(built.system)
    assert len(js) == len(sc.joints) == 4
    bottom = -np.asarray(sc.body("b1").placement.position_m)
    for j, cfg in zip(js, sc.joints):
        x = j.p1.position(built.system.bodies, built.states)
        np.testing.assert_allclose(
            x, sc.body(cfg.body).placement.to_global(cfg.point_m), rtol=0, atol=1e-14
        )
        assert j.length == pytest.approx(ELL, rel=1e-13)
        off = x - np.asarray(j.p2) + (bottom if cfg.body == "b1" else 0.0)
        np.testing.assert_allclose(off, [0.0, 0.0, -ELL], rtol=0, atol=1e-14)


@pytest.mark.parametrize("model", ["mvm", "rigid"])
def test_joint_point_off_the_body_is_a_one_line_input_error(model):
    data = _data(model)
    data["joints"][1]["point_m"] = [0.75, 0.0, 0.05]  # 4 cm above a rod of radius 1 cm
    sc = scenario_from_dict(data, "pendulum_release.toml")
    with pytest.raises(InputError) as info:
        build_scenario(sc)
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith("joints[1].point_m:") and "off the body" in msg


def _short_scenario(model: str = "mvm"):
    """pendulum_release.toml with b1 on its swing arc GAP_M before its apex reaches b2, at the
    speed it has there (sqrt(V0^2 - 2 g dz)): the same bottom speed, impact and swing after."""
    data = _data(model)
    phi = math.asin(GAP_M / ELL)
    dz = ELL * (1 - math.cos(phi))
    v = math.sqrt(V0**2 - 2 * G * dz)
    b1 = data["bodies"][0]
    b1["placement"]["position_m"] = [-ELL * math.sin(phi), 0.0, dz]
    b1["placement"]["velocity_mps"] = [v * math.cos(phi), 0.0, -v * math.sin(phi)]
    t_approach = ELL * phi / V0  # arc length at ~V0 (V0 varies by 4e-5 over it)
    data["time"]["t_end_s"] = round(t_approach + 0.66e-3 + AFTER_S, 6)
    return scenario_from_dict(data, "pendulum_release.toml (started 3 mm before impact)")


def _seed_on_the_pendulums_scheme():
    """rod_impact.toml with the pendulum's models and scheme: both rods MVM, theta and the
    contact's law and mass redistribution as in pendulum_release.toml (the seed case ships
    the undamped scheme, the pendulum the damped one)."""
    pend = load_scenario(PENDULUM)
    data = load_scenario(SEED).with_overrides(model="mvm", t_end_s=0.8e-3).model_dump(mode="json")
    data["time"]["theta"] = pend.time.theta
    c = pend.contacts[0]
    data["contacts"][0].update(law=c.law.value, redistribute_mass=c.redistribute_mass)
    return scenario_from_dict(data, "rod_impact.toml (the pendulum's scheme)")


@functools.cache
def _runs():
    own = run_scenario(_short_scenario())
    seed = run_scenario(_seed_on_the_pendulums_scheme())
    return own, seed


@pytest.mark.validation  # long: in `pytest -m validation`, not the default run
def test_short_pendulum_event_steps_big_in_the_swing_and_dt_at_contact():
    """The step-size policy: steps of 2^k dt up to dt_max far from contact, coming down level
    by level on the approach, dt through the contact, growing again after it. Measured: 1,330
    steps at dt (0.665 ms: the contact, 0.657 ms, and a few steps each side), 58 at 256 us;
    the outputs in contact every output_contact_dt_s (2 us)."""
    own, _ = _runs()
    s, res = own.summary, own.result
    dt = own.built.grid.dt_s
    counts = s["step_size_counts"]
    assert s["dt_min_taken_s"] == dt and s["dt_max_taken_s"] == own.built.grid.dt_max_s
    n_dt = counts[f"{dt:.6g}"]
    t0, t1 = s["contact_intervals_s"][0][0], s["contact_intervals_s"][-1][1]
    assert (t1 - t0) / dt <= n_dt <= (t1 - t0) / dt + 100  # dt only at and near the contact
    assert sum(n for h, n in counts.items() if float(h) >= 64 * dt) >= 20
    inside = (res.t > t0) & (res.t <= t1)
    np.testing.assert_allclose(np.diff(res.t[inside]), 2e-6, rtol=1e-9)


@pytest.mark.validation  # long: in `pytest -m validation`, not the default run
def test_short_pendulum_impact_matches_the_seed_case():
    """Impact speed sqrt(2 g h) at the bottom (here: the arc start's speed plus its fall),
    and the impact phase against rod_impact.toml (the same MVM models, scheme, dt, output step),
    aligned at first contact (the force reaching 1 % of its peak; a single 0.5 us touch 2 us
    before the contact proper is not it). Measured on the scenario's undamped scheme (theta =
    1/2, position law, massless contact nodes): speed error -2.4e-7; force NCC 0.99990, peak
    -0.66 %, impulse -0.011 %, duration -0.075 %; b2 free-end NCC 0.99959, impact-end NCC
    0.970 (on the damped scheme, theta(h) = 1/2 + h / (4 tau) at every step size: speed error
    -3.4e-5, theta reaching 1 on the swing's 256 us steps; with theta fixed at its dt_s value
    it was -3.6e-6; 0.99978, +0.37 %, -0.004 %, -0.25 %; 0.99972, 0.947). Required: speed
    within 0.1 % (the issue asks 0.5 %; the undamped scheme's swing error over 3 mm is ~1e-6), force NCC >= 0.995 (the issue's), peak and
    duration within 1 % (what gravity, strings and the sag may change: the strings act along
    x with m g x / l ~ 1e-3 N against a 600 N force; the sag puts the apex and b2's end centre
    3.6 um apart vertically), free-end NCC >= 0.995, impact-end NCC >= 0.9 (one node under the
    contact patch, not a criterion in docs/validation.md: the seed case against itself shifted
    by 1 us gives 0.986; started undeformed, with the rods' ends vibrating vertically at
    ~1 cm/s, it was 0.84)."""
    own, seed = _runs()
    v = impact_speed(own.built, own.result)["v_mps"]
    assert abs(v / V0 - 1) < 1e-3
    c = impact_comparison(own.result, seed.result)
    assert c["ncc_force"] >= 0.995
    assert abs(c["peak_err"]) < 0.01 and abs(c["duration_err"]) < 0.01
    assert c["ncc_b2_free_end"] >= 0.995 and c["ncc_b2_impact_end"] >= 0.9


@pytest.mark.validation  # long: in `pytest -m validation`, not the default run
def test_sagged_rods_hang_still_until_the_impact():
    """Both rods start in their quasi-static sag (placement.sagged): b2 hangs still and b1
    swings without bending vibration. Measured before the contact: b2's end nodes |v| <= 5.5e-6
    m/s (started undeformed: 7e-3 m/s, the rods' bending vibration under gravity), b1's apex
    |v_z| 1.44e-3 m/s, its swing's own v sin(phi) = 1.26e-3 at the start. Required: b2 1e-4 m/s,
    b1's apex 2e-3 m/s."""
    own, _ = _runs()
    res = own.result
    before = res.t < own.summary["contact_intervals_s"][0][0]
    for name in ("b2_impact_end", "b2_free_end"):
        i = res.probe_names.index(name)
        assert np.abs(res.probe_v[before, i]).max() < 1e-4, name
    i = res.probe_names.index("b1_apex")
    assert np.abs(res.probe_v[before, i, 2]).max() < 2e-3
    assert np.linalg.norm(own.built.states[1].q) > 0  # b2 did start sagged


def test_sag_needs_a_frame_that_does_not_turn():
    data = _data("mvm")
    data["bodies"][1]["placement"]["angular_velocity_radps"] = [0.0, 0.0, 0.1]
    with pytest.raises(InputError) as info:
        build_scenario(scenario_from_dict(data, "pendulum_release.toml"))
    assert "\n" not in str(info.value)
    assert str(info.value).startswith(
        "bodies[b2].placement: sagged = true needs a body whose frame"
    )


@pytest.mark.validation  # long: in `pytest -m validation`, not the default run
def test_short_pendulum_after_separation_and_strings():
    """After the separation each rod swings on as a rigid pendulum: its x-momentum at the end
    against p_sep cos(w tau) - m w x_sep sin(w tau) (w = sqrt(g / l)); at the separation
    against the seed case's momenta after its contact (no gravity, no strings). Measured:
    -2.6e-6 and -5.6e-6 (rigid pendulum, b1, b2), 3.7e-5 and -1.25e-4 (seed case). Required 3e-5
    and 1e-3 (the strings' pull over the 0.66 ms contact, m g x / l dt ~ 1e-6 kg m/s, and the rods'
    vibration, whose momentum is in the centre-of-mass momentum). b2 hangs still until the
    impact: |p_x| < 1e-8 kg m/s (measured 3.7e-10; 3.7e-9 started undeformed, whose bending
    vibration turns the sections under the attachment points, 0.01 m above the axis, and so
    tilts the strings; with the strings on the nodes 0.01 m off it was 0.017 m/s x 0.85 kg,
    test_pendulum's ancestor, the strict xfail in test_validation_live); the strings keep their length (drift < 1e-9 m) and stay on
    their points (length from the attachment positions)."""
    own, seed = _runs()
    m = momenta_after_separation(own.built, own.result, seed.result)
    for name in ("b1", "b2"):
        assert abs(m[name]["p_end_rel_err_x"]) < 3e-5, m[name]
        assert abs(m[name]["p_sep_rel_err_x_vs_seed_case"]) < 1e-3, m[name]
    res, s = own.result, own.summary
    before = res.t < s["contact_intervals_s"][0][0]
    assert np.abs(res.body_momentum[before, 1, 0]).max() < 1e-8
    assert s["max_joint_drift"] < 1e-9
    js = strings(own.built.system)
    lengths = np.linalg.norm(
        attachment_positions(own.built, res) - np.array([j.p2 for j in js])[None], axis=2
    )
    np.testing.assert_allclose(lengths, ELL, rtol=0, atol=1e-9)
    assert isinstance(js[0], DistanceJoint)


def _contact_block(res, s) -> np.ndarray:
    """The outputs of the contact block (every output_contact_dt_s, 2 us) from the last output
    before the first contact."""
    t = res.t
    start = float(t[int(np.searchsorted(t, s["contact_intervals_s"][0][0])) - 1])
    end = float(t[-1])
    for k in range(int(np.searchsorted(t, start)), len(t) - 1):
        if abs(t[k + 1] - t[k] - 2e-6) > 1e-12:
            end = float(t[k])
            break
    return (t >= start - 1e-12) & (t <= end + 1e-12)


@pytest.mark.validation  # long: in `pytest -m validation`, not the default run
def test_short_pendulum_impact_with_gravity_and_strings():
    """Contact with gravity and joints together, on the short event (b1 MVM 3-5 + 80, b2 MVM
    1-3 + 37, four strings, contact step 0.5 us): over the 0.66 ms contact the strings barely
    act along x (pendulum period 1.4 s), so the impact is the free seed case's. Measured: first
    contact (the start of the step that closes the gap) 14.2950 ms against the rigid bifilar
    pendulum's 14.2960 ms; force vs the seed's 1D wave-Hertz solution aligned at the force
    onset: NCC 0.99764, peak +1.3 %, contact end -0.9 % of the duration; string drift 1.9e-15
    m; momentum balance error 9.2e-10 of p0 over the contact block. Required:
    - contact begins when the rigid pendulum started at the event's angle phi and speed v
      reaches the bottom, t = atan(phi l w / v) / w (w = sqrt(g / l); bifilar strings keep b1
      level, so every point swings as a simple pendulum; sin phi = phi to 6e-6), within 2 us
      (one output step);
    - NCC >= 0.99, peak within 3 %, contact end within 3 % of the contact duration (the free
      seed case's acceptance of docs/validation.md);
    - the joints hold: position-level string rows, drift < 1e-9 m;
    - momentum balance over the contact block (2 us outputs): the change of total momentum
      equals the string impulses (lambda along each string, direction from the attachment
      points, midpoint over each output interval) plus M g t, to 1e-7 of the initial momentum
      in each component (the direction turns by v dt / l ~ 1e-6 rad per interval; over the
      swing's 1 ms outputs it turns 400 x more, so the balance is taken where the impact is).
      The contact forces are internal and drop out; with the strings attached at their points
      (vertical at the bottom) they pull along x only by the swing's own tilt: |dp_x| < 2e-5
      p0 (measured 4.6e-6 p0; it was 5.5e-4 p0 with the strings on the nodes 0.01 m off).
    (Until this shared run it was test_validation_live's own run, started 20 us before the
    impact, b1 3-5 + 40: NCC 0.99924, peak +1.9 %, drift 1.3e-13 m, balance 1.4e-9 p0.)"""
    own, _ = _runs()
    built, res, s = own.built, own.result, own.summary
    b1 = _short_scenario().body("b1").placement
    v = float(np.linalg.norm(b1.velocity_mps))
    phi, w = math.asin(GAP_M / ELL), math.sqrt(G / ELL)
    assert abs(s["contact_intervals_s"][0][0] - math.atan(phi * ELL * w / v) / w) <= 2e-6
    assert s["lcp_residual_max"] <= 1e-8 and s["steps_on_roundoff_floor"] == 0
    block = _contact_block(res, s)
    t, f = res.t[block], res.contact_force[block]
    assert t[-1] > s["contact_intervals_s"][-1][1]  # the block holds the whole contact
    tt, ft, _, _ = theory_histories(load_scenario(SEED).with_overrides(t_end_s=0.72e-3))
    tt = tt - force_onset(tt, ft) + force_onset(t, f)
    c = compare_runs(tt, ft, {}, t, f, {})
    assert c["ncc_force"] >= 0.99
    assert abs(c["peak_err"]) < 0.03
    end, on_th = s["contact_intervals_s"][-1][1], tt[ft > 0]
    assert abs(end - on_th.max()) < 0.03 * (on_th.max() - on_th.min())
    assert s["max_joint_drift"] < 1e-9
    # momentum balance
    joints = strings(built.system)
    assert len(joints) == len(built.system.joints) == 4
    ground = np.array([j.p2 for j in joints], float)
    e = attachment_positions(built, res)[block] - ground[None]
    e /= np.linalg.norm(e, axis=2)[:, :, None]
    mid = 0.5 * (e[1:] + e[:-1])  # string directions over each output interval
    lam = res.joint_force[block]
    J = np.vstack(
        [np.zeros(3), np.cumsum((lam[1:, :, None] * mid).sum(1) * np.diff(t)[:, None], 0)]
    )
    M = sum(float(b.inv.mass) for b in built.system.bodies)
    p = res.momentum[block]
    dp = p - p[0]
    err = dp - J - M * built.system.gravity[None] * (t - t[0])[:, None]
    p0 = np.linalg.norm(res.momentum[0])
    assert np.abs(err).max() < 1e-7 * p0, np.abs(err).max(0)
    assert abs(dp[-1, 0]) < 2e-5 * p0
    # and the impact moved b2 forward (its frame) while b1 slowed
    assert res.frame_v[-1, 1, 0] > 0.1 and res.frame_v[-1, 0, 0] < V0


def test_event_figure(tmp_path):
    """plot_event draws the three panels and the inset; arrays not like t are a one-line
    InputError. (`flexmvm run` draws it as <scenario>_event.png for a pendulum scenario.)"""
    from flexmvm.plots.pendulum import plot_event

    t = np.linspace(0.0, 0.36, 400)
    force = np.where((t > 0.3548) & (t < 0.3555), 600.0, 0.0)
    path = tmp_path / "event.png"
    plot_event(
        path,
        t,
        {"b1.1": -0.09 * np.cos(4.4 * t)},
        0.047 * np.cos(4.4 * t),
        force,
        [(0.3548, 0.3555)],
        title="synthetic",
    )
    assert path.stat().st_size > 10_000
    with pytest.raises(InputError) as info:
        plot_event(path, t, {"b1.1": t[:-1]}, t, force)
    assert "\n" not in str(info.value) and "angle_rad[b1.1]" in str(info.value)
