"""The headline physics, live in the default test run (issue 11).

1. The seed case on short rods (scenarios/rod_impact_short.toml: both rods 0.1 m, the seed's
   materials, radius, speed, contact-zone mesh grading and models; full FE 9,801 + 9,075 DOF)
   against the 1D wave-Hertz solution (`flexmvm theory`), and the scenario's MVM model (b2 1-3 +
   37 modes) against its full FE.
2. An `mvm-seed` (seed eq. 4) body, a `modal` body and a `rigid` body in contact, on the same
   short rods (striker: the scenario's b1 mvm model, 3-5 + 40 modes, to keep them cheap).
(Contact with gravity and joints together, scenarios/pendulum_release.toml started just
before the impact, is checked on the short event that tests/test_pendulum.py runs for its
other checks: test_short_pendulum_impact_with_gravity_and_strings.)

Tolerances come from the short case's measured convergence (docs/validation.md, "Short seed
case", made by `python -m tools.validation`): halving the step changes the force by NCC
1 - 2e-7 and the peak by 0.015 %; refining the contact zone (first element 0.15 mm, 4 core
elements: 23,751 + 22,113 DOF) moves the peak by 1.0 % and the contact end by 3 %, and brings
the force NCC against theory from 0.9972 to 0.9994 (peak +3.7 % -> +2.8 %). So at this mesh
the contact-patch discretisation is the dominant numerical error, and the remaining ~3 %
peak excess over the 1D theory is its own limit (1D rods + Hertz half-space compliance). The
1D striker is a cylinder of length L: 3.5 % heavier than the FE striker, whose hemispherical
end has volume pi r^2 (L - r/3); that alone makes the theory's momentum transfer (impulse)
1 % larger (-0.14 % with the mass-equivalent length L - r/3, measured).
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
from _short_case import short_run

from flexmvm.materials import ALUMINIUM, BRASS, Material
from flexmvm.runs.compare import compare_runs
from flexmvm.runs.run import run_scenario
from flexmvm.scenarios import ModelConfig
from flexmvm.studies.grid import seed_scheme
from flexmvm.theory.scenario import theory_histories
from flexmvm.theory.wave import ContactLaw, Rod1D, two_rod_impact
from tools import validation
from tools.validation import acceptance

ROOT = Path(__file__).resolve().parents[1]
V0, L, R = 0.21, 0.1, 0.01
#: The striker of the body-type runs: rod_impact_short.toml's b1 mvm model (3-5 + 40 modes).
STRIKER = ModelConfig(kind="mvm", selection="3-5", modes=40)
TARGET_CB = ModelConfig(kind="mvm", selection="1-3", modes=37)
#: Penetration bounds of the short case, of the 1D solution's peak Hertz approach
#: (F/k)^(2/3) = 12.3 um (k = 4/3 E* sqrt(R)), as for the seed case: b2's contact nodes (the
#: constrained slave nodes) into b1 within 2 %; any node of either surface into the other
#: (measured after every step, contact.penetration) within 12 %: b1's cap nodes are not
#: constrained and sit inside b2's flat facets by the facets' chord error over the dent,
#: measured 0.8-1.26 um here (7-10 %), 1.8 um of 21.3 um on the seed case.
PEN_MAX = 0.02 * 12.3e-6
PEN_ANY = 0.12 * 12.3e-6


def _penetration_ok(summary: dict, slave_factor: float = 1.0) -> None:
    by = summary["max_penetration_by_direction_m"]
    assert by["b2 nodes into b1"] < slave_factor * PEN_MAX, by
    assert summary["max_penetration_m"] < PEN_ANY, by


@functools.cache
def _short(which: str):
    """The short seed case with the models ``which``, on its own scheme (theta = 1/2 + dt_s /
    (4 tau) = 0.51, position law, mass redistribution) or, with a "-damped" suffix, on the damped one: Moreau's velocity
    law (restitution 0) without redistribution, theta = 0.55 (studies.grid.seed_scheme). The
    scenario's own models are the run tests/_short_case.py shares with other tests."""
    if which == "mvm":
        return short_run("scenario")[0]
    sc = validation.short_scenario()
    if which.endswith("-damped"):
        which = which.removesuffix("-damped")
        sc = seed_scheme(sc, "b2")
    models = {
        "full": None,
        "mvm": None,
        "mvm-seed": {"b1": STRIKER, "b2": ModelConfig(kind="mvm-seed", selection="1-3", modes=37)},
        "modal": {"b1": STRIKER, "b2": ModelConfig(kind="modal", modes=20)},
        "rigid-striker": {"b1": ModelConfig(kind="rigid"), "b2": TARGET_CB},
        "rigid-both": {"b1": ModelConfig(kind="rigid"), "b2": ModelConfig(kind="rigid")},
    }[which]
    if which == "full":
        sc = sc.with_overrides(model="full")
    elif models is not None:
        sc = sc.with_overrides(body_models=models)
    return run_scenario(sc)


