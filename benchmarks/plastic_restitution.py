"""Restitution of a rigid sphere striking a free elastic-perfectly plastic full-FE block,
against Thornton's model (C. Thornton, J. Appl. Mech. 64 (1997) 383-386; theory.thornton,
docs/plasticity.md "Restitution against Thornton (1997)").

    python benchmarks/plastic_restitution.py OUT [--speeds 1,2,5,10,30,100] [--quick]
    python benchmarks/plastic_restitution.py OUT --from-csv STUDY.csv

--from-csv runs nothing: it reads a stored study (the CSV and the JSON beside it), adds the
published-law columns below to its rows and redraws the figure; the FE numbers are kept. It
refuses, in one line, a study whose provenance stamp (the JSON's meta "provenance":
runs.provenance.script_stamp of this script, its setup and speeds: code, libraries
with scikit-fem and gmsh, this script's SHA-256) is not the one this code would write.

Speeds are v / v_y, v_y = theory.thornton.yield_velocity (p_y = 1.61 Y, m* the reduced mass
of sphere and block). Each speed runs twice, one after the other: the block elastic (the
"mesh and vibration" baseline) and plastic (H = 0). Measured per run:

- e: separation / approach speed of the sphere's frame relative to the block's frame, along
  the impact (the block's floating frame moves with its centre of mass);
- the peak contact force over Thornton's F_y = 2/3 pi p_y a_y^2 (against peak_force_ratio);
- the plastic work (sum sigma : d eps_p dx) over the impact's relative kinetic energy
  E_rel = 1/2 m* v^2;
- the permanent dent (summary's permanent_indentation_m: the residual field of the final
  plastic strain at the most loaded contact node) against Thornton's alpha* - delta_el;
- the elastic run's largest von Mises stress at the integration points (outputs near the
  peak force): the mesh's own first-yield speed v (Y / sigma_max)^(5/2) (stresses of a Hertz
  impact grow as v^(2/5); tests/test_plastic_dynamics.py).

The block (why, in docs/plasticity.md): 16 x 16 x 8 mm tet10, 0.45 mm within 1.8 mm of the
contact, growing to 2 mm over 3 mm; E 70 GPa, nu 0.33, rho 2700, Y 620 MPa (Thornton's
contact radius at first yield a_y = 0.20 mm, at 100 v_y 8.6 a_y = 1.7 mm). The sphere: the
committed rigid R 10 mm sphere at 1000 kg/m^3 (4.1 g). --quick: the tests' coarse
10 x 10 x 5 mm block (0.5 mm within 1 mm), Y 2.35 GPa, 250 kg/m^3, speeds 1,2,3,5
(its contact radius reaches 3 elements and 0.3 of the half-width at 5 v_y).

Beside Thornton, the FE-fitted sphere-flat law of Jackson and Green (2005) in the form of
Ghaednia et al. (2019) (theory.restitution_fits), at the block's E*, nu, Y and the study's
m*: its e with Brake's (2015) unloading and with Thornton's rule on its contact radius, its
peak force over Thornton's F_y, its residual interference, and the FE e over each law's.

Writes OUT/plastic_restitution.json and .csv (one row per speed), OUT/restitution.png, and
prints the table. Runs take tens of seconds each on the shared 2-core machine.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import platform
import time
from pathlib import Path

import numpy as np

from flexmvm.assembly.build import build_scenario
from flexmvm.integrate.driver import simulate
from flexmvm.mesh.gmsh_session import Refinement
from flexmvm.mesh.io import read_mesh
from flexmvm.mesh.parts import block
from flexmvm.mesh.quality import mesh_volume
from flexmvm.plasticity.body import PlasticBody
from flexmvm.plasticity.material import J2Plasticity
from flexmvm.plasticity.return_mapping import von_mises
from flexmvm.runs.plastic_summary import plastic_summary
from flexmvm.runs.provenance import script_stamp, script_stamp_mismatch
from flexmvm.runs.showcases.hertz_block import SPHERE_BLOCK
from flexmvm.scenarios.load import scenario_from_dict
from flexmvm.theory import thornton
from flexmvm.theory.hertz import hertz_impact
from flexmvm.theory.restitution_fits import (
    FlatteningLaw,
    Unloading,
    flattening_restitution,
    peak_interference,
)

SPHERE = SPHERE_BLOCK.parent / "meshes" / "sphere_r10_cap.msh"
R = 0.010  # sphere radius [m]
E, NU, RHO = 70e9, 0.33, 2700.0
E_STAR = E / (1.0 - NU**2)  # rigid sphere: the block's plane-strain modulus [Pa]
TURNED = {"axis": [0, 1, 0], "angle_deg": 90.0}  # the block's top face normal along +x

# name: (block lx, ly, lz; fine size, fine radius, grow, coarse [m]; Y [Pa]; ball rho)
SETUPS = {
    "study": ((16e-3, 16e-3, 8e-3), (0.45e-3, 1.8e-3, 3e-3, 2e-3), 620e6, 1000.0),
    "quick": ((10e-3, 10e-3, 5e-3), (0.5e-3, 1.0e-3, 2e-3, 2e-3), 2.35e9, 250.0),
}


def make_block(out: Path, setup) -> Path:
    (lx, ly, lz), (fine, radius, grow, coarse) = setup[0], setup[1]
    refine = Refinement((0, 0, 0), fine, radius, grow)
    return block(out / f"block_{fine * 1e6:.0f}um.msh", lx, ly, lz, coarse, order=2, refine=refine)


def scenario(
    mesh: Path,
    v: float,
    y_pa: float | None,
    rho_ball: float,
    t_end: float,
    dt: float,
    ball: Path = SPHERE,
    name: str = "plastic_restitution",
) -> dict:
    """The rigid sphere (mesh ``ball``, density rho_ball) at v [m/s] onto the free block
    ``mesh`` (elastic if y_pa is None, else perfectly plastic, Thornton's material), as a
    scenario dict; benchmarks/yield_onset.py builds its runs with it too."""
    material = {"name": "metal", "E_pa": E, "nu": NU, "rho_kg_m3": RHO}
    if y_pa is not None:
        material["plasticity"] = {"yield_pa": y_pa}  # no hardening: Thornton's material
    ball_material = {"name": "s", "E_pa": 210e9, "nu": 0.3, "rho_kg_m3": rho_ball}
    return {
        "name": name,
        "gravity_mps2": [0.0, 0.0, 0.0],
        "time": {
            "t_end_s": t_end,
            "dt_s": dt,
            "dt_max_s": dt,
            "output_dt_s": dt,
            "hf_damping_time_s": 12.5e-6,  # as tests/test_plastic_dynamics.py
        },
        "bodies": [
            {
                "name": "ball",
                "material": ball_material,
                "mesh_file": str(ball),
                "model": {"kind": "rigid"},
                "placement": {
                    "position_m": [R, 0, 0],
                    "rotation": TURNED,
                    "velocity_mps": [-v, 0, 0],
                },
            },
            {
                "name": "block",
                "material": material,
                "mesh_file": str(mesh),
                "model": {"kind": "full"},
                "placement": {"rotation": TURNED},
            },
        ],
        "contacts": [{"slave": "block.top", "master": "ball.front", "law": "position"}],
    }


def thornton_scales(y_pa: float, m_star: float) -> dict:
    """Thornton's v_y, a_y, alpha_y, F_y (p_y = 1.61 Y) for this sphere and block."""
    p_y = thornton.ONSET_PRESSURE_RATIO * y_pa
    a_y = math.pi * p_y * R / (2.0 * E_STAR)  # p0 = 2 E* a / (pi R) (Johnson eq. 4.23)
    return {
        "p_y": p_y,
        "v_y": thornton.yield_velocity(R, E_STAR, m_star, y_pa),
        "a_y": a_y,
        "alpha_y": a_y * a_y / R,
        "F_y": 2.0 / 3.0 * math.pi * p_y * a_y * a_y,
    }


def thornton_dent(s: float, sc: dict, m_star: float) -> tuple[float, float]:
    """(alpha*, permanent approach alpha* - delta_el) [m] of Thornton's model at v = s v_y:
    loading Hertz to alpha_y, then F = F_y + pi p_y R (alpha - alpha_y) (energy balance
    1/2 m* v^2 = W_Hertz(alpha_y) + F_y x + pi p_y R x^2 / 2, x = alpha* - alpha_y); unloading
    Hertz with R_p = 4 E* a_p^3 / (3 F*) recovers delta_el = (3 F* / (4 E* sqrt(R_p)))^(2/3)
    (theory.thornton's module doc)."""
    v = s * sc["v_y"]
    if s <= 1.0:
        hz = hertz_impact(R, v, E_STAR, m_star)
        return hz.delta_max_m, 0.0
    k = math.pi * sc["p_y"] * R
    w_rest = 0.5 * m_star * v * v - 0.5 * m_star * sc["v_y"] ** 2
    x = (-sc["F_y"] + math.sqrt(sc["F_y"] ** 2 + 2.0 * k * w_rest)) / k
    f_star = sc["F_y"] + k * x
    a_p = math.sqrt((2.0 * f_star + sc["F_y"]) / (2.0 * math.pi * sc["p_y"]))
    r_p = 4.0 * E_STAR * a_p**3 / (3.0 * f_star)
    delta_el = (3.0 * f_star / (4.0 * E_STAR * math.sqrt(r_p))) ** (2.0 / 3.0)
    return sc["alpha_y"] + x, sc["alpha_y"] + x - delta_el


def timing(s: float, sc: dict, m_star: float) -> tuple[float, float]:
    """(t_end, dt) [s]: the Hertz duration at v plus, past v_y, a quarter period of the
    plastic loading stiffness pi p_y R (an upper bound on the plastic loading time), with a
    30 % margin; about 40 steps in the contact, at most 0.5 us."""
    v = s * sc["v_y"]
    contact = hertz_impact(R, v, E_STAR, m_star).duration_s
    if s > 1.0:
        contact += 0.5 * math.pi * math.sqrt(m_star / (math.pi * sc["p_y"] * R))
    return 1.3 * contact, min(0.5e-6, contact / 40.0)


def peak_von_mises(built, res) -> float:
    """Largest elastic von Mises stress [Pa] at the block's integration points over the
    outputs within 3 of the peak force (u = psi q of the block, elastic PlasticBody)."""
    info = built.info[1]
    body = built.system.bodies[1]
    elastic = PlasticBody.build(info.mesh, info.material, J2Plasticity(1e30))
    state = elastic.virgin_state()
    k0 = int(np.argmax(res.contact_force))
    worst = 0.0
    for k in range(max(k0 - 3, 0), min(k0 + 4, len(res.t))):
        u = body.psi @ res.q[1][k]
        worst = max(worst, float(von_mises(elastic.respond(u, state).stress).max()))
    return worst


def run_pair(mesh: Path, s: float, sc: dict, m_star: float, y_pa: float, rho_ball: float):
    """Elastic and plastic runs at v = s v_y: their measures (module doc) as a dict."""
    v = s * sc["v_y"]
    t_end, dt = timing(s, sc, m_star)
    row = {"v_over_vy": s, "v_mps": v, "dt_s": dt, "t_end_s": t_end}
    for key, y in (("el", None), ("pl", y_pa)):
        data = scenario(mesh, v, y, rho_ball, t_end, dt)
        t0 = time.perf_counter()
        built = build_scenario(scenario_from_dict(data))
        res = simulate(built.system, built.states, built.grid)
        row[f"wall_{key}_s"] = time.perf_counter() - t0
        separated = bool(res.contact_intervals and res.contact_intervals[-1][1] < res.t[-1])
        row[f"separated_{key}"] = separated
        # the ball is rigid: its velocity is exact; the block's centre of mass from the
        # momentum the step conserves, m_b (-v) = m_b u_b + M u_B (its floating frame
        # velocity carries vibration)
        u_ball = float(res.frame_v[-1, 0, 0])
        m_ball, m_block = (b.inv.mass for b in built.system.bodies)
        u_block = -m_ball * (v + u_ball) / m_block
        row[f"e_{key}"] = (u_ball - u_block) / v
        row[f"e_frame_{key}"] = float(res.frame_v[-1, 0, 0] - res.frame_v[-1, 1, 0]) / v
        row[f"peak_force_{key}_n"] = float(np.max(res.contact_force))
        row[f"contact_{key}_s"] = float(sum(b - a for a, b in res.contact_intervals))
        row[f"not_converged_{key}"] = int(res.steps_on_roundoff_floor)
        row[f"step_cuts_{key}"] = int(res.step_cuts)
        if key == "el":
            row["peak_von_mises_el_pa"] = peak_von_mises(built, res)
            continue
        rep = res.plastic["block"]
        summary = plastic_summary(res, built)["plastic"]["block"]
        row["plastic_work_j"] = rep.plastic_work_j
        row["plastic_work_fraction"] = rep.plastic_work_j / (0.5 * m_star * v * v)
        row["dent_m"] = summary["permanent_indentation_m"]
        row["peak_alpha"] = rep.peak_equivalent_plastic_strain
        row["plastic_cells"] = summary["plastic_cells"]
    return row


def compare(row: dict, sc: dict, m_star: float, y_pa: float) -> dict:
    """Thornton's values beside the measured ones, and the mesh's onset speed."""
    s = row["v_over_vy"]
    e_th = thornton.restitution(s)
    alpha_star, dent = thornton_dent(s, sc, m_star)
    row["e_thornton"] = e_th
    row["e_ratio"] = row["e_pl"] / row["e_el"]
    row["loss_pl_minus_el"] = (1.0 - row["e_pl"] ** 2) - (1.0 - row["e_el"] ** 2)
    row["loss_thornton"] = 1.0 - e_th**2
    row["force_ratio_pl"] = row["peak_force_pl_n"] / sc["F_y"]
    row["force_ratio_thornton"] = thornton.peak_force_ratio(s)
    row["dent_thornton_m"] = dent
    row["approach_thornton_m"] = alpha_star
    row["v_y_mesh_mps"] = row["v_mps"] * (y_pa / row["peak_von_mises_el_pa"]) ** 2.5
    return row


def fitted_columns(row: dict, meta: dict) -> dict:
    """The FE-fitted law's values beside the measured ones (module doc), at the block's
    E*, nu, Y (meta["yield_pa"]) and the study's m* and Thornton v_y (meta)."""
    law = FlatteningLaw.make(R, E_STAR, meta["yield_pa"], NU)
    m_star, v = meta["m_star_kg"], row["v_over_vy"] * meta["thornton"]["v_y"]
    d_m = peak_interference(law, 0.5 * m_star * v * v)
    row["e_jg_brake"] = flattening_restitution(law, m_star, v, Unloading.BRAKE)
    row["e_jg_hertz"] = flattening_restitution(law, m_star, v, Unloading.HERTZ_AT_CONTACT_RADIUS)
    row["force_ratio_jg"] = law.force(d_m) / meta["thornton"]["F_y"]
    row["dent_jg_brake_m"] = max(law.unloading(d_m)[0], 0.0)
    row["dent_jg_hertz_m"] = max(law.unloading_at_contact_radius(d_m)[0], 0.0)
    row["e_pl_over_thornton"] = row["e_pl"] / row["e_thornton"]
    row["e_pl_over_jg_brake"] = row["e_pl"] / row["e_jg_brake"]
    row["e_pl_over_jg_hertz"] = row["e_pl"] / row["e_jg_hertz"]
    return row


COLUMNS = [
    ("v/vy", "v_over_vy", "{:.0f}"),
    ("v m/s", "v_mps", "{:.2f}"),
    ("e_el", "e_el", "{:.3f}"),
    ("e_pl", "e_pl", "{:.3f}"),
    ("e_Th", "e_thornton", "{:.3f}"),
    ("e_JG,B", "e_jg_brake", "{:.3f}"),
    ("e_JG,H", "e_jg_hertz", "{:.3f}"),
    ("FE/Th", "e_pl_over_thornton", "{:.3f}"),
    ("FE/JG,B", "e_pl_over_jg_brake", "{:.3f}"),
    ("FE/JG,H", "e_pl_over_jg_hertz", "{:.3f}"),
    ("e_pl/e_el", "e_ratio", "{:.3f}"),
    ("dloss", "loss_pl_minus_el", "{:.3f}"),
    ("1-e_Th^2", "loss_thornton", "{:.3f}"),
    ("Wp/Erel", "plastic_work_fraction", "{:.3f}"),
    ("F/Fy", "force_ratio_pl", "{:.2f}"),
    ("F/Fy Th", "force_ratio_thornton", "{:.2f}"),
    ("F/Fy JG", "force_ratio_jg", "{:.2f}"),
    ("dent um", "dent_m", "{:.3g}"),
    ("dent Th", "dent_thornton_m", "{:.3g}"),
    ("dent JG,B", "dent_jg_brake_m", "{:.3g}"),
    ("dent JG,H", "dent_jg_hertz_m", "{:.3g}"),
    ("vy_mesh/vy", "vy_mesh_ratio", "{:.3f}"),
    ("wall s", "wall_pl_s", "{:.0f}"),
]


def print_table(rows: list[dict]) -> None:
    print("  ".join(f"{h:>10}" for h, _, _ in COLUMNS))
    for r in rows:
        cells = []
        for _, key, fmt in COLUMNS:
            value = r[key] * 1e6 if key.startswith("dent") else r[key]
            cells.append(f"{fmt.format(value):>10}")
        print("  ".join(cells))


def figure(rows: list[dict], meta: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = np.array([r["v_over_vy"] for r in rows])
    fine = np.geomspace(1.0, max(100.0, s.max()), 200)
    fig, ax = plt.subplots(figsize=(6.0, 4.2))
    ax.semilogx(fine, thornton.restitution(fine), "k-", label="Thornton (1997)")
    law = FlatteningLaw.make(R, E_STAR, meta["yield_pa"], NU)
    v = fine * meta["thornton"]["v_y"]
    for unloading, style, name in (
        (Unloading.BRAKE, "k--", "Jackson-Green FE-fitted law, Brake unloading"),
        (
            Unloading.HERTZ_AT_CONTACT_RADIUS,
            "k:",
            "Jackson-Green FE-fitted law, Thornton unloading",
        ),
    ):
        e_fit = flattening_restitution(law, meta["m_star_kg"], v, unloading)
        ax.semilogx(fine, e_fit, style, label=name)
    ax.semilogx(s, [r["e_el"] for r in rows], "s--", color="0.5", label="FE elastic (baseline)")
    ax.semilogx(s, [r["e_pl"] for r in rows], "o-", color="C3", label="FE plastic")
    ax.semilogx(s, [r["e_ratio"] for r in rows], "^-", color="C0", label="FE e_pl / e_el")
    ax.set_xlabel("impact speed v / v_y (v_y: Thornton, p_y = 1.61 Y)")
    ax.set_ylabel("coefficient of restitution e")
    ax.set_ylim(0.0, 1.05)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def setup_name(args) -> str:
    """The setup of SETUPS the arguments ask for."""
    return "quick" if args.quick else "study"


def run_study(args) -> tuple[list[dict], dict]:
    """Runs the study at args.speeds (module doc): its rows and meta."""
    setup = SETUPS[setup_name(args)]
    default = "1,2,3,5" if args.quick else "1,2,5,10,30,100"
    speeds = [float(x) for x in (args.speeds or default).split(",")]
    mesh = make_block(args.out, setup)
    y_pa, rho_ball = setup[2], setup[3]
    m_ball = rho_ball * mesh_volume(read_mesh(SPHERE))
    m_block = RHO * mesh_volume(read_mesh(mesh))
    m_star = m_ball * m_block / (m_ball + m_block)
    sc = thornton_scales(y_pa, m_star)
    meta = {
        "setup": "quick" if args.quick else "study",
        "block_m": setup[0],
        "refinement_m": setup[1],
        "yield_pa": y_pa,
        "m_ball_kg": m_ball,
        "m_block_kg": m_block,
        "m_star_kg": m_star,
        "n_dof_block": 3 * read_mesh(mesh).nodes.shape[0],
        "thornton": sc,
        "machine": f"{platform.node()} {platform.processor() or platform.machine()}",
        "provenance": script_stamp(Path(__file__), {"setup": setup_name(args), "speeds": speeds}),
    }
    rows = []
    for s in speeds:  # one after the other: the machine is shared
        row = compare(run_pair(mesh, s, sc, m_star, y_pa, rho_ball), sc, m_star, y_pa)
        row["vy_mesh_ratio"] = row["v_y_mesh_mps"] / sc["v_y"]
        rows.append(fitted_columns(row, meta))
        print(json.dumps(row), flush=True)
    return rows, meta


def _cell(text: str):
    """A stored CSV cell as the JSON type it was written from (bool, int or float)."""
    if text in ("True", "False"):
        return text == "True"
    try:
        return int(text)
    except ValueError:
        return float(text)


def from_csv(path: Path) -> tuple[list[dict], dict]:
    """A stored study's rows (path, .csv) and meta (the .json beside it), with the
    published-law columns added; nothing is rerun. SystemExit with one line if either
    file is missing or the study's stamp is not this code's (module doc)."""
    meta_path = path.with_suffix(".json")
    if not path.is_file() or not meta_path.is_file():
        raise SystemExit(f"--from-csv: expected {path} and {meta_path}, not found")
    meta = json.loads(meta_path.read_text())["meta"]
    why = script_stamp_mismatch(meta.get("provenance"), Path(__file__))
    if why is not None:
        raise SystemExit(f"--from-csv: {meta_path} was {why}: rerun the study")
    with open(path, newline="") as f:
        rows = [{k: _cell(v) for k, v in r.items()} for r in csv.DictReader(f)]
    return [fitted_columns(r, meta) for r in rows], meta


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--speeds", default=None, help="v / v_y, comma separated")
    ap.add_argument("--quick", action="store_true", help="the tests' coarse block")
    ap.add_argument("--from-csv", type=Path, default=None, help="a stored study: rerun nothing")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    rows, meta = from_csv(args.from_csv) if args.from_csv else run_study(args)
    (args.out / "plastic_restitution.json").write_text(
        json.dumps({"meta": meta, "rows": rows}, indent=1)
    )
    with open(args.out / "plastic_restitution.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    figure(rows, meta, args.out / "restitution.png")
    print(json.dumps(meta))
    print_table(rows)


if __name__ == "__main__":
    main()
