"""Onset of yield of a rigid sphere striking a free elastic block: how close the FE field comes
to Hertz's subsurface von Mises maximum, and what sets the gap (issue 37, "onset of yield at
the Hertz speed where p0 = 1.6 Y, within 5 %"; tests/test_plastic_dynamics.py,
tests/test_yield_onset.py).

    python benchmarks/yield_onset.py OUT [--cases base,cap,...] [--plastic CASE:0.95,1.05]

The case is the tests' (tests/test_plastic_dynamics.py's module doc): sphere R 10 mm, rigid,
250 kg/m^3; block 10 x 10 x 5 mm tet10, E 70 GPa, nu 0.33, rho 2700; Y 2.35 GPa. Each case
runs the block elastic at Hertz's yield speed v_y (theory.hertz_yield: p0 = 1.649 Y at
nu = 0.33, where Hertz's subsurface von Mises maximum is Y), through the deepest approach,
and measures:

- the peak contact force against Hertz's (quasi-static Hertz impact with the recoil of the
  free block; Johnson 1985, eq. 11.24), F_FE / F_H;
- the largest von Mises stress at the block's integration points over the outputs within 3
  of the peak force, over Y (= over Hertz's maximum at v_y), and where it is (depth and
  distance from the axis over a);
- the same stress over Hertz's maximum at the FE's own peak force, Y (F_FE / F_H)^(1/3): the
  field's error alone, the force's share taken out (p0 grows as F^(1/3), Johnson eq. 4.23);
- the mesh's own onset speed over Hertz's, (Y / sigma_max)^(5/2): stresses of a Hertz impact
  grow as v^(2/5).

Cases (CASES below): the block's fine-zone element size h (elements per contact radius a/h,
a = 0.77 mm) and its radius; the sphere's cap (the committed sphere_r10_cap.msh, 0.1 mm
facets within 0.6 mm of its pole, or a cap written here with gmsh: facet size within a
radius); the step; the block's size (a thicker and wider block, for the finite free block);
the contact pairing (the block's top nodes slaves on the sphere's facets, or the reverse).

--plastic CASE:s1,s2 runs that case's mesh plastic (elastic-perfectly plastic, Y) at s v_y
and reports whether any point yields, the number of yielding points and the peak
equivalent plastic strain.

Writes OUT/yield_onset.json (one row per run) and prints the table; each run's CPU time
(process time) is in its row. One run after another: the machine is shared. Each row keeps its
provenance stamp (runs.provenance.script_stamp of this script and plastic_restitution.py,
its case and speed: code, libraries with scikit-fem and gmsh); rows are appended to an
existing record only if every row in it is stamped by this code (else one line and exit:
rows of two code versions are not one table).
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from plastic_restitution import scenario as restitution_scenario

from flexmvm.assembly.build import build_scenario
from flexmvm.integrate.driver import simulate
from flexmvm.integrate.theta import theta_for_damping_time
from flexmvm.mesh.gmsh_session import Refinement
from flexmvm.mesh.io import read_mesh
from flexmvm.mesh.parts import block, sphere
from flexmvm.mesh.quality import mesh_volume
from flexmvm.plasticity.body import PlasticBody
from flexmvm.plasticity.material import J2Plasticity
from flexmvm.plasticity.return_mapping import von_mises
from flexmvm.runs.provenance import script_stamp, script_stamp_mismatch
from flexmvm.runs.showcases.hertz_block import SPHERE_BLOCK
from flexmvm.scenarios.load import scenario_from_dict
from flexmvm.theory.hertz import hertz_impact
from flexmvm.theory.hertz_yield import yield_onset

#: The scripts a row's numbers depend on (its provenance stamp).
SCRIPTS = (Path(__file__), Path(__file__).with_name("plastic_restitution.py"))
SPHERE = SPHERE_BLOCK.parent / "meshes" / "sphere_r10_cap.msh"
R = 0.010  # sphere radius [m]
E, NU, RHO, RHO_BALL, Y = 70e9, 0.33, 2700.0, 250.0, 2.35e9
E_STAR = E / (1.0 - NU**2)  # rigid sphere: the block's plane-strain modulus [Pa]
HF_DAMPING_TIME_S = 12.5e-6  # theta(h) as tests/test_plastic_dynamics.py


@dataclass(frozen=True)
class Case:
    """One elastic run: block fine size and radius [m], block size lx = ly, lz [m], the cap
    (None: the committed sphere; else (facet size, radius) [m] at the pole), step dt [s], and
    the contact pairing (default: the block's top nodes slaves on the sphere's facets)."""

    fine_m: float
    radius_m: float
    lx_m: float = 10e-3
    lz_m: float = 5e-3
    cap: tuple[float, float] | None = None
    dt_s: float = 0.5e-6
    sphere_slave: bool = False  # the sphere's cap nodes as slaves on the block's top faces


CASES = {
    "base": Case(0.3e-3, 0.8e-3),  # the tests' block (2.6 per a)
    "base_dt": Case(0.3e-3, 0.8e-3, dt_s=0.25e-6),
    "base_wide": Case(0.3e-3, 1.6e-3),  # the fine zone to 2 a
    "base_cap": Case(0.3e-3, 0.8e-3, cap=(0.05e-3, 1.5e-3)),
    "base_big": Case(0.3e-3, 0.8e-3, lx_m=20e-3, lz_m=10e-3),
    "h20": Case(0.2e-3, 1.2e-3),  # 3.85 per a
    "h20_cap": Case(0.2e-3, 1.2e-3, cap=(0.05e-3, 1.5e-3)),
    "h14": Case(0.14e-3, 1.0e-3),  # 5.5 per a
    "h14_cap": Case(0.14e-3, 1.0e-3, cap=(0.05e-3, 1.5e-3)),
    "h20_big": Case(0.2e-3, 1.2e-3, lx_m=20e-3, lz_m=10e-3),
    "h20_big_cap": Case(0.2e-3, 1.2e-3, lx_m=20e-3, lz_m=10e-3, cap=(0.05e-3, 1.5e-3)),
    "h20_big_swap": Case(0.2e-3, 1.2e-3, lx_m=20e-3, lz_m=10e-3, sphere_slave=True),
    "h20_big_dt": Case(0.2e-3, 1.2e-3, lx_m=20e-3, lz_m=10e-3, dt_s=0.25e-6),
    "h14_big": Case(0.14e-3, 1.0e-3, lx_m=20e-3, lz_m=10e-3),
    "h20_dt": Case(0.2e-3, 1.2e-3, dt_s=0.25e-6),
    "h10": Case(0.10e-3, 0.9e-3),  # 7.7 per a
}


def block_mesh(out: Path, case: Case) -> Path:
    name = f"block_{case.lx_m * 1e3:.0f}x{case.lz_m * 1e3:.0f}_{case.fine_m * 1e6:.0f}um_"
    path = out / f"{name}{case.radius_m * 1e6:.0f}um.msh"
    if not path.exists():
        refine = Refinement((0, 0, 0), case.fine_m, case.radius_m, 2e-3)
        block(path, case.lx_m, case.lx_m, case.lz_m, 2e-3, order=2, refine=refine)
    return path


def cap_mesh(out: Path, case: Case) -> Path:
    """The committed sphere, or a rigid sphere (tet4) with facets cap[0] within cap[1] of its
    -z pole, growing to 2.5 mm over 6 mm (as mesh.parts.hertz_sphere_part)."""
    if case.cap is None:
        return SPHERE
    size, radius = case.cap
    path = out / f"sphere_cap_{size * 1e6:.0f}um_{radius * 1e6:.0f}um.msh"
    if not path.exists():
        sphere(path, R, 2.5e-3, refine=Refinement((0.0, 0.0, -R), size, radius, 6e-3))
    return path


def scenario(mesh: Path, ball: Path, v: float, y_pa, t_end: float, dt: float) -> dict:
    """The sphere at v [m/s] onto the free block (elastic if y_pa is None), as a dict: the
    restitution study's scenario (plastic_restitution.scenario) with this study's ball."""
    return restitution_scenario(mesh, v, y_pa, RHO_BALL, t_end, dt, ball, "yield_onset")


def paired(data: dict, case: Case) -> dict:
    """The scenario with the case's contact pairing."""
    if case.sphere_slave:
        data["contacts"] = [{"slave": "ball.front", "master": "block.top", "law": "position"}]
    return data