@functools.cache
def _theory():
    return theory_histories(validation.short_scenario())


def _masses(run) -> tuple[float, float]:
    return tuple(float(b.inv.mass) for b in run.built.system.bodies)


def _impulse(run) -> float:
    """Exact contact impulse [N s]: the output force is the impulse over the interval ending at
    each output time, divided by its length."""
    res = run.result
    return float(np.sum(res.contact_force[1:] * np.diff(res.t)))


def _restitution(run) -> float:
    """Effective coefficient of restitution of the two free bodies: the impulse relative to the
    perfectly plastic one, e = J / (m1 m2 v0 / (m1 + m2)) - 1 (0 plastic, 1 elastic)."""
    m1, m2 = _masses(run)
    return _impulse(run) / (m1 * m2 * V0 / (m1 + m2)) - 1.0


def _ncc_below(a: np.ndarray, b: np.ndarray, cut_hz: float, dt_s: float) -> float:
    """Pearson r of two histories on the same output grid (dt_s) after an FFT low-pass at
    cut_hz (the histories start and end at rest: no window needed)."""
    n = min(len(a), len(b))
    keep = np.fft.rfftfreq(n, dt_s) <= cut_hz
    a, b = (np.fft.irfft(np.fft.rfft(x[:n]) * keep, n) for x in (a, b))
    return float(np.corrcoef(a, b)[0, 1])


