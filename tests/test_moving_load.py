"""The moving load on a simply supported beam (issue 53, item 3, first check): Fryba's
moving-force series (flexmvm.theory.moving_load) against its static limit and its closed form
at the critical speed, the HEX27 beam's node sets (flexmvm.mesh.box27), and the shipped
scenario (scenarios/moving_load.toml: a rigid slider pressed by 2 N, driven at 60 m/s = 0.65
c_cr along an aluminium beam 1000 x 20 x 20 mm, full FE) against the series.

The fine check (a finer mesh, a slow speed, step and mesh convergence, what separates the 3D
beam from Euler-Bernoulli) is benchmarks/moving_load_check.py; its output is in
docs/notes/2026-11-29-moving-load.md.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

import flexmvm as fm
from flexmvm.errors import InputError
from flexmvm.mesh.box27 import hex27_box_beam
from flexmvm.metrics.ncc import ncc
from flexmvm.theory.moving_load import MovingForce, static_deflection

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
E, RHO, B = 70.0e9, 2700.0, 0.02  # the scenario's beam: aluminium, 20 x 20 mm
EI, MU = E * B**4 / 12.0, RHO * B * B


def test_static_limit_is_the_static_deflection_under_the_load():
    """c = 1e-4 c_cr: the deflection under the force, at five positions a = c t, against
    P a b (L^2 - a^2 - b^2) / (6 E I L) to 3e-4 (measured 1.5e-4 at 200 modes: the free
    vibration the entry leaves is of order alpha = 1e-4 of the static deflection)."""
    ccr = MovingForce(1.0, EI, MU, 2.0, 1.0).critical_speed_mps
    m = MovingForce(1.0, EI, MU, 2.0, 1e-4 * ccr)
    t = m.crossing_time_s * np.array([0.1, 0.3, 0.5, 0.7, 0.9])
    a = m.speed_mps * t
    w = np.array([m.deflection(x, [s], n_modes=200)[0] for x, s in zip(a, t, strict=True)])
    np.testing.assert_allclose(w, static_deflection(a, a, 1.0, 2.0, EI), rtol=3e-4)
    assert static_deflection(0.5, 0.5, 1.0, 2.0, EI) == pytest.approx(m.midspan_static_m)


def test_critical_speed_midspan_is_48_over_pi_cubed():
    """alpha = 1: the mid-span deflection when the force leaves the span is 48 / pi^3 =
    1.5481 of P L^3 / (48 E I) (module doc: mode 1 at resonance, every other mode zero there;
    Fryba 1999, sec. 1.3, the critical speed); to 1e-6 (the series' round-off; measured 1e-9),
    and 1e-7 above c_cr the same to 1e-6 (the resonant limit is continuous)."""
    for factor in (1.0, 1.0 + 1e-7):
        m = MovingForce(1.0, EI, MU, 2.0, 1.0)
        m = MovingForce(1.0, EI, MU, 2.0, factor * m.critical_speed_mps)
        w = m.deflection(0.5, [m.crossing_time_s])[0] / m.midspan_static_m
        assert w == pytest.approx(48.0 / math.pi**3, rel=1e-6)


def test_shear_adds_the_timoshenko_static_deflection():
    """With shear (kappa G A given) the slow mid-span deflection is w0 + P L / (4 kappa G A)
    to 1e-4 (the sine series of the shear term converges as 1/j^2: 400 modes), and its first
    frequency lies below Euler-Bernoulli's by the Timoshenko beam's ~ (1 + E/(kappa G)) (pi
    r / L)^2 / 2 (r the radius of gyration: 3.6e-4 here) to 10 %."""
    G, kappa = E / 2.66, 10.0 * 1.33 / (12.0 + 11.0 * 0.33)
    kw = {"kappa_G_pa": kappa * G, "area_m2": B * B, "rho_I_kg_m": RHO * B**4 / 12.0}
    m = MovingForce(1.0, EI, MU, 2.0, 1e-5, **kw)
    w = m.deflection(0.5, [0.5 * m.crossing_time_s], n_modes=400)[0]
    shear = 2.0 * 1.0 / (4.0 * kappa * G * B * B)
    assert w == pytest.approx(m.midspan_static_m + shear, rel=1e-4)
    eb = MovingForce(1.0, EI, MU, 2.0, 1e-5).modes(1)[2][0]
    drop = 1.0 - m.modes(1)[2][0] / eb
    expected = 0.5 * (1.0 + E / (kappa * G)) * (math.pi * B / math.sqrt(12.0)) ** 2
    assert drop == pytest.approx(expected, rel=0.1)


def test_moving_force_input_errors():
    """A non-positive speed, or shear half given: one InputError line."""
    with pytest.raises(InputError, match="speed_mps: expected a finite number > 0"):
        MovingForce(1.0, EI, MU, 2.0, 0.0)
    with pytest.raises(InputError, match="give both kappa_G_pa and area_m2"):
        MovingForce(1.0, EI, MU, 2.0, 1.0, kappa_G_pa=1e9)


def test_box_beam_sets():
    """The HEX27 beam's node sets where the supports and the probe need them; an odd cell
    count along x (no mid-span node) is refused in one line."""
    m = hex27_box_beam(1.0, 0.02, 0.02, (4, 1, 1))
    x = m.nodes
    assert np.allclose(x[m.node_set("mid_axis")], [[0.5, 0.0, -0.01]])
    assert np.allclose(x[m.node_set("end_a_axis")][:, [0, 2]], [0.0, -0.01])
    assert len(m.node_set("end_b")) == 9 and np.allclose(x[m.node_set("end_b"), 0], 1.0)
    assert np.allclose(x[m.node_set("top"), 2], 0.0)
    with pytest.raises(InputError, match="even count along x"):
        hex27_box_beam(1.0, 0.02, 0.02, (3, 1, 1))


def _scenario(speed_mps: float, dt_s: float) -> fm.Scenario:
    """The shipped scenario with the slider driven at speed_mps [m/s] until x = 0.998 L."""
    with open(SCENARIOS / "moving_load.toml", "rb") as f:
        d = tomllib.load(f)
    for b in d["bodies"]:
        b["mesh_file"] = str(SCENARIOS / b["mesh_file"])
    d["time"].update(t_end_s=0.998 / speed_mps, dt_s=dt_s, output_dt_s=dt_s)
    d["bodies"][1]["placement"]["velocity_mps"] = [speed_mps, 0.0, 0.0]
    d["joints"][0]["velocity_mps"] = [speed_mps, 0.0, 0.0]
    return fm.scenario_from_dict(d)


@pytest.mark.parametrize(("speed", "dt"), [(60.0, 5e-5), (10.0, 2e-4)])
def test_slider_on_the_beam_against_fryba(speed, dt):
    """The shipped scenario (2 N on a rigid slider, the 2,187-DOF HEX27 beam, full FE) near
    the critical speed (60 m/s = 0.65 c_cr, its own 333 steps of 50 us) and slow (10 m/s =
    0.108 c_cr, 499 steps of 200 us): the mid-span deflection (the axis node) against the
    series, peak within 0.5 % (measured +0.093 % and -0.048 %: the 3D beam is 0.08 % more
    flexible than Euler-Bernoulli statically, its shear; the issue asks 2 %) and NCC >= 0.9995
    (measured 0.99997 and 0.99993; the issue asks 0.99). The contact carries the force: its
    mean is 2 N to 0.1 % (measured 2.0003 and 2.00000 N), no step unconverged, penetration
    below 1e-6 m (measured 3.5e-8 and 1.4e-8 m). Frictionless, the closed pairs held and
    following the slide (contact.held_pairs); the same to 1e-5 of the peak as with mu = 1e-6
    (pairs re-projected every step). Before the held pairs followed the slide the beam never
    bent (3e-15 m); with the velocity law the slider sank 3e-5 m, peak -5.8 %. Takes ~5 and
    ~9 s of CPU (after numba's compile)."""
    run = fm.run(_scenario(speed, dt))
    assert run.summary["status"] == "completed" and run.summary["steps_on_roundoff_floor"] == 0
    z = run.probe("mid_axis").x[:, 2]
    w = -(z - z[0])
    theory = MovingForce(1.0, EI, MU, 2.0, speed).deflection(0.5, run.t)
    assert w.max() == pytest.approx(theory.max(), rel=5e-3)
    assert ncc(run.t, theory, run.t, w) >= 0.9995
    assert run.contact_force[1:].mean() == pytest.approx(2.0, rel=1e-3)
    assert run.summary["max_penetration_m"] <= 1e-6


def test_frictionless_sliding_slider_bends_the_beam():
    """The scenario frictionless (mu = 0: the closed pairs held, contact.held_pairs) over the
    first half of the passage at 60 m/s (166 steps): the held pair follows the slide (it
    takes the scan's facet and weights, its gap kept, when its node reaches another facet or
    has moved 0.1 of its facet), so the beam bends as the series says: mid-span at half
    passage within 1 % (measured -0.61 %, as with re-projected pairs, mu = 1e-12: -0.61 %;
    the 3D beam against Euler-Bernoulli) and NCC >= 0.9995 (measured 0.999995). Before the
    fix the pair stayed on the facet over the support it closed on: 6e-16 m against 4.4e-5 m
    (a strict xfail recorded it). The contact's work (energy ledger) is the faceted top face's
    (a node crossing a kink of the bent face within a step), below 1e-2 of the energy the
    beam took: measured -3.52e-7 J of 7.41e-5 J (re-projected: -3.57e-7 J;
    docs/notes/2026-11-29-held-sliding.md). ~3 s of CPU."""
    sc = _scenario(60.0, 5e-5)
    data = sc.model_dump(mode="json", exclude_none=True)
    data["contacts"][0]["friction_coefficient"] = 0.0
    data["time"]["t_end_s"] = 0.5 / 60.0
    run = fm.run(fm.scenario_from_dict(data))
    z = run.probe("mid_axis").x[:, 2]
    w = -(z - z[0])
    theory = MovingForce(1.0, EI, MU, 2.0, 60.0).deflection(0.5, run.t)
    assert w[-1] == pytest.approx(theory[-1], rel=1e-2)
    assert ncc(run.t, theory, run.t, w) >= 0.9995
    energy = run.result.total_energy
    work = run.result.energy_ledger.contact[-1]
    assert abs(work) <= 1e-2 * (energy.max() - energy[0])
