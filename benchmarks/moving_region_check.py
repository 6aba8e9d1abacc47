"""The moving region on the moving-load beam (issue 53 items 1 and 3): scenarios/moving_load.toml
with the beam as a moving region (static modes switching: global modes + the windows' static
constraint modes, flexmvm.assembly.moving_region.run_moving) against full FE and Fryba's
series; per switch the jump of the beam's kinetic + strain energy and momentum, and the
contact force of the step after against the step before, beside full FE's same two steps.

    PYTHONPATH=src python benchmarks/moving_region_check.py [speed] [modes] [spacing] [half]
        [--fine]

prints a markdown report (docs/notes/2026-11-29-moving-region.md holds one); CPU seconds
(time.process_time) of the setup and of the run of each, one after the other in one process.
"""

from __future__ import annotations

import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

import flexmvm as fm
from flexmvm.assembly.build import build_scenario
from flexmvm.integrate.driver import simulate
from flexmvm.metrics.ncc import ncc
from flexmvm.theory.moving_load import MovingForce

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
EI, MU, P = 70.0e9 * 0.02**4 / 12.0, 2700.0 * 0.02 * 0.02, 2.0


def scenario(speed, dt, t_end=None, fine=None, kind="full", modes=10, spacing=0.0125, half=0.0375):
    """The shipped scenario at ``speed`` [m/s], step ``dt`` [s], until x = 0.998 L or t_end,
    the beam's model ``kind`` with ``modes`` and windows every ``spacing`` of ``half`` [m]."""
    with open(SCENARIOS / "moving_load.toml", "rb") as f:
        d = tomllib.load(f)
    for b in d["bodies"]:
        b["mesh_file"] = str(SCENARIOS / b["mesh_file"])
    if fine:
        d["bodies"][0]["mesh_file"] = str(fine)
    d["time"].update(t_end_s=t_end or 0.998 / speed, dt_s=dt, output_dt_s=dt)
    d["bodies"][1]["placement"]["velocity_mps"] = [speed, 0.0, 0.0]
    d["joints"][0]["velocity_mps"] = [speed, 0.0, 0.0]
    model = d["bodies"][0]["model"]
    model.update(kind=kind, modes=modes)
    model["moving"].update(spacing_m=spacing, half_width_m=half)
    return fm.scenario_from_dict(d)


def timed_run(sc):
    """(result, built, setup CPU [s], run CPU [s])."""
    c0 = time.process_time()
    built = build_scenario(sc)
    c1 = time.process_time()
    res = simulate(built.system, built.states, built.grid, built.probes, switches=built.switches)
    return res, built, c1 - c0, time.process_time() - c1


def deflection(res) -> np.ndarray:
    z = res.probe_x[:, res.probe_names.index("mid_axis"), 2]
    return -(z - z[0])


def step_force(res) -> tuple[np.ndarray, np.ndarray]:
    st = res.steps
    return st.t_s, st.contact_impulse_Ns / st.h_s


def switch_table(res, region, full) -> list[dict]:
    """Per switch: relative jumps of the beam's energy and momentum and the force ratios."""
    tm, fm_ = step_force(res)
    tf, ff = step_force(full)
    e_scale = max(max(sum(s.kinetic) + sum(s.strain) for s in region.switches), 1e-300)
    rows = []
    for s in region.switches:
        i = int(np.argmin(np.abs(tm - s.t_s)))
        j = int(np.argmin(np.abs(tf - s.t_s)))
        e0, e1 = s.kinetic[0] + s.strain[0], s.kinetic[1] + s.strain[1]
        p0, p1 = s.momentum
        h0, h1 = s.angular
        rows.append(
            {
                "t": s.t_s,
                "dE/E": (e1 - e0) / max(e0, 1e-300),
                "dE/Emax": (e1 - e0) / e_scale,
                "dp": float(np.abs(p1 - p0).max()),
                "p": float(np.abs(p0).max()),
                "dh": float(np.abs(h1 - h0).max()),
                "lam_ratio": fm_[i + 1] / fm_[i] if i + 1 < len(fm_) else np.nan,
                "full_ratio": ff[j + 1] / ff[j] if j + 1 < len(ff) else np.nan,
            }
        )
    return rows