def _check_sane(run, e_min: float = 0.99) -> None:
    """What every free two-body impact must satisfy, whatever the body models:
    - total linear momentum, as the steps converged (before the balance of their
      translational rows, which makes momentum_rel_error round-off by construction), within
      the validation table's bound (acceptance.MOMENTUM_CONVERGED_BOUND, 5e-9: the Newton
      rtol 1e-10 a step; measured 1.8e-10 to 6.9e-10 over 340-414 steps, 2.0e-9 with the
      rigid striker);
    - contact force never tensile, positive during the impact, released before t_end;
    - energy: the end value at most the initial and never above it by more than 1e-9 of it
      (the scenario's scheme, the position law at theta = 1/2 + dt_s / (4 tau), adds none: a
      closed pair does no work and nothing pushes a penetrated node out; it loses what theta
      - 1/2 = 0.01 damps, the end equilibrium of the massless nodes and the entry of pairs.
      Measured at the end: full FE -1.8e-4, MVM -1.8e-4, mvm-seed -3.1e-4, modal -4.4e-4,
      rigid striker -2.2e-4 (at theta = 1/2: -6.4e-6 to -2.9e-5); no rise. The damped scheme loses 0.04-0.1 % and is allowed a rise of 2e-3: the velocity
      law's penetration recovery, ~ theta beta F g per step, measured up to 8.3e-4 while it
      was uncapped; capped by each pair's closing speed (contact/pairs.py) it measured no rise
      on the rigid striker, -9.9e-4 at the end);
    - the impulse lies between the perfectly plastic and the perfectly elastic one, and near
      the elastic one: these Hertz contacts last 5-6 striker transits, so the rods come apart
      nearly free of vibration. 1D wave-Hertz: e = 0.99978; the 3D runs measured 0.9981
      (rigid striker) on the damped scheme, 0.9980 (mvm-seed, modal) to
      0.99956 (rigid striker) on the scenario's: e >= 0.99 with room for the unresolved modes;
      e <= 1 + 1e-6 (an impulse above the elastic one would create energy);
    - rebound direction: after the impact both move in +x and the target faster than the
      striker (m1 = 0.255 kg > m2 = 0.085 kg: the striker follows, slower)."""
    s, res = run.summary, run.result
    assert s["momentum_rel_error_converged"] < acceptance.MOMENTUM_CONVERGED_BOUND
    assert s["max_contact_force_interval_mean_N"] > 0.0
    # every LCP met its complementarity tolerance (a tensile impulse reads ~1) and every step
    # converged to the Newton tolerance
    assert s["lcp_residual_max"] <= 1e-8 and s["steps_on_roundoff_floor"] == 0
    assert s["contact_intervals_s"] and s["contact_intervals_s"][0][0] < 2e-6
    assert s["contact_intervals_s"][-1][1] < res.t[-1] - 10e-6
    E = res.total_energy
    rise = 1e-9 if s["contact_laws_add_no_energy"] else 2e-3
    assert E[-1] <= E[0] and E.max() <= E[0] * (1 + rise)
    e = _restitution(run)
    assert e_min <= e <= 1.0 + 1e-6, e
    m1, m2 = _masses(run)
    J = _impulse(run)
    v1, v2 = V0 - J / m1, J / m2  # centre-of-mass velocities after the impact
    assert 0.0 < v1 < v2
    # the frames (tied to end B) agree with the centre-of-mass velocities up to the rods'
    # residual vibration: within 5 % of v0
    assert abs(res.frame_v[-1, 1, 0] - v2) < 0.05 * V0


# --- 1. the short seed case ------------------------------------------------------------------


def test_short_full_fe_against_wave_hertz_theory():
    """Full FE vs 1D wave-Hertz on the short case (measured on the scenario's scheme: force NCC
    over the contact 0.99617 (0.99719 over the whole window), peak +3.78 %, impulse -0.93 %,
    contact duration +0.52 %, b2 free-end NCC 0.99984):
    - force NCC >= 0.995: the gap to 1 is the contact-patch discretisation (coarse vs refined
      mesh NCC 0.9973; refined vs theory 0.9994);
    - peak within 6 %: +2.8 % 1D/3D limit (refined mesh) + 1.0 % mesh, 1.5x margin;
    - impulse within 2 %: -1 % from the striker's mass (1D cylinder 3.5 % heavier);
    - contact duration within 5 %: the mesh moves it by 3 % (coarse +0.5 %, refined -2.6 %);
    - b2 free-end velocity NCC >= 0.999 (measured 0.99984; 0.99978 refined).
    Conservation: momentum 1e-9; no tensile force; penetration below 2 % of the peak Hertz
    approach (measured 2.0e-9 m vs 2.5e-7 m; the damped scheme 1.5e-7 m); energy error within
    5e-4 (measured -1.8e-4 on the scenario's theta = 0.51, which loses energy in proportion to
    theta - 1/2: -6.4e-6 at theta = 1/2; the damped scheme's theta = 0.55 lost 0.062 %, 0.037 %
    at h/2, which this bound refuses). The numbers above are the scenario's scheme; the damped
    one measured NCC 0.99719, peak +3.74 %."""
    run = _short("full")
    tt, ft, pt, _ = _theory()
    c = compare_runs(tt, ft, pt, *run.result.curves())
    assert c["ncc_force"] >= 0.995
    assert abs(c["peak_err"]) < 0.06
    assert abs(c["impulse_err"]) < 0.02
    assert abs(c["duration_err"]) < 0.05
    assert c["ncc_b2_free_end"] >= 0.999
    s = run.summary
    assert s["model"] == {"b1": "full", "b2": "full"} and s["dof"]["b2"] > 9000
    _penetration_ok(s)
    assert abs(s["energy_rel_change"]) < 5e-4
    _check_sane(run)


