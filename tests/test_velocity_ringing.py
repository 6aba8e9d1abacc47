"""Pin velocities of the slider-crank free of step-to-step ringing (issue 51, item 9): the
end-of-step velocity projection onto the joints' velocity rows
(integrate.moreau_jean.velocity_projection) against the rigid mechanism's closed-form kinematics and
MVM against full FE.

Before the projection the position-level joint rows left v+ = (v_m - (1 - theta) v-) / theta
along them: an alternation at the step's Nyquist frequency, fed by the turning mechanism and
damped only by theta - 1/2 = 0.005 (docs/notes/2026-11-29-velocity-ringing.md).
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

import flexmvm as fm

pytest.importorskip("gmsh")

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
R_M, L_M, OMEGA = 0.15, 0.30, 150.0  # crank, rod [m], crank speed [rad/s]
OFFSET_M = -0.004  # the pin probes sit on the rod's -y edge, 4 mm off its axis
T_END = 0.013  # the ringing peaked at ~10 ms before the projection

pytestmark = pytest.mark.filterwarnings("ignore::flexmvm.assembly.cost.ReducedCostWarning")


def _rigid_point(phi: np.ndarray, s: float, d: float) -> np.ndarray:
    """(x, y) [m] of the rigid rod's point at s along the chord from pin A and d along its
    normal z x u, crank angle phi: A = r (cos phi, sin phi), B = (r cos phi +
    sqrt(l^2 - r^2 sin^2 phi), 0)."""
    a = np.stack([R_M * np.cos(phi), R_M * np.sin(phi)], -1)
    b = np.stack([R_M * np.cos(phi) + np.sqrt(L_M**2 - (R_M * np.sin(phi)) ** 2), 0 * phi], -1)
    u = (b - a) / L_M
    return a + s * u + d * np.stack([-u[..., 1], u[..., 0]], -1)


def _rigid_velocity(t: np.ndarray, s: float) -> np.ndarray:
    """d/dt of _rigid_point at phi = omega t, by a central difference of 1e-7 s (error
    ~1e-9 m/s against velocities of ~20 m/s)."""
    e = 1.0e-7
    return (
        _rigid_point(OMEGA * (t + e), s, OFFSET_M) - _rigid_point(OMEGA * (t - e), s, OFFSET_M)
    ) / (2 * e)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Full FE and MVM of the shipped slider-crank on the coarse rod (8 mm tet10, 4,860 DOF),
    h = 100 us, theta(h) = 0.505 as shipped, over 13 ms."""
    from flexmvm.mesh import link

    mesh = link.slider_crank_rod(tmp_path_factory.mktemp("ringing") / "rod_8mm.msh", 8.0e-3)
    out = {}
    for kind in ("full", "mvm"):
        with open(SCENARIOS / "slider_crank.toml", "rb") as f:
            d = tomllib.load(f)
        for b in d["bodies"]:
            b["mesh_file"] = str(SCENARIOS / b["mesh_file"])
        d["bodies"][1]["mesh_file"] = str(mesh)
        d["bodies"][1]["model"]["kind"] = kind
        d["time"].update(t_end_s=T_END, dt_s=1.0e-4, output_dt_s=1.0e-4)
        d.pop("compare", None)
        out[kind] = fm.run(fm.scenario_from_dict(d))
    return out


def test_pin_velocities_follow_the_rigid_kinematics_without_ringing(runs):
    """The pin probes' in-plane velocities from 3 ms on (after the start's transient):

    - against the rigid slider-crank's closed-form velocity at the probe point, within
      0.3 m/s of a ~20 m/s signal (what the rod's elastic motion adds there: its end faces turn
      with the bending slope, ~24 rad/s at the 1.8 mm, 203 Hz deflection, times the probe's
      4 mm offset ~ 0.1 m/s, and its axial vibration; measured 0.04 (pin A), 0.20 (pin B) m/s
      full FE; before the projection 0.36 and 0.57);
    - the step-to-step alternation, RMS of the second difference / 4 (the amplitude of a +-a
      sawtooth), below 0.05 m/s (measured 0.003 and 0.032: the rest is the rod's 8.4 kHz axial
      vibration, 0.84 of the step's Nyquist frequency; before 0.25 and 0.25 full FE);
    - MVM against full FE within 0.15 m/s at every sample (measured 0.065; before 0.50).

    ~16 s at load ~2 (mesh, two setups, 130 steps of each rod)."""
    t = runs["full"].t
    w = t >= 3.0e-3
    for kind, run in runs.items():
        assert run.summary["steps_on_roundoff_floor"] == 0
        assert run.result.max_joint_drift <= 1e-9  # positions untouched (measured ~5e-14)
        for name, s in (("pin_a", 0.0), ("pin_b", L_M)):
            v = run.probe(name).v[w, :2]
            assert np.abs(v - _rigid_velocity(t[w], s)).max() <= 0.3, (kind, name)
            alternation = np.sqrt(np.mean(np.diff(v, 2, axis=0) ** 2)) / 4
            assert alternation <= 0.05, (kind, name, alternation)
    for name in ("pin_a", "pin_b"):
        diff = runs["mvm"].probe(name).v - runs["full"].probe(name).v
        assert np.abs(diff).max() <= 0.15, name