def hertz_at(mesh: Path, ball: Path, v: float):
    m_ball = RHO_BALL * mesh_volume(read_mesh(ball))
    return hertz_impact(R, v, E_STAR, m_ball, RHO * mesh_volume(read_mesh(mesh)))


def yield_speed(mesh: Path, ball: Path) -> float:
    """Hertz's v_y [m/s]: the impact's deepest approach (growing as v^(4/5)) reaches the
    approach of first yield (theory.hertz_yield)."""
    return (yield_onset(Y, E_STAR, R, NU).delta_m / hertz_at(mesh, ball, 1.0).delta_max_m) ** 1.25


def peak_stress(built, res, theta: float) -> tuple[float, float, np.ndarray]:
    """Largest elastic von Mises stress [Pa] at the block's integration points over the
    outputs within 3 of the peak force, at the step ends and at the step midpoints
    q_m = q + theta (q+ - q) (where a plastic run returns: plastic_bodies), and the
    midpoint peak's undeformed position (3,) [m]."""
    info, body = built.info[1], built.system.bodies[1]
    elastic = PlasticBody.build(info.mesh, info.material, J2Plasticity(1e30))
    state = elastic.virgin_state()
    q = res.q[1]
    k0 = int(np.argmax(res.contact_force))
    ends, mids, where = 0.0, 0.0, -1
    for k in range(max(k0 - 3, 1), min(k0 + 4, len(res.t))):
        ends = max(ends, float(von_mises(elastic.respond(body.psi @ q[k], state).stress).max()))
        q_m = q[k - 1] + theta * (q[k] - q[k - 1])
        vm = von_mises(elastic.respond(body.psi @ q_m, state).stress)
        if vm.max() > mids:
            mids, where = float(vm.max()), int(np.argmax(vm))
    return ends, mids, elastic.point_coordinates()[where]