def test_short_mvm_matches_its_full_fe():
    """The scenario's MVM model (b1 full FE, b2 1-3 + 37 modes; 129 DOF: its 25 retained face
    nodes are massless, so their constraint modes split into the 75 nodal unit vectors and the
    static fields of 11 smooth patterns, reduction/basis.py MasslessStatics.PATCH) against its
    full FE on
    the short case: force NCC >= 1 - 5e-6 (the issue's target 0.999; measured 1 - 6.2e-7:
    the MVM reproduces its full FE's force to the step's error, NCC(h/2 vs h) 1 - 2e-7), peak,
    impulse and contact duration within 0.5 % (measured -0.033 %, -2e-4 %, +0.08 %: the
    step-halving change is 0.015-0.025 %, so 0.5 % is still far below the 1-3 % mesh error),
    b2 free-end velocity NCC >= 0.995 whole and >= 1 - 3e-4 below 50 kHz (measured 0.99955
    and 1 - 4.5e-5; on the damped scheme 0.99996 and 0.99999; at theta = 1/2, where nothing damps the
    content the 37-mode basis and the full mesh carry differently above 50 kHz, 0.99801 and
    0.99985)."""
    full, mvm = _short("full"), _short("mvm")
    assert mvm.summary["dof"]["b2"] == 3 * 25 + 11 + 37 + 6
    c = compare_runs(*full.result.curves(), *mvm.result.curves())
    assert c["ncc_force"] >= 1 - 5e-6
    for key in ("peak_err", "impulse_err", "duration_err"):
        assert abs(c[key]) < 0.005, (key, c[key])
    assert c["ncc_b2_free_end"] >= 0.995
    v_full, v_mvm = (run.result.curves()[2]["b2_free_end"] for run in (full, mvm))
    assert _ncc_below(v_full, v_mvm, 50e3, 2e-6) >= 1 - 3e-4
    _penetration_ok(mvm.summary)
    _check_sane(mvm)


# --- 2. body models in contact ---------------------------------------------------------------


def test_mvm_seed_body_in_contact():
    """b2 as seed eq. (4), diag(Psi_I, I_II) with the 1-3 region II and 37 modes of region I.
    Sane (see _check_sane; measured e = 0.9980) and it transfers the same momentum as the full
    FE (impulse within 0.5 %, measured -0.07 %), but it is much stiffer at the contact than the
    Craig-Bampton model with the same nodes and modes: region II is joined to region I only
    through fixed-interface modes, with no static (constraint) modes, so measured against the
    full FE: force NCC over the contact 0.7735 (0.836 over the whole window), peak +27.6 %,
    contact 20.3 % shorter (CB with the same nodes and modes: NCC 1 - 1e-6, peak -0.03 %).
    Required: NCC in [0.70, 0.85], peak +20 % to +35 %, contact 15 % to 25 % shorter: a
    regression to the CB form (peak and duration within 0.1 %) or a basis losing region II's
    coupling (stiffer still, as the modal body's +44 %) falls outside; the margins are the
    step and mesh changes of these numbers (a few percent of the peak)."""
    full, run = _short("full"), _short("mvm-seed")
    assert run.summary["model"]["b2"] == "mvm-seed"
    _check_sane(run)
    c = compare_runs(*full.result.curves(), *run.result.curves())
    assert abs(c["impulse_err"]) < 0.005
    assert 0.70 <= c["ncc_force"] <= 0.85
    assert 0.20 < c["peak_err"] < 0.35
    assert -0.25 < c["duration_err"] < -0.15
    # its stiffer contact field makes the contact nodes' impacts harder: penetration measured
    # 2.9e-7 m, 2.4 % of the peak Hertz approach; allowed 3 % (full FE: 1.5e-7 m within 2 %)
    _penetration_ok(run.summary, 1.5)