def main(argv) -> None:
    fine = "--fine" in argv
    args = [a for a in argv if not a.startswith("--")]
    speed = float(args[0]) if args else 60.0
    modes = int(args[1]) if len(args) > 1 else 10
    spacing = float(args[2]) if len(args) > 2 else 0.0125
    half = float(args[3]) if len(args) > 3 else 0.0375
    mesh = None
    if fine:
        from flexmvm.mesh.box27 import write_box_beam

        mesh = write_box_beam(
            Path(tempfile.mkdtemp()) / "beam_fine.vtu", 1.0, 0.02, 0.02, (80, 2, 2)
        )
    fm.run(scenario(speed, 5e-5, 1e-3, mesh))  # numba's compile, the setup cache
    full, _, c_full_setup, c_full = timed_run(scenario(speed, 5e-5, None, mesh))
    res, built, c_mv_setup, c_mv = timed_run(
        scenario(speed, 5e-5, None, mesh, "mvm-moving", modes, spacing, half)
    )
    region = built.switches
    t = full.t
    series = MovingForce(1.0, EI, MU, P, speed).deflection(0.5, t)
    w_f, w_m = deflection(full), deflection(res)
    nq = region.body(0).nq
    print(f"speed {speed} m/s, {modes} modes, spacing {spacing} m, half width {half} m, nq {nq}")
    print(f"windows {len(region.windows.centres)}, switches {len(region.switches)}")
    print("| model | peak [m] | vs series | vs full | NCC series | NCC full | run CPU [s] |")
    print("|---|---|---|---|---|---|---|")
    for name, w, cpu in (("full", w_f, c_full), ("moving", w_m, c_mv)):
        print(
            f"| {name} | {w.max():.6g} | {w.max() / series.max() - 1:+.3%} | "
            f"{w.max() / w_f.max() - 1:+.3%} | {ncc(t, series, t, w):.6f} | "
            f"{ncc(t, w_f, t, w):.6f} | {cpu:.2f} |"
        )
    n_sw = max(len(region.switches), 1)
    print(
        f"CPU: full FE setup {c_full_setup:.2f} s, run {c_full:.2f} s ({full.n_steps} steps); "
        f"moving setup {c_mv_setup:.2f} s (windows), run {c_mv:.2f} s of which "
        f"switches {region.switch_cpu_s:.2f} s ({1e3 * region.switch_cpu_s / n_sw:.1f} ms "
        f"each); run ratio full / moving {c_full / c_mv:.2f}"
    )
    rows = switch_table(res, region, full)
    de = np.array([r["dE/E"] for r in rows])
    lam = np.array([r["lam_ratio"] for r in rows])
    lf = np.array([r["full_ratio"] for r in rows])
    dm = np.array([r["dE/Emax"] for r in rows])
    print(f"switch dE/E: min {de.min():+.3e} max {de.max():+.3e} median {np.median(de):+.3e}")
    print(f"switch dE / largest E at a switch: min {dm.min():+.3e} max {dm.max():+.3e}")
    print(
        f"switch |dp| max {max(r['dp'] for r in rows):.3e} (|p| up to "
        f"{max(r['p'] for r in rows):.3e}); |dh| max {max(r['dh'] for r in rows):.3e}"
    )
    print(
        f"force after/before at switches: moving {np.nanmin(lam):.5f}..{np.nanmax(lam):.5f}, "
        f"full same steps {np.nanmin(lf):.5f}..{np.nanmax(lf):.5f}, "
        f"|moving - full| max {np.nanmax(np.abs(lam - lf)):.5f}"
    )
    _, fm_f = step_force(res)
    print(
        f"mean contact force: moving {fm_f[1:].mean():.5f} N, full {step_force(full)[1][1:].mean():.5f} N"
    )


if __name__ == "__main__":
    main(sys.argv[1:])