def elastic_row(out: Path, name: str, case: Case) -> dict:
    mesh, ball = block_mesh(out, case), cap_mesh(out, case)
    v_y = yield_speed(mesh, ball)
    hz = hertz_at(mesh, ball, v_y)
    onset = yield_onset(Y, E_STAR, R, NU)
    t0 = time.process_time()
    built = build_scenario(
        scenario_from_dict(
            paired(scenario(mesh, ball, v_y, None, 0.6 * hz.duration_s, case.dt_s), case)
        )
    )
    res = simulate(built.system, built.states, built.grid)
    cpu_run = time.process_time() - t0
    theta = theta_for_damping_time(case.dt_s, HF_DAMPING_TIME_S)
    ends, sigma, point = peak_stress(built, res, theta)
    force = float(res.contact_force.max())
    ratio = sigma / Y  # Hertz's maximum at v_y is Y
    field = sigma / (Y * (force / hz.force_max_n) ** (1.0 / 3.0))
    return {
        "case": name,
        **asdict(case),
        "elements_per_a": onset.radius_m / case.fine_m,
        "n_dof_block": built.system.bodies[1].psi.shape[0],
        "v_y_mps": v_y,
        "force_ratio": force / hz.force_max_n,
        "sigma_ratio_step_ends": ends / Y,
        "v_y_mesh_ratio_step_ends": (ends / Y) ** -2.5,
        "sigma_ratio": ratio,
        "sigma_ratio_at_fe_force": field,
        "peak_depth_over_a": float(-point[2] / onset.radius_m),
        "peak_off_axis_over_a": float(np.hypot(point[0], point[1]) / onset.radius_m),
        "v_y_mesh_ratio": ratio**-2.5,
        "steps_not_converged": int(res.steps_on_roundoff_floor),
        "cpu_run_s": cpu_run,
        "cpu_total_s": time.process_time() - t0,
    }