def test_modal_body_in_contact():
    """b2 as 20 free-interface modes of the end-B-supported rod (26 DOF): its end face cannot
    take the local Hertz indentation, so only the striker's side is compliant: vs full FE peak
    +44.0 %, contact 25.8 % shorter, force NCC over the contact 0.607 (0.711 over the whole
    window) (measured). What must hold: sane impact (measured e = 0.9980), the same momentum
    transfer as full FE (impulse within 0.5 %, measured -0.077 %), the contact of a rigid
    face on the striker's Hertz compliance: peak +35 % to +55 % and contact 20 % to 30 %
    shorter (a rigid face removes b2's share 0.58 of the Hertz compliance: E* x 2.38, and a
    Hertz impact's peak scales as E*^(2/5), its duration as E*^(-2/5): +41 % and -29 %; a
    face that indents, as full FE or MVM, reads within a few percent), and
    the free-end velocity following the wave (NCC >= 0.9, measured 0.945)."""
    full, run = _short("full"), _short("modal")
    assert run.summary["model"]["b2"] == "modal" and run.summary["dof"]["b2"] == 26
    _check_sane(run)
    c = compare_runs(*full.result.curves(), *run.result.curves())
    assert abs(c["impulse_err"]) < 0.005
    assert 0.35 < c["peak_err"] < 0.55
    assert -0.30 < c["duration_err"] < -0.20
    assert c["ncc_b2_free_end"] >= 0.9
    _penetration_ok(run.summary)


def _stiff(m: Material) -> Material:
    return Material(E=m.E * 1e4, nu=m.nu, rho=m.rho, name="rigid-limit")


def test_rigid_striker_against_rigid_limit_theory():
    """b1 rigid (6 DOF) onto b2 (CB 1-3 + 37). The 1D solution with the striker 1e4 times
    stiffer (same mass; its Hertz term (1 - nu^2)/E vanishes, c x 100) is the rigid-striker
    theory. On the scenario's scheme (theta = 0.51, position law, b2's contact nodes
    massless; the rigid striker has none) measured: force NCC 0.9953, peak +2.0 %, contact
    +1.8 %, impulse -0.94 % (the 1D striker's extra 3.5 % mass), e = 0.99956 (E x 100 gives
    the same to 0.3 %). Required: NCC >= 0.99, peak within 5 %, duration within 5 %, impulse
    within 2 % (as for the flexible short case, whose mesh error these share), and a sane
    impact. The ring b2 keeps after the separation: test_rigid_striker_ring_after_separation."""
    run = _short("rigid-striker")
    assert run.summary["dof"]["b1"] == 6
    _check_sane(run)
    r1, r2 = Rod1D.from_material(_stiff(BRASS), L, R), Rod1D.from_material(ALUMINIUM, L, R)
    th = two_rod_impact(
        r1,
        r2,
        V0,
        0.25e-3,
        ContactLaw.HERTZ,
        sphere_radius_m=R,
        dt=min(r1.round_trip_s, r2.round_trip_s) / 200,
    )
    c = compare_runs(th.t, th.contact_force, {}, *run.result.curves())
    assert c["ncc_force"] >= 0.99
    assert abs(c["peak_err"]) < 0.05
    assert abs(c["duration_err"]) < 0.05
    assert abs(c["impulse_err"]) < 0.02
    _penetration_ok(run.summary)


def _newton_restitution(run) -> float:
    """Newton's coefficient of restitution at the contact point of a single impact between two
    free rigid bodies, from Kelvin's theorem: an impulse J along the normal n changes the
    kinetic energy by J (u_N- + u_N+) / 2, so with u_N+ = -e u_N- the impact loses
    (1 - e) J |u_N-| / 2 (Glocker 2001, Set-Valued Force Laws, sec. 8.3; Brogliato,
    Nonsmooth Mechanics, 3rd ed., sec. 4.1). J and n are b2's momentum at the end (it starts
    at rest and only the contact acts on it), u_N- = -v0 n_x (no rotation before the impact),
    the loss that of the total energy (rigid bodies: kinetic only). Unlike _restitution, exact
    when the normal is tilted: the apex pair's normal is a facet normal of the faceted cap,
    1.7e-2 rad off the axis here, so the impulse turns the rods and the point-mass formula
    reads 1e-3 low at e = 0."""
    res = run.result
    p2 = res.body_momentum[-1, 1]
    J = float(np.linalg.norm(p2))
    closing = V0 * p2[0] / J
    E = res.total_energy
    return 1.0 - 2.0 * (E[0] - E[-1]) / (J * closing)


