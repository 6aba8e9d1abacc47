"""The moving-load check (issue 53, item 3, first check), fine: scenarios/moving_load.toml's
rigid slider driven along the simply supported HEX27 beam at a slow speed and near the critical
one, full FE against Fryba's moving-force series (flexmvm.theory.moving_load), with what
separates the 3D beam from Euler-Bernoulli measured one by one:

- statically (K u = f, no run): the mid-span deflection under a mid-span force on the axis,
  top and bottom nodes of the coarse (40 x 1 x 1) and fine (80 x 2 x 2) meshes against
  P L^3 / (48 E I) and the Timoshenko beam's + P L / (4 kappa G A); with the shipped supports
  (end faces held vertically) and with line supports on the bottom edges (the support's 3D
  form);
- dynamically: the series with shear (Timoshenko) against Euler-Bernoulli; each run's peak
  and NCC on the axis node, the top node under the load (local indentation) against the axis,
  the step halved, the fine mesh, the slider 10 x heavier (a moving mass, not a force).

    PYTHONPATH=src python benchmarks/moving_load_check.py [--quick]

prints a markdown report (docs/notes/2026-11-29-moving-load.md holds one) with CPU seconds
(time.process_time) per run. --quick: the coarse mesh at the two speeds only.
"""

from __future__ import annotations

import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spl

import flexmvm as fm
from flexmvm.fe.assembly import assemble
from flexmvm.materials import Material
from flexmvm.mesh.box27 import hex27_box_beam, write_box_beam
from flexmvm.metrics.ncc import ncc
from flexmvm.reduction.clamp import held_dofs
from flexmvm.theory.moving_load import MovingForce

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "moving_load.toml"
L, B, E, NU, RHO, P = 1.0, 0.02, 70.0e9, 0.33, 2700.0, 2.0
EI, MU = E * B**4 / 12.0, RHO * B * B
G = E / (2.0 * (1.0 + NU))
KAPPA = 10.0 * (1.0 + NU) / (12.0 + 11.0 * NU)  # Cowper's rectangle
TIMO = {"kappa_G_pa": KAPPA * G, "area_m2": B * B, "rho_I_kg_m": RHO * B**4 / 12.0}
SPEEDS = (10.0, 60.0, 83.0)  # alpha = 0.108, 0.650, 0.899
COARSE, FINE = (40, 1, 1), (80, 2, 2)


def _node(mesh, x, y, z) -> int:
    return int(np.argmin(np.linalg.norm(mesh.nodes - [x, y, z], axis=1)))


def static_case(cells, supports: str) -> dict[str, float]:
    """Mid-span deflection [m] of the axis, top and bottom nodes under P on the top's mid-span
    node, supports "faces" (the scenario's) or "lines" (bottom edges held in z, end A's bottom
    edge in x, both edges' middle nodes in y)."""
    m = hex27_box_beam(L, B, B, cells)
    fe = assemble(m, Material(E=E, nu=NU, rho=RHO))
    if supports == "faces":
        held = [
            held_dofs(np.r_[m.node_set("end_a"), m.node_set("end_b")], ["z"]),
            held_dofs(np.r_[m.node_set("end_a_axis"), m.node_set("end_b_axis")], ["y"]),
            held_dofs(m.node_set("end_a_axis"), ["x"]),
        ]
    else:
        ends = np.r_[m.node_set("end_a_bottom"), m.node_set("end_b_bottom")]
        mids = [_node(m, 0.0, 0.0, -B), _node(m, L, 0.0, -B)]
        held = [
            held_dofs(ends, ["z"]),
            held_dofs(mids, ["y"]),
            held_dofs(m.node_set("end_a_bottom"), ["x"]),
        ]
    free = np.setdiff1d(np.arange(m.n_dof), np.unique(np.concatenate(held)))
    top = _node(m, L / 2, 0.0, 0.0)
    f = np.zeros(m.n_dof)
    f[3 * top + 2] = -P
    u = np.zeros(m.n_dof)
    u[free] = spl.splu(fe.K[free][:, free].tocsc()).solve(f[free])
    where = {"axis": (L / 2, 0.0, -B / 2), "top": (L / 2, 0.0, 0.0), "bottom": (L / 2, 0.0, -B)}
    return {k: -u[3 * _node(m, *x) + 2] for k, x in where.items()}


def _data(c: float, dt: float, mesh: Path | None, rho: float) -> dict:
    with open(SCENARIO, "rb") as f:
        d = tomllib.load(f)
    for b in d["bodies"]:
        b["mesh_file"] = str(SCENARIO.parent / b["mesh_file"])
    if mesh is not None:
        d["bodies"][0]["mesh_file"] = str(mesh)
    d["time"].update(t_end_s=0.998 * L / c, dt_s=dt, output_dt_s=dt)
    slider = d["bodies"][1]
    slider["placement"]["velocity_mps"] = [c, 0.0, 0.0]
    slider["material"]["rho_kg_m3"] = rho
    d["joints"][0]["velocity_mps"] = [c, 0.0, 0.0]
    return d


