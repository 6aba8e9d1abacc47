"""A step's cost against body size and against region size: full FE, the dense reduced body
(kind mvm) and the sparse one (kind mvm-sparse), on a plate meshed as a user meshes it.

    python benchmarks/bench_scaling.py [--far-mm 4,2.5,1.7] [--radii-mm 0.6,1.2,2.4]
        [--steps 40] [--work DIR] [--dense-limit 4000]

The part: a 100 x 100 x 4 mm aluminium plate clamped on its sides, gmsh tet10, 0.2 mm within
1 mm of its centre and --far-mm elsewhere (one plate per value: its DOF grows as far^-2), struck
at its centre by a rigid steel ball R 5 mm at 1 m/s (the contact from the first step). Two
sweeps, every case a process of its own (FLEXMVM_NO_CACHE=1: set-up measured cold):
- body size: each plate in full FE and as mvm-sparse with the first --radii-mm region + 60
  modes;
- region size: the first plate as mvm and mvm-sparse for every --radii-mm (mvm skipped above
  --dense-limit retained DOF, its dense matrices growing as their square).
Prints per case: DOF, retained nodes, the dense corner (mvm-sparse), set-up CPU, CPU per step
over --steps steps, peak RSS, and the step's floor: the bytes of the matrices a step must read
(the factor of W for full FE and mvm-sparse, the dense W and the G2 blocks for mvm) over
10 GB/s. States the CPU and the commit; docs/performance.md quotes ratios, docs/notes/ the runs.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_ring_body import commit_hash, cpu_name  # the same machine line

SCENARIO = """name = "plate_scaling"
description = "rigid ball R 5 mm at 1 m/s onto a clamped 100 x 100 x 4 mm plate"
gravity_mps2 = [0.0, 0.0, 0.0]

[time]
t_end_s = {t_end}
dt_s = 0.5e-6
dt_max_s = 0.5e-6
output_dt_s = 0.5e-6

[[bodies]]
name = "ball"
material = {{ name = "steel", E_pa = 210.0e9, nu = 0.3, rho_kg_m3 = 7850.0 }}
mesh_file = "{ball}"
[bodies.model]
kind = "rigid"
[bodies.placement]
position_m = [0.0, 0.0, 0.005]
velocity_mps = [0.0, 0.0, -1.0]

[[bodies]]
name = "plate"
material = "aluminium"
mesh_file = "{plate}"
[bodies.model]
kind = "full"

[[supports]]
type = "clamp"
body = "plate"
node_set = "side"