def _end_b_ring(run) -> float:
    """Standard deviation [m/s] of b2's end-B centre velocity over the last 120 us (65 us
    after the separation at 150 us onward), about its mean."""
    res = run.result
    v = res.probe_v[:, res.probe_names.index("b2_free_end"), 0]
    return float(v[res.t > res.t[-1] - 120e-6].std())


def test_rigid_striker_ring_after_separation():
    """The rigid striker's Craig-Bampton target rings after the separation on the scenario's
    scheme, a limit stated in docs/contact_law.md ("A rigid striker onto a Craig-Bampton
    target"). b2's end-B velocity about its mean over the last 120 us (_end_b_ring), measured:
    0.0100 m/s = 0.048 v0 on the scenario's scheme, 0.0019 on the damped one, 0.0019 for b2
    full FE struck on the scenario's scheme, 0.0060 for the scenario's own MVM pair (b1 MVM
    3-5 + 40). What rings is the top of the target's reduced spectrum (with 0.5-us outputs:
    330 kHz with 20 fixed-interface modes, 430 kHz with 37, with 60 the ring down to the full
    FE's level), which theta = 0.51 damps at a rate (theta - 1/2) omega^2 h / 2, ~2e4 / s,
    where theta = 0.55 damps 5 x faster. After the separation the steps are 2 us, which do
    not resolve it: by the free-flight theta (integrate/theta.py) the ring is 0.035 v0 at
    1/2 + h / (4 tau) = 0.54 (the rule of 2026-11-27..28), 0.048 at theta(dt_s) = 0.51 (before),
    0.062 at 1/2 + dt_s^2 / (4 tau h) = 0.5025 (since 2026-11-29: the resolved waves no
    longer damped 16 x faster than at dt_s, the seed window's energy -1.9e-4 for -1.7e-3;
    what the 2 us step does not resolve decays at 1 / (200 us) instead of 1 / tau).
    Required: the scenario's scheme below 0.075 v0 (the limit as measured, 20 % of room: it
    must not grow) and the damped one below 0.015 v0, twice the full FE's (the ring is the
    reduced model's on this scheme, not the contact's)."""
    assert _end_b_ring(_short("rigid-striker")) < 0.075 * V0
    assert _end_b_ring(_short("rigid-striker-damped")) < 0.015 * V0


def test_two_rigid_bodies_impact_conserves_momentum_and_loses_energy():
    """Both rods rigid, on the damped scheme (velocity law, theta = 0.55; the scenario's own
    scheme gives it e = (1 - theta) / theta: test_two_rigid_bodies_rebound_with_the_schemes_restitution):
    one impulse at t = 0 brings the contact point to rest (Newton e = 0),
    the exact outcome is the plastic impact, v = m1 v0 / (m1 + m2), losing m2 / (m1 + m2) =
    25.0 % of the energy. What must hold whatever the stabilisation: momentum as converged
    to 2e-10 (measured 3.0e-11 over 500 steps), the impulse between plastic and elastic (the
    point-mass formula of _restitution reads it -9.7e-4 below the plastic one: the impulse
    also turns the rods, as on the scheme's own rebound; bound -2e-3), the energy loss within 1 % of the plastic one
    (measured 24.95 %: the impulse turns the rods, test_two_rigid_bodies_impact_is_plastic),
    one impact: the first step carries the impulse, and what the bodies then exchange while
    they stay touching (their contact points at rest relative to each other, the rods
    turning) is round-off, below 1e-6 of it (measured 3e-7, 1e-11 N s a step)."""
    run = _short("rigid-both-damped")
    s = run.summary
    m1, m2 = _masses(run)
    assert s["momentum_rel_error_converged"] < 2e-10 and s["lcp_residual_max"] <= 1e-8
    assert -2e-3 <= _restitution(run) <= 1.0
    assert abs(-s["energy_rel_change"] - m2 / (m1 + m2)) < 0.01
    steps = run.result.steps
    later = np.asarray(steps.t_s) > 2 * 0.5e-6
    impulses = np.asarray(steps.contact_impulse_Ns)
    assert s["contact_intervals_s"][0][1] <= 2 * 2e-6
    assert impulses[later].sum() < 1e-6 * impulses.sum()


