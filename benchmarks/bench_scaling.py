"""A step's cost against body size and against region size: full FE, the dense reduced body
(kind mvm) and the sparse one (kind mvm-sparse), on a plate meshed as a user meshes it; the
scaling table of docs/performance.md in one command.

    python benchmarks/bench_scaling.py [--far-mm 10,4,2.5,2,1.7,1.2,1] [--nodes
        10,100,1000,3000,10000] [--steps 20] [--work DIR] [--dense-limit 4000]
        [--memory-limit-gb 8] [--json FILE] [--markdown FILE] [--sweeps body,region]
        [--no-warm-up]

The part: a 100 x 100 x 4 mm aluminium plate clamped on its sides, gmsh tet10, 0.2 mm within
1 mm of its centre and --far-mm elsewhere (one plate per value), struck at its centre by a rigid
steel ball R 5 mm at 1 m/s (the contact from the first step); --steps steps of 0.5 us, the
CPU a step (time.process_time of the process: every thread) the mean over the steps after
the first (which factors the iteration matrix W once: its CPU is kept as first_step_cpu_s).
Two sweeps, every case a process of its own (FLEXMVM_NO_CACHE=1: set-up measured cold),
after a two-step run of each kind on the coarsest plate that compiles the kernels:
- body size: each plate in full FE and as mvm-sparse with the region of the first --nodes
  count of at least 100 nodes + 60 modes;
- region size: the --far-mm plate nearest 48,000 DOF (its full FE the reference), as
  mvm-sparse and as mvm for every --nodes count (the region: the ball about the contact
  point holding that many mesh nodes; mvm skipped above --dense-limit retained DOF, its dense
  matrices growing as their square).
A case whose peak resident set a power law through the measured cases of its kind and sweep
predicts above --memory-limit-gb is not run: its row is that power law's estimate (DOF, CPU
a step, set-up, memory, floor), marked "est.". The floor of a step: the bytes of the matrices
it must read (the L D L^T factor of W for full FE and mvm-sparse, plus the packed corner blocks
of the latter; the dense W and the G2 blocks for mvm) over STREAM_BYTES_PER_S. Prints per case
a line, then markdown tables; --json writes the rows (and the region sweep's full-FE
reference) with the provenance stamp (runs.provenance.script_stamp), --markdown the tables. docs/performance.md quotes the
ratios, docs/notes/ the runs.
"""

from __future__ import annotations

import argparse
import json
import math
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
    ends: list[float] = []  # CPU at each accepted step's end: the first step factors W
    on_step = lambda _step: ends.append(time.process_time())
    res = simulate(built.system, built.states, built.grid, built.probes, on_step=on_step)
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
        "first_step_cpu_s": ends[0] - c1,
        "step_ms": 1e3 * (ends[-1] - ends[0]) / max(len(ends) - 1, 1),
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


def radius_for(plate: Path, n: int) -> float:
    """The radius [m] of the ball about the contact point (the origin) holding n mesh nodes."""
    import meshio
    import numpy as np

    d = np.sort(np.linalg.norm(meshio.read(plate).points, axis=1))
    n = min(n, d.size)
    return float(0.5 * (d[n - 1] + d[n])) if n < d.size else float(d[-1] * 1.01)


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
        r = json.loads(out.read_text())
        r["floor_ms"] = 1e3 * r["floor_bytes"] / STREAM_BYTES_PER_S
        return r


#: The quantities a power law in the DOF (or the retained nodes) extrapolates.
FITTED = ("step_ms", "setup_cpu_s", "peak_rss_mb", "floor_ms")


def power_law(rows: list[dict], x_key: str, x: float, y_key: str) -> float | None:
    """y at x from the power law through the last two or three measured rows (least squares in
    log-log), None with fewer than two."""
    import numpy as np

    pts = [(r[x_key], r[y_key]) for r in rows if "error" not in r and not r.get("estimated")]
    pts = [(a, b) for a, b in pts if a > 0 and b > 0][-3:]
    if len(pts) < 2:
        return None
    lx, ly = np.log([a for a, _ in pts]), np.log([b for _, b in pts])
    slope, icpt = np.polyfit(lx, ly, 1)
    return float(math.exp(icpt + slope * math.log(x)))


def case(kind, plate, ball, radius_m, steps, measured, x_key, x, limit_mb, extra) -> dict:
    """A measured case, or the power law's estimate when its predicted peak RSS is over
    limit_mb (``measured``: the cases of the same kind and sweep so far)."""
    rss = power_law(measured, x_key, x, "peak_rss_mb")
    if rss is not None and rss > limit_mb:
        est = {k: power_law(measured, x_key, x, k) for k in FITTED}
        return {"kind": kind, "plate": Path(plate).name, "estimated": True, **extra, **est}
    r = _run(kind, plate, ball, radius_m, steps) | extra
    measured.append(r)
    return r