[[contacts]]
slave = "plate.top"
master = "ball.front"
law = "position"
"""

STREAM_BYTES_PER_S = 10e9  # a core's memory stream, order of magnitude (the step's floor)


def meshes(work: Path, far_mm: float) -> tuple[Path, Path]:
    """The plate of far_mm [mm] away from the contact and the ball, made once in work."""
    from flexmvm.mesh.gmsh_session import Refinement
    from flexmvm.mesh.parts import block, sphere

    plate = work / f"plate_{far_mm:g}mm.msh"
    ball = work / "ball.msh"
    if not plate.exists():
        refine = Refinement((0.0, 0.0, 0.0), 0.2e-3, 1.0e-3, 10.0e-3)
        block(plate, 0.1, 0.1, 0.004, far_mm * 1e-3, order=2, refine=refine)
    if not ball.exists():
        sphere(ball, 0.005, 1.5e-3, refine=Refinement((0.0, 0.0, -0.005), 0.1e-3, 0.5e-3, 3e-3))
    return plate, ball


def child(kind: str, plate: str, ball: str, radius_m: float, steps: int, out: Path) -> None:
    import flexmvm as fm
    from flexmvm.assembly.build import build_scenario
    from flexmvm.integrate.driver import simulate

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "plate.toml"
        text = SCENARIO.format(t_end=steps * 0.5e-6, ball=ball, plate=plate)
        path.write_text(text)
        sc = fm.load_scenario(path)
    if kind != "full":
        region = {"ball": {"centre_m": [0.0, 0.0, 0.0], "radius_m": radius_m}}
        model = fm.mvm(region=region, modes=60, kind=fm.ModelKind(kind))
        sc = sc.with_model("plate", model.model_copy(update={"allow_costly": True}))
    c0 = time.process_time()
    built = build_scenario(sc)
    c1 = time.process_time()
    res = simulate(built.system, built.states, built.grid, built.probes)
    c2 = time.process_time()
    body = built.system.bodies[1]
    info = {
        "kind": kind,
        "plate": Path(plate).name,
        "radius_mm": radius_m * 1e3,
        "dof": int(body.nv),
        "retained": int(built.info[1].n_retained_nodes),
        "corner": int(body.corner.size) if getattr(body, "corner", None) is not None else None,
        "setup_cpu_s": c1 - c0,
        "sim_cpu_s": c2 - c1,
        "steps": int(res.n_steps),
        "peak_force_n": float(max(res.contact_force)),
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "floor_bytes": _floor_estimate(body),
    }
    out.write_text(json.dumps(info))


def _floor_estimate(body) -> float:
    """Bytes a step reads at least once (module doc): the L D L^T factor of W's pattern for a
    sparse W (its symbolic analysis), the dense W's triangle and the 4.5 nq^2 packed G2
    blocks for a dense body."""
    import scipy.sparse as sp

    from flexmvm.fe.solvers.symbolic import SymbolicFactor

    if not body.nq:
        return 0.0
    if sp.issparse(body.k_hat):
        W = sp.csr_matrix(body.inv.M_qq + body.k_hat)
        extra = 0.0
        corner = getattr(body, "corner", None)
        if corner is not None:
            extra = 8.0 * 4.5 * corner.size**2  # the packed corner blocks of the contraction
        return 8.0 * SymbolicFactor(W).nnz + extra
    nq = body.nq
    return 8.0 * 5.0 * nq * nq


def _run(kind, plate, ball, radius_m, steps) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "case.json"
        cmd = [sys.executable, __file__, "--child", kind, str(plate), str(ball)]
        cmd += [str(radius_m), str(steps), str(out)]
        env = dict(os.environ, FLEXMVM_NO_CACHE="1")
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False, env=env)
        if proc.returncode != 0:
            tail = (proc.stderr.strip().splitlines() or ["?"])[-1]
            return {"kind": kind, "plate": Path(plate).name, "error": tail}
        return json.loads(out.read_text())


def _line(r: dict) -> str:
    if "error" in r:
        return f"{r['kind']:>10} {r['plate']}: failed: {r['error']}"
    per_step = r["sim_cpu_s"] / max(r["steps"], 1)
    floor = r["floor_bytes"] / STREAM_BYTES_PER_S
    corner = f", corner {r['corner']}" if r["corner"] is not None else ""
    region = (
        f" {r['radius_mm']:.1f} mm ({r['retained']} nodes{corner})" if r["kind"] != "full" else ""
    )
    return (
        f"{r['kind']:>10} {r['plate']}{region}: {r['dof']:,} DOF; set-up {r['setup_cpu_s']:.1f} s"
        f" CPU; {1e3 * per_step:.2f} ms CPU a step ({r['steps']} steps; floor "
        f"{1e3 * floor:.2f} ms: {r['floor_bytes'] / 1e6:.0f} MB read at 10 GB/s); peak RSS "
        f"{r['peak_rss_mb']:.0f} MB; peak force {r['peak_force_n']:.1f} N"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--far-mm", default="4,2.5,1.7")
    ap.add_argument("--radii-mm", default="0.6,1.2,2.4")
    ap.add_argument("--steps", type=int, default=40)
    ap.add_argument("--work", default=None)
    ap.add_argument("--dense-limit", type=int, default=4000)
    args = ap.parse_args()
    work = Path(args.work or tempfile.mkdtemp(prefix="flexmvm-scaling-"))
    work.mkdir(parents=True, exist_ok=True)
    print(
        f"CPU: {cpu_name()}; commit {commit_hash()}; {os.cpu_count()} cores; load {os.getloadavg()}"
    )
    fars = [float(x) for x in args.far_mm.split(",")]
    radii = [float(x) * 1e-3 for x in args.radii_mm.split(",")]
    print("body size (full FE against mvm-sparse, first radius):", flush=True)
    for far in fars:
        plate, ball = meshes(work, far)
        full = _run("full", plate, ball, 0.0, args.steps)
        sparse = _run("mvm-sparse", plate, ball, radii[0], args.steps)
        print(_line(full), flush=True)
        print(_line(sparse), flush=True)
        if "error" not in full and "error" not in sparse:
            print(
                f"  full FE / mvm-sparse: CPU a step {full['sim_cpu_s'] / sparse['sim_cpu_s']:.1f}"
                f", memory {full['peak_rss_mb'] / sparse['peak_rss_mb']:.2f}",
                flush=True,
            )
    print("region size (first plate, mvm against mvm-sparse):", flush=True)
    plate, ball = meshes(work, fars[0])
    for r in radii:
        sparse = _run("mvm-sparse", plate, ball, r, args.steps)
        print(_line(sparse), flush=True)
        if "error" in sparse or 3 * sparse["retained"] > args.dense_limit:
            print(f"{'mvm':>10} {r * 1e3:.1f} mm: skipped (--dense-limit)", flush=True)
            continue
        dense = _run("mvm", plate, ball, r, args.steps)
        print(_line(dense), flush=True)
        if "error" not in dense:
            print(
                f"  mvm / mvm-sparse: CPU a step {dense['sim_cpu_s'] / sparse['sim_cpu_s']:.1f}"
                f", set-up {dense['setup_cpu_s'] / sparse['setup_cpu_s']:.1f}, memory "
                f"{dense['peak_rss_mb'] / sparse['peak_rss_mb']:.2f}",
                flush=True,
            )


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        kind, plate, ball, radius, steps, out = sys.argv[2:8]
        child(kind, plate, ball, float(radius), int(steps), Path(out))
    else:
        main()