def run_case(c: float, dt: float, mesh: Path | None = None, rho: float = 26.0) -> dict:
    """One run: peak (axis node) against the series, NCC, the top node's peak, CPU [s]."""
    t0 = time.process_time()
    run = fm.run(fm.scenario_from_dict(_data(c, dt, mesh, rho)))
    cpu = time.process_time() - t0
    t = run.t
    w = {}
    for name in ("mid_axis", "mid_top"):
        z = run.probe(name).x[:, 2]
        w[name] = -(z - z[0])
    theory = MovingForce(L, EI, MU, P, c).deflection(L / 2, t)
    return {
        "alpha": c / MovingForce(L, EI, MU, P, c).critical_speed_mps,
        "peak": w["mid_axis"].max(),
        "peak_th": theory.max(),
        "rel": w["mid_axis"].max() / theory.max() - 1.0,
        "ncc": ncc(t, theory, t, w["mid_axis"]),
        "top_rel": w["mid_top"].max() / w["mid_axis"].max() - 1.0,
        "force": float(run.contact_force[1:].mean()),
        "pen": run.summary["max_penetration_m"],
        "steps": len(t) - 1,
        "dof": run.summary["dof"]["beam"],
        "cpu": cpu,
    }


def _series_rows() -> list[str]:
    rows = [
        "| c [m/s] | alpha | EB peak / w0 | Timoshenko peak / w0 | shear effect |",
        "|---|---|---|---|---|",
    ]
    for c in SPEEDS:
        eb = MovingForce(L, EI, MU, P, c)
        ti = MovingForce(L, EI, MU, P, c, **TIMO)
        t = np.linspace(0.0, 0.998 * eb.crossing_time_s, 4001)
        a, b = eb.deflection(L / 2, t, 200).max(), ti.deflection(L / 2, t, 200).max()
        w0 = eb.midspan_static_m
        rows.append(f"| {c:g} | {eb.alpha:.3f} | {a / w0:.4f} | {b / w0:.4f} | {b / a - 1:+.4%} |")
    return rows


def _static_rows() -> list[str]:
    w0 = P * L**3 / (48.0 * EI)
    shear = P * L / (4.0 * KAPPA * G * B * B)
    rows = [
        f"EB w0 = {w0:.5e} m; Timoshenko adds {shear / w0:+.4%}.",
        "",
        "| mesh | supports | axis / w0 - 1 | top / w0 - 1 | bottom / w0 - 1 |",
        "|---|---|---|---|---|",
    ]
    for cells in (COARSE, FINE):
        for sup in ("faces", "lines"):
            s = static_case(cells, sup)
            rows.append(
                f"| {cells} | {sup} | {s['axis'] / w0 - 1:+.4%} | {s['top'] / w0 - 1:+.4%} | "
                f"{s['bottom'] / w0 - 1:+.4%} |"
            )
    return rows


def main(argv: list[str]) -> int:
    quick = "--quick" in argv
    out = ["## Series: shear (Timoshenko) against Euler-Bernoulli", "", *_series_rows(), ""]
    out += ["## Static: the 3D beam and its supports", "", *_static_rows(), ""]
    print("\n".join(out), flush=True)
    head = "| case | alpha | DOF | steps | peak [m] | series [m] | peak rel | NCC | top/axis | mean F [N] | pen [m] | CPU [s] |"
    print("## Runs (full FE)\n\n" + head + "\n|" + "---|" * 12, flush=True)
    cases = [
        (f"coarse c={c:g} dt={dt:g}", c, dt, None, 26.0) for c, dt in ((10.0, 1e-4), (60.0, 5e-5))
    ]
    with tempfile.TemporaryDirectory() as tmp:
        fine = write_box_beam(Path(tmp) / "fine.vtu", L, B, B, FINE)
        if not quick:
            cases += [
                ("coarse c=83 dt=5e-05", 83.0, 5e-5, None, 26.0),
                ("coarse c=10 dt=5e-05", 10.0, 5e-5, None, 26.0),
                ("coarse c=60 dt=2.5e-05", 60.0, 2.5e-5, None, 26.0),
                ("coarse c=60 slider x10", 60.0, 5e-5, None, 260.0),
                ("fine c=60 dt=5e-05", 60.0, 5e-5, fine, 26.0),
                ("fine c=10 dt=1e-04", 10.0, 1e-4, fine, 26.0),
            ]
        for label, c, dt, mesh, rho in cases:
            r = run_case(c, dt, mesh, rho)
            print(
                f"| {label} | {r['alpha']:.3f} | {r['dof']} | {r['steps']} | {r['peak']:.5e} | "
                f"{r['peak_th']:.5e} | {r['rel']:+.3%} | {r['ncc']:.5f} | {r['top_rel']:+.3%} | "
                f"{r['force']:.4f} | {r['pen']:.1e} | {r['cpu']:.1f} |",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