def plastic_row(out: Path, name: str, case: Case, s: float) -> dict:
    mesh, ball = block_mesh(out, case), cap_mesh(out, case)
    v_y = yield_speed(mesh, ball)
    t_end = 0.6 * hertz_at(mesh, ball, v_y).duration_s
    t0 = time.process_time()
    data = paired(scenario(mesh, ball, s * v_y, Y, t_end, case.dt_s), case)
    res = simulate(*_built(data))
    report = res.plastic["block"]
    alpha = report.point_equivalent_plastic_strain
    return {
        "case": name,
        "v_over_vy": s,
        "yielded": bool(alpha.max() > 0.0),
        "yielding_points": int(np.count_nonzero(alpha)),
        "peak_alpha": float(alpha.max()),
        "cells_returned": int(report.n_set_cells),
        "steps_not_converged": int(res.steps_on_roundoff_floor),
        "cpu_s": time.process_time() - t0,
    }


def _built(data: dict):
    built = build_scenario(scenario_from_dict(data))
    return built.system, built.states, built.grid


COLUMNS = [
    ("case", "case", "{}"),
    ("a/h", "elements_per_a", "{:.2f}"),
    ("DOF", "n_dof_block", "{}"),
    ("F/F_H", "force_ratio", "{:.4f}"),
    ("ends s/s_H", "sigma_ratio_step_ends", "{:.4f}"),
    ("s/s_H", "sigma_ratio", "{:.4f}"),
    ("s/s_H(F)", "sigma_ratio_at_fe_force", "{:.4f}"),
    ("z/a", "peak_depth_over_a", "{:.2f}"),
    ("r/a", "peak_off_axis_over_a", "{:.2f}"),
    ("vy_mesh/vy", "v_y_mesh_ratio", "{:.3f}"),
    ("cpu s", "cpu_total_s", "{:.0f}"),
]


def row_stamp(name: str, v_over_vy: float | None) -> dict:
    """A row's provenance stamp: SCRIPTS, the case's settings and the plastic run's speed
    (None: the elastic run)."""
    return script_stamp(SCRIPTS, {"case": name, **asdict(CASES[name]), "v_over_vy": v_over_vy})


def stamped_rows(record: Path) -> list[dict]:
    """The rows of an existing record, [] if there is none; SystemExit with one line if a
    row is not stamped by this code (module doc)."""
    rows = json.loads(record.read_text()) if record.exists() else []
    for k, row in enumerate(rows):
        why = script_stamp_mismatch(row.get("provenance"), SCRIPTS)
        if why is not None:
            raise SystemExit(
                f"{record}: row {k} ({row.get('case')}) was {why}: write to another OUT"
            )
    return rows


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--cases", default="base,h20,h14", help="names of CASES, comma separated")
    ap.add_argument("--plastic", default=None, help="CASE:s1,s2 (v / v_y)")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    record = args.out / "yield_onset.json"
    rows = stamped_rows(record)
    names = [] if args.plastic else args.cases.split(",")
    for name in names:
        rows.append(elastic_row(args.out, name, CASES[name]))
        rows[-1]["provenance"] = row_stamp(name, None)
        print(json.dumps(rows[-1]), flush=True)
        record.write_text(json.dumps(rows, indent=1))
    if args.plastic:
        name, speeds = args.plastic.split(":")
        for s in speeds.split(","):
            rows.append(plastic_row(args.out, name, CASES[name], float(s)))
            rows[-1]["provenance"] = row_stamp(name, float(s))
            print(json.dumps(rows[-1]), flush=True)
            record.write_text(json.dumps(rows, indent=1))
    print("  ".join(f"{h:>10}" for h, _, _ in COLUMNS))
    for r in rows:
        if "sigma_ratio" in r:
            print("  ".join(f"{f.format(r[k]):>10}" for _, k, f in COLUMNS))


if __name__ == "__main__":
    main()
