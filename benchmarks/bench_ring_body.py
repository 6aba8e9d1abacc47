"""The sparse reduced body (kind mvm-sparse: Craig-Bampton with the ring as its only boundary)
against the dense one (kind mvm) and full FE, on the sphere striking the shipped block, for
regions of growing radius: each case in a process of its own, side by side in one run.

    python benchmarks/bench_ring_body.py [--radii-mm 0.5,1.1,2.0] [--modes 20] [--t-end 1e-4]

Prints, per case: DOF, the region's nodes and ring nodes, the dense corner n_c, set-up and
simulation time (wall and CPU of the process), CPU per step, peak resident memory, the force
NCC and peak error against full FE; then the ratios full FE / mvm-sparse and mvm /
mvm-sparse in simulation CPU and memory. CPU time is reported beside wall time because a
shared machine's load moves wall time (docs/notes/ keeps the runs). States the CPU and the
commit. A dense case whose memory would pass --dense-limit-gb is skipped and said so.
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

SCENARIO = Path(__file__).parents[1] / "scenarios" / "sphere_block.toml"


def cpu_name() -> str:
    """The machine's CPU model (lscpu), for the first line of a benchmark's output."""
    out = subprocess.run(["lscpu"], capture_output=True, text=True, check=False).stdout
    for line in out.splitlines():
        if line.startswith("Model name:"):
            return line.split(":", 1)[1].strip()
    return "unknown CPU"


def commit_hash() -> str:
    """The checkout's short commit hash."""
    out = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=False
    )
    return out.stdout.strip() or "unknown"


def child(kind: str, radius_m: float, modes: int, t_end: float, out: Path) -> None:
    """One case: build, simulate, write its numbers as JSON to ``out``."""
    import numpy as np

    import flexmvm as fm
    from flexmvm.assembly.build import build_scenario
    from flexmvm.integrate.driver import simulate

    sc = fm.load_scenario(SCENARIO).with_time(t_end_s=t_end)
    if kind != "full":
        region = {"ball": {"centre_m": [0.0, 0.0, 0.0], "radius_m": radius_m}}
        model = fm.mvm(region=region, modes=modes, kind=fm.ModelKind(kind))
        sc = sc.with_model("block", model.model_copy(update={"allow_costly": True}))
    else:
        sc = sc.with_model("block", fm.full())
    w0, c0 = time.perf_counter(), time.process_time()
    built = build_scenario(sc)
    w1, c1 = time.perf_counter(), time.process_time()
    res = simulate(built.system, built.states, built.grid, built.probes)
    w2, c2 = time.perf_counter(), time.process_time()
    body = built.system.bodies[1]
    corner = getattr(body, "corner", None)
    info = {
        "kind": kind,
        "radius_mm": radius_m * 1e3,
        "dof": int(body.nv),
        "corner": int(corner.size) if corner is not None else None,
        "build_wall_s": w1 - w0,
        "build_cpu_s": c1 - c0,
        "sim_wall_s": w2 - w1,
        "sim_cpu_s": c2 - c1,
        "steps": int(res.n_steps),
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "t": np.asarray(res.t).tolist(),
        "force": np.asarray(res.contact_force).tolist(),
    }
    out.write_text(json.dumps(info))


def _run(kind: str, radius_m: float, modes: int, t_end: float) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "case.json"
        cmd = [sys.executable, __file__, "--child", kind, str(radius_m), str(modes), str(t_end)]
        env = dict(os.environ, FLEXMVM_NO_CACHE="1")  # set-up measured cold, every case
        proc = subprocess.run(
            [*cmd, str(out)], capture_output=True, text=True, check=False, env=env
        )
        if proc.returncode != 0:
            tail = (proc.stderr.strip().splitlines() or ["?"])[-1]
            return {"kind": kind, "radius_mm": radius_m * 1e3, "error": tail}
        return json.loads(out.read_text())


def _line(r: dict, ref: dict | None) -> str:
    if "error" in r:
        return f"{r['kind']:>10} {r['radius_mm']:4.1f} mm: failed: {r['error']}"
    import numpy as np

    from flexmvm.metrics.ncc import ncc

    text = (
        f"{r['kind']:>10} {r['radius_mm']:4.1f} mm: {r['dof']:6d} DOF"
        + (f", corner {r['corner']:5d}" if r["corner"] is not None else "")
        + f"; set-up {r['build_wall_s']:6.1f} s wall {r['build_cpu_s']:6.1f} s CPU"
        f"; simulation {r['sim_wall_s']:6.2f} s wall {r['sim_cpu_s']:6.2f} s CPU"
        f" ({1e3 * r['sim_cpu_s'] / max(r['steps'], 1):.2f} ms CPU a step, {r['steps']} steps)"
        f"; peak RSS {r['peak_rss_mb']:6.0f} MB"
    )
    if ref is not None and "error" not in ref and r is not ref:
        f, fr = np.asarray(r["force"]), np.asarray(ref["force"])
        n = ncc(np.asarray(ref["t"]), fr, np.asarray(r["t"]), f)
        text += f"; force NCC {n:.6f}, peak {100 * (f.max() - fr.max()) / fr.max():+.3f} %"
    return text


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--radii-mm", default="0.5,1.1,2.0")
    ap.add_argument("--modes", type=int, default=20)
    ap.add_argument("--t-end", type=float, default=1e-4)
    ap.add_argument("--skip-dense-above-mm", type=float, default=1.5)
    args = ap.parse_args()
    print(
        f"CPU: {cpu_name()}; commit {commit_hash()}; {os.cpu_count()} cores; load {os.getloadavg()}"
    )
    full = _run("full", 0.0, 0, args.t_end)
    print(_line(full, None), flush=True)
    for r_mm in (float(x) for x in args.radii_mm.split(",")):
        sparse = _run("mvm-sparse", r_mm * 1e-3, args.modes, args.t_end)
        print(_line(sparse, full), flush=True)
        dense = None
        if r_mm <= args.skip_dense_above_mm:
            dense = _run("mvm", r_mm * 1e-3, args.modes, args.t_end)
            print(_line(dense, full), flush=True)
        else:
            print(f"{'mvm':>10} {r_mm:4.1f} mm: skipped (--skip-dense-above-mm)")
        if "error" in sparse or "error" in full:
            continue
        ratio = (
            f"  ratios at {r_mm:.1f} mm: full FE / mvm-sparse simulation CPU "
            f"{full['sim_cpu_s'] / sparse['sim_cpu_s']:.2f}, memory "
            f"{full['peak_rss_mb'] / sparse['peak_rss_mb']:.2f}"
        )
        if dense is not None and "error" not in dense:
            ratio += (
                f"; mvm / mvm-sparse simulation CPU {dense['sim_cpu_s'] / sparse['sim_cpu_s']:.2f}"
                f", set-up CPU {dense['build_cpu_s'] / sparse['build_cpu_s']:.2f}"
                f", memory {dense['peak_rss_mb'] / sparse['peak_rss_mb']:.2f}"
            )
        print(ratio, flush=True)


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        kind, radius, modes, t_end, out = sys.argv[2:7]
        child(kind, float(radius), int(modes), float(t_end), Path(out))
    else:
        main()