def _line(r: dict) -> str:
    if "error" in r:
        return f"{r['kind']:>10} {r['plate']}: failed: {r['error']}"
    if r.get("estimated"):
        return (
            f"{r['kind']:>10} {r['plate']}: estimated (over the memory limit): "
            f"{r['step_ms']:.1f} ms CPU a step (floor {r['floor_ms']:.2f} ms), set-up "
            f"{r['setup_cpu_s']:.0f} s, peak RSS {r['peak_rss_mb']:,.0f} MB"
        )
    corner = f", corner {r['corner']}" if r["corner"] is not None else ""
    region = (
        f" {r['radius_mm']:.2f} mm ({r['retained']} nodes{corner})" if r["kind"] != "full" else ""
    )
    return (
        f"{r['kind']:>10} {r['plate']}{region}: {r['dof']:,} DOF; set-up {r['setup_cpu_s']:.1f} s"
        f" CPU; {r['step_ms']:.2f} ms CPU a step ({r['steps']} steps; floor "
        f"{r['floor_ms']:.2f} ms: {r['floor_bytes'] / 1e6:.0f} MB); peak RSS "
        f"{r['peak_rss_mb']:.0f} MB; peak force {r['peak_force_n']:.1f} N"
    )


def _cell(r: dict | None, what: str) -> str:
    """A table cell: 'ms (floor)', set-up s, or MB; 'est.' on an estimate; '-' if none."""
    if r is None or "error" in r:
        return "-" if r is None else "failed"
    est = " est." if r.get("estimated") else ""
    if what == "step":
        return f"{r['step_ms']:,.1f} ({r['floor_ms']:.1f}){est}"
    if what == "setup":
        return f"{r['setup_cpu_s']:,.0f} s{est}"
    return f"{r['peak_rss_mb']:,.0f} MB{est}"