def test_two_rigid_bodies_impact_is_plastic():
    """Moreau's impact law (velocity law, restitution 0) between two rigid bodies on the damped
    scheme (theta = 0.55): Newton's e at the contact point (_newton_restitution) is 0. The
    step that closes the pair ends with it at rest and inside by h (1 - theta) v0 = 47 nm
    (Moreau-Jean's position update); the penetration recovery (contact/pairs.py beta = 0.2)
    is capped by the pair's closing speed, 0 from then on, so it does not turn that
    penetration into a separation velocity beta (1 - theta) v0 (measured before the cap:
    e = 0.089, separation 0.0186 m/s). Required |e| < 2e-6 (measured 2.9e-7, 6e-8 m/s of
    the 0.21 m/s closing speed; the issue's bound is 1e-3); the penetration held at that of the
    closing step, h (1 - theta) v0, within 2 % for b2's constrained nodes (4.7e-8 m
    measured), while b1's apex node, not constrained, sits inside b2's flat facets as the rods
    turn (1.06e-7 m measured after 250 us, within PEN_MAX)."""
    run = _short("rigid-both-damped")
    e = _newton_restitution(run)
    assert abs(e) < 2e-6, e
    by = run.summary["max_penetration_by_direction_m"]
    assert by["b2 nodes into b1"] <= 1.02 * 0.5e-6 * (1 - 0.55) * V0, by
    assert run.summary["max_penetration_m"] < PEN_MAX, by


def test_two_rigid_bodies_rebound_with_the_schemes_restitution():
    """Both rods rigid on the scenario's own scheme: the position law holds the gap at the end
    of the step, g + h (theta u_N+ + (1 - theta) u_N-) >= 0, so a rigid pair closing at g = 0
    leaves with u_N+ = -((1 - theta) / theta) u_N-: Newton's restitution e = (1 - theta) /
    theta = 0.9608 at theta = 0.51 (1 at theta = 1/2; rigid bodies have no contact nodes to
    make massless, and the scheme's restitution is all a rigid impact gets). Exact outcome:
    v1 = (m1 - e m2) v0 / (m1 + m2), v2 = (1 + e) m1 v0 / (m1 + m2), the energy lost
    (1 - e^2) m2 / (m1 + m2) of the start (the relative motion's share). Required: momentum as
    converged to 2e-10 (measured 2.1e-11 over 137 steps); the restitution from the impulse within 5e-3 of (1 - theta) / theta (measured 0.9589
    against 0.9608: the apex pair's normal is that of a facet of the faceted cap, tilted by
    about a facet over the cap radius, so the impulse also turns the rods and the point-mass
    formula of _restitution reads it 0.2 % short, as at theta = 1/2: 0.9981); the energy lost
    that of e = (1 - theta) / theta to 1e-4 of the start, 0.5 % of the loss (measured 1.9187e-2
    against 1.9211e-2: the turning again); one short contact."""
    run = _short("rigid-both")
    s = run.summary
    theta = run.built.grid.theta
    assert s["momentum_rel_error_converged"] < 2e-10 and s["lcp_residual_max"] <= 1e-8
    e = _restitution(run)
    assert abs(e - (1 - theta) / theta) < 5e-3
    m1, m2 = _masses(run)
    e_scheme = (1 - theta) / theta
    assert abs(-s["energy_rel_change"] - (1 - e_scheme**2) * m2 / (m1 + m2)) < 1e-4
    assert len(s["contact_intervals_s"]) == 1
    assert s["contact_intervals_s"][0][1] <= 2 * 2e-6
