"""The plastic sphere on block (scenarios/sphere_block_plastic.toml) as full FE, as its reduced
form in kind mvm-sparse and in the dense kind mvm (the same region and modes), side by side in
one command: the simulation's CPU and wall time of each, the set-up's CPU, the peak resident
set of each process, and against full FE the force NCC, the peak, the plastic work, the
yielded cells and the permanent dent.

    python benchmarks/bench_plastic_sparse.py [--t-end-s S] [--kinds full,mvm-sparse,mvm]
        [--no-warm-up] [--json FILE]

Every case is a process of its own (benchmarks/bench_showcases.py's form: a ten-step run of
each first compiles the kernels and fills the setup cache as a user has it), run one after
the other; CPU is time.process_time of the process (every thread). Prints the machine and a
markdown table; --json writes the rows, each with the stamp of the resolved scenario it ran
(runs.provenance.stamp), and the record's own (runs.provenance.script_stamp).
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

from bench_ring_body import cpu_name
from bench_showcases import _rss_mb, _Sampler

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = ROOT / "scenarios" / "sphere_block_plastic.toml"
KINDS = ("full", "mvm-sparse", "mvm")


def child(kind: str, t_end: float, out: Path) -> None:
    """One case: build, simulate, write its numbers as JSON to ``out``."""
    import warnings

    import numpy as np

    import flexmvm as fm
    from flexmvm.assembly.build import build_scenario
    from flexmvm.integrate.driver import simulate
    from flexmvm.runs.plastic_summary import plastic_summary
    from flexmvm.runs.provenance import stamp

    sampler = _Sampler()
    c00 = time.process_time()
    sc = fm.load_scenario(SCENARIO)
    if t_end < 0:  # the warm-up: ten steps
        t_end = 10 * sc.time.dt_s
    if t_end > 0:
        sc = sc.with_time(t_end_s=t_end, output_dt_s=min(t_end, sc.time.output_dt_s))
    sc = sc.with_kind(kind)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        c0 = time.process_time()
        built = build_scenario(sc)
        w1, c1 = time.perf_counter(), time.process_time()
        setup_peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
        sampler.reset()
        res = simulate(built.system, built.states, built.grid, built.probes)
        w2, c2 = time.perf_counter(), time.process_time()
    plastic = plastic_summary(res, built)["plastic"]["block"]
    block = built.system.bodies[1]
    info = {
        "kind": kind,
        "t_end_s": float(sc.time.t_end_s),
        "dof": int(block.nv),
        "setup_cpu_s": c1 - c0,
        "sim_wall_s": w2 - w1,
        "sim_cpu_s": c2 - c1,
        "process_cpu_s": c2 - c00,
        "steps": int(res.n_steps),
        "setup_peak_mb": setup_peak,
        "sim_peak_mb": max(sampler.peak, _rss_mb()),
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "provenance": stamp(sc),  # of the resolved scenario this case ran
        "warnings": sorted({f"{w.category.__name__}: {w.message}" for w in caught}),
        "plastic": plastic,
        "cells": (res.plastic["block"].cell_equivalent_plastic_strain > 0).tolist(),
        "t": np.asarray(res.t).tolist(),
        "force": np.asarray(res.contact_force).tolist(),
    }
    out.write_text(json.dumps(info))


def _run(kind: str, t_end: float) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "case.json"
        cmd = [sys.executable, __file__, "--child", kind, str(t_end), str(out)]
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
        if proc.returncode != 0:
            tail = (proc.stderr.strip().splitlines() or ["?"])[-1]
            return {"kind": kind, "error": tail}
        return json.loads(out.read_text())


def compare(full: dict, case: dict) -> dict:
    """A case against full FE: force NCC, peak, plastic work, dent and yielded cells."""
    import numpy as np

    from flexmvm.metrics.ncc import ncc

    row = {k: v for k, v in case.items() if k not in ("t", "force", "cells")}
    if "error" in case or "error" in full:
        return row
    yf, yc = np.array(full["force"]), np.array(case["force"])
    pf, pc = full["plastic"], case["plastic"]
    cf, cc = np.array(full["cells"]), np.array(case["cells"])
    row["peak_n"] = float(yc.max())
    row["ncc"] = float(ncc(np.array(full["t"]), yf, np.array(case["t"]), yc))
    row["peak_diff_pct"] = 100.0 * (yc.max() / yf.max() - 1.0)
    row["plastic_work_diff_pct"] = 100.0 * (pc["plastic_work_J"] / pf["plastic_work_J"] - 1.0)
    dent = pc["permanent_indentation_m"] / pf["permanent_indentation_m"] - 1.0
    row["dent_diff_pct"] = 100.0 * dent
    row["yielded_cells_as_full"] = bool(np.array_equal(cf, cc))
    row["sim_cpu_full_over"] = full["sim_cpu_s"] / case["sim_cpu_s"]
    row["sim_peak_over_full"] = case["sim_peak_mb"] / full["sim_peak_mb"]
    return row


HEAD = (
    "| model | DOF | set-up CPU | simulation CPU (per step) | wall | full / it, CPU |"
    " peak RSS simulation (set-up) | force NCC | peak | plastic work | dent | cells |"
    "\n|---|---|---|---|---|---|---|---|---|---|---|---|"
)


def line(r: dict) -> str:
    if "error" in r:
        return f"| {r['kind']} | failed: {r['error']} |" + " |" * 10
    p = r["plastic"]
    ms = 1e3 * r["sim_cpu_s"] / max(r["steps"], 1)
    vs = "" if "ncc" not in r else f"{r['ncc']:.6f}"
    return (
        f"| {r['kind']} | {r['dof']:,} | {r['setup_cpu_s']:.1f} s |"
        f" {r['sim_cpu_s']:.1f} s ({ms:.0f} ms) | {r['sim_wall_s']:.1f} s |"
        f" {r.get('sim_cpu_full_over', 1.0):.2f} |"
        f" {r['sim_peak_mb']:,.0f} MB ({r['setup_peak_mb']:,.0f} MB) | {vs} |"
        f" {r.get('peak_n', float('nan')):.6g} N ({r.get('peak_diff_pct', 0.0):+.3f} %) |"
        f" {p['plastic_work_J']:.6g} J ({r.get('plastic_work_diff_pct', 0.0):+.3f} %) |"
        f" {p['permanent_indentation_m']:.6g} m ({r.get('dent_diff_pct', 0.0):+.3f} %) |"
        f" {p['plastic_cells']}, {p['cells_yield_outside_retained']} outside |"
    )


def main() -> None:
    from flexmvm.runs.provenance import script_stamp

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end-s", type=float, default=0.0, help="0: the scenario's window")
    ap.add_argument("--kinds", default=",".join(KINDS), help="full first, comma separated")
    ap.add_argument("--json", default=None, help="write the rows and the provenance here")
    ap.add_argument("--no-warm-up", action="store_true", help="skip the 10-step compile runs")
    args = ap.parse_args()
    kinds = [k.strip() for k in args.kinds.split(",") if k.strip()]
    if kinds[0] != "full":
        raise SystemExit("bench_plastic_sparse: --kinds must start with full (the reference)")
    if not args.no_warm_up:  # numba compiles on first use, the setup cache fills
        for kind in kinds:
            _run(kind, -1.0)
    load0 = os.getloadavg()
    print(f"CPU: {cpu_name()}; {os.cpu_count()} cores; load {load0}", flush=True)
    full = _run("full", args.t_end_s)
    rows = [compare(full, full)]
    print(line(rows[-1]), flush=True)
    for kind in kinds[1:]:
        rows.append(compare(full, _run(kind, args.t_end_s)))
        print(line(rows[-1]), flush=True)
    load1 = os.getloadavg()
    print(f"load at the end {load1}\n\n{HEAD}\n" + "\n".join(line(r) for r in rows))
    if args.json:
        settings = {"scenario": str(SCENARIO.relative_to(ROOT)), "t_end_s": args.t_end_s}
        stamp = script_stamp([Path(__file__), ROOT / "benchmarks" / "bench_showcases.py"], settings)
        record = {"cpu": cpu_name(), "load": [load0, load1], "rows": rows, "provenance": stamp}
        Path(args.json).write_text(json.dumps(record, indent=1))


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        kind, t_end, out = sys.argv[2:5]
        child(kind, float(t_end), Path(out))
    else:
        main()