def body_table(pairs: list[tuple[dict, dict, int]]) -> str:
    """Markdown: per plate, full FE and mvm-sparse side by side and their step ratio."""
    out = [
        (
            "| plate DOF | full FE ms CPU a step (floor) | set-up | peak RSS | mvm-sparse DOF"
            " (retained nodes) | ms CPU a step (floor) | set-up | peak RSS | step ratio |"
        ),
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for full, sparse, dof in pairs:
        dofs = f"{sparse['dof']:,} ({sparse['retained']})" if "dof" in sparse else "-"
        ratio = "-"
        if "step_ms" in full and "step_ms" in sparse:
            ratio = f"{full['step_ms'] / sparse['step_ms']:.1f}"
            ratio += " est." if full.get("estimated") or sparse.get("estimated") else ""
        cells = [f"{dof:,}", *(_cell(full, w) for w in ("step", "setup", "rss")), dofs]
        cells += [*(_cell(sparse, w) for w in ("step", "setup", "rss")), ratio]
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def region_table(full: dict, rows: list[tuple[int, dict, dict | None]]) -> str:
    """Markdown: per region size, mvm-sparse and mvm, full FE's step beside."""
    out = [
        f"Full FE on this plate: {_cell(full, 'step')} ms a step, {_cell(full, 'rss')}.",
        "",
        (
            "| retained nodes | mvm-sparse DOF (corner) | ms CPU a step (floor) | set-up | peak RSS"
            " | mvm ms CPU a step (floor) | set-up | peak RSS | full FE / mvm-sparse a step |"
        ),
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for n, sparse, dense in rows:
        nodes = sparse.get("retained", n)
        dofs = f"{sparse['dof']:,} ({sparse['corner']:,})" if "dof" in sparse else "-"
        cells = [f"{nodes:,}", dofs, *(_cell(sparse, w) for w in ("step", "setup", "rss"))]
        cells += [_cell(dense, w) for w in ("step", "setup", "rss")]
        ok = "step_ms" in full and "step_ms" in sparse
        cells.append(f"{full['step_ms'] / sparse['step_ms']:.1f}" if ok else "-")
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def mesh_dof(plate: Path) -> int:
    """3 x the plate mesh's nodes (the DOF before the clamp)."""
    import meshio

    return 3 * int(meshio.read(plate).points.shape[0])


def body_sweep(args, work: Path, fars: list[float], nodes: int) -> list:
    """Full FE and mvm-sparse (the ball of ``nodes`` nodes about the contact) on each plate:
    (full, sparse, mesh DOF) per plate."""
    limit = 1024.0 * args.memory_limit_gb
    done: dict[str, list] = {"full": [], "mvm-sparse": []}
    pairs = []
    for far in fars:
        plate, ball = meshes(work, far)
        dof, radius_m = mesh_dof(plate), radius_for(plate, nodes)
        extra = {"far_mm": far, "mesh_dof": dof}
        got = [
            case(kind, plate, ball, radius_m, args.steps, done[kind], "mesh_dof", dof, limit, extra)
            for kind in ("full", "mvm-sparse")
        ]
        print(_line(got[0]) + "\n" + _line(got[1]), flush=True)
        pairs.append((got[0], got[1], dof))
    return pairs


def region_sweep(args, plate: Path, ball: Path, counts: list[int]) -> list:
    """mvm-sparse and mvm (under --dense-limit retained DOF) for each region node count."""
    limit = 1024.0 * args.memory_limit_gb
    done: dict[str, list] = {"mvm-sparse": [], "mvm": []}
    rows = []
    for n in counts:
        r = radius_for(plate, n)
        extra = {"nodes_asked": n}
        sparse = case(
            "mvm-sparse",
            plate,
            ball,
            r,
            args.steps,
            done["mvm-sparse"],
            "nodes_asked",
            n,
            limit,
            extra,
        )
        print(_line(sparse), flush=True)
        dense = None
        if 3 * n <= args.dense_limit:
            dense = case(
                "mvm", plate, ball, r, args.steps, done["mvm"], "nodes_asked", n, limit, extra
            )
            print(_line(dense), flush=True)
        rows.append((n, sparse, dense))
    return rows


def main() -> None:
    from flexmvm.runs.provenance import script_stamp

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--far-mm", default="10,4,2.5,2,1.7,1.2,1")
    ap.add_argument("--nodes", default="10,100,1000,3000,10000")
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--work", default=None)
    ap.add_argument("--dense-limit", type=int, default=4000)
    ap.add_argument("--memory-limit-gb", type=float, default=8.0)
    ap.add_argument("--json", default=None)
    ap.add_argument("--markdown", default=None)
    ap.add_argument("--sweeps", default="body,region", help="of body,region")
    ap.add_argument("--no-warm-up", action="store_true", help="kernels compiled already")
    args = ap.parse_args()
    work = Path(args.work or tempfile.mkdtemp(prefix="flexmvm-scaling-"))
    work.mkdir(parents=True, exist_ok=True)
    load0 = os.getloadavg()
    print(f"CPU: {cpu_name()}; commit {commit_hash()}; {os.cpu_count()} cores; load {load0}")
    fars = [float(x) for x in args.far_mm.split(",")]
    counts = [int(x) for x in args.nodes.split(",")]
    plate, ball = meshes(work, max(fars))
    if not args.no_warm_up:  # numba compiles here, not in the timed runs
        for kind in ("full", "mvm-sparse", "mvm"):
            _run(kind, plate, ball, radius_for(plate, 100), 2)
    first = next((n for n in counts if n >= 100), counts[0])
    pairs, rows, text, ref = [], [], "", None
    if "body" in args.sweeps:
        pairs = body_sweep(args, work, fars, first)
        text += (
            f"Body size (mvm-sparse: the ~{first} nodes about the contact + 60 modes; "
            f"{args.steps} steps of 0.5 us; floor at {STREAM_BYTES_PER_S / 1e9:g} GB/s):\n\n"
            + body_table(pairs)
        )
    if "region" in args.sweeps:  # the plate nearest 48,000 DOF, its full FE as the reference
        far = min(fars, key=lambda f: abs(math.log(mesh_dof(meshes(work, f)[0]) / 48000.0)))
        plate, ball = meshes(work, far)
        ref = _run("full", plate, ball, 0.0, args.steps)
        print(_line(ref), flush=True)
        rows = region_sweep(args, plate, ball, counts)
        text += (
            f"\n\nRegion size on the {mesh_dof(plate):,}-DOF plate ({far:g} mm):\n\n"
            + region_table(ref, rows)
        )
    load1 = os.getloadavg()
    print(f"load at the end {load1}\n\n{text}")
    if args.markdown:
        Path(args.markdown).write_text(text + "\n")
    if args.json:
        keys = ("far_mm", "nodes", "steps", "dense_limit", "sweeps")
        settings = {k: getattr(args, k) for k in keys}
        settings["memory_limit_gb"] = args.memory_limit_gb
        scripts = [Path(__file__), Path(__file__).with_name("bench_ring_body.py")]
        record = {
            "cpu": cpu_name(),
            "cores": os.cpu_count(),
            "load": [load0, load1],
            "body_size": [{"full": f, "mvm-sparse": s, "mesh_dof": d} for f, s, d in pairs],
            "region_size": [{"nodes": n, "mvm-sparse": s, "mvm": d} for n, s, d in rows],
            "region_full": ref,  # the region sweep's full-FE reference (None without it)
            "region_plate_dof": mesh_dof(plate) if rows else None,
            "provenance": script_stamp(scripts, settings),
        }
        Path(args.json).write_text(json.dumps(record, indent=1))


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        kind, plate, ball, radius, steps, out = sys.argv[2:8]
        child(kind, plate, ball, float(radius), int(steps), Path(out))
    else:
        main()
