"""Every shipped showcase as full FE and as its reduced model, side by side in one run: the
simulation's CPU and wall time of each, their ratio, the peak resident set of each (the set-up's
and the simulation's), the force NCC and the peak's difference
(without contact, slider_crank: of the velocity of its probe "mid").

    python benchmarks/bench_showcases.py [--scenario scenarios/sphere_beam.toml ...]
        [--t-end-s 1e-3] [--json FILE]

Default: the seven shipped non-rod showcases with a reduced form (SHOWCASES), each over its own
window (--t-end-s shortens every one of them). Full FE is ``flexmvm run --model full``; the
reduced model is the scenario as shipped when it already has a reduced body
(arm_stop_flexible: the arm mvm, the stop full FE), else ``--model mvm-moving`` when a body
has a moving region's windows (cam_follower: the windows switch during the simulation, timed
with it), else ``--model mvm`` (each body's own region and modes; sphere_block_plastic
``--model mvm-sparse``, REDUCED_KIND). Every case is a process of its own, run one after the other (the setup cache
as a user has it: FLEXMVM_CACHE_DIR or the default), CPU time is time.process_time of the
process over the simulation alone (every thread; a ten-step run of each case first compiles
the kernels), the simulation's resident peak is sampled
every 20 ms. Prints the machine (CPU, cores, load at the start and the end) and a markdown
table; --json writes the rows with the provenance stamp (runs.provenance.script_stamp).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from bench_ring_body import cpu_name  # the same machine line

ROOT = Path(__file__).resolve().parent.parent
SHOWCASES = (
    "scenarios/sphere_block.toml",
    "scenarios/sphere_beam.toml",
    "scenarios/arm_stop.toml",
    "scenarios/arm_stop_flexible.toml",
    "scenarios/sphere_block_plastic.toml",
    "scenarios/slider_crank.toml",
    "scenarios/cam_follower.toml",
)


def _rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return float(line.split()[1]) / 1024.0
    return float("nan")


class _Sampler:
    """The largest resident set [MB] sampled every ``every_s`` since the last reset."""

    def __init__(self, every_s: float = 0.02) -> None:
        self.peak = 0.0
        self._every = every_s
        threading.Thread(target=self._run, daemon=True).start()

    def _run(self) -> None:
        while True:
            self.peak = max(self.peak, _rss_mb())
            time.sleep(self._every)

    def reset(self) -> None:
        self.peak = _rss_mb()


#: the showcases whose reduced form is another kind than --model mvm (scenario name: kind)
REDUCED_KIND = {"sphere_block_plastic": "mvm-sparse"}


def reduced_form(sc):
    """The scenario as shipped if one of its bodies is already reduced, else --model
    mvm-moving when a body carries a moving region's windows (cam_follower), else --model
    mvm (or REDUCED_KIND's)."""
    from flexmvm.reduction.kinds.registry import ModelKind

    shipped = {b.model.kind for b in sc.bodies if b.model.kind.spec.has_basis}
    if shipped - {ModelKind("full")}:
        return sc
    moving = any(getattr(b.model, "moving", None) is not None for b in sc.bodies)
    return sc.with_kind("mvm-moving" if moving else REDUCED_KIND.get(sc.name, "mvm"))


def child(path: str, model: str, t_end: float, out: Path) -> None:
    """One case: build, simulate, write its numbers as JSON to ``out``."""
    import numpy as np

    import flexmvm as fm
    from flexmvm.assembly.build import build_scenario
    from flexmvm.integrate.driver import simulate

    sampler = _Sampler()
    sc = fm.load_scenario(ROOT / path)
    if t_end < 0:  # the warm-up: ten steps
        t_end = 10 * sc.time.dt_s
    if t_end > 0:
        sc = sc.with_time(t_end_s=t_end, output_dt_s=min(t_end, sc.time.output_dt_s))
    sc = sc.with_kind("full") if model == "full" else reduced_form(sc)
    w0, c0 = time.perf_counter(), time.process_time()
    built = build_scenario(sc)
    w1, c1 = time.perf_counter(), time.process_time()
    setup_peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    sampler.reset()
    res = simulate(built.system, built.states, built.grid, built.probes, switches=built.switches)
    w2, c2 = time.perf_counter(), time.process_time()
    info = {
        "scenario": sc.name,
        "model": model,
        "t_end_s": float(sc.time.t_end_s),
        "dof": int(sum(b.nv for b in built.system.bodies)),
        "setup_wall_s": w1 - w0,
        "setup_cpu_s": c1 - c0,
        "sim_wall_s": w2 - w1,
        "sim_cpu_s": c2 - c1,
        "steps": int(res.n_steps),
        "setup_peak_mb": setup_peak,
        "sim_peak_mb": max(sampler.peak, _rss_mb()),
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "t": np.asarray(res.t).tolist(),
        "force": np.asarray(res.contact_force).tolist(),
    }
    curves = res.curves()[2]  # without contact (slider_crank): a probe's velocity instead
    if curves:
        name = "mid" if "mid" in curves else next(iter(curves))
        info["probe"], info["probe_v"] = name, np.asarray(curves[name]).tolist()
    out.write_text(json.dumps(info))


def _run(path: str, model: str, t_end: float) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "case.json"
        cmd = [sys.executable, __file__, "--child", path, model, str(t_end), str(out)]
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
        if proc.returncode != 0:
            tail = (proc.stderr.strip().splitlines() or ["?"])[-1]
            return {"scenario": Path(path).stem, "model": model, "error": tail}
        return json.loads(out.read_text())


def compare(full: dict, red: dict) -> dict:
    """The row of one showcase: ratios, NCC and the peak's difference."""
    import numpy as np

    from flexmvm.metrics.ncc import ncc

    if "error" in full or "error" in red:
        return {"scenario": full["scenario"], "error": full.get("error") or red.get("error")}
    what = "force"
    if max(full["force"]) <= 0.0 and "probe_v" in full:  # no contact: the probe's velocity
        what = "probe_v"
    yf, yr = np.array(full[what]), np.array(red[what])
    pf, pr = float(np.max(np.abs(yf))), float(np.max(np.abs(yr)))
    rho = ncc(np.array(full["t"]), yf, np.array(red["t"]), yr)
    keep = ("dof", "steps", "setup_cpu_s", "sim_cpu_s", "sim_wall_s", "setup_peak_mb")
    keep += ("sim_peak_mb", "peak_rss_mb")
    return {
        "scenario": full["scenario"],
        "t_end_s": full["t_end_s"],
        "full": {k: full[k] for k in keep},
        "reduced": {k: red[k] for k in keep},
        "cpu_ratio": full["sim_cpu_s"] / red["sim_cpu_s"],
        "wall_ratio": full["sim_wall_s"] / red["sim_wall_s"],
        "sim_memory_ratio": red["sim_peak_mb"] / full["sim_peak_mb"],
        "compared": "contact force [N]" if what == "force" else f"probe {full['probe']} v",
        "ncc": float(rho),
        "peak_full_n": pf,
        "peak_reduced_n": pr,
        "peak_diff_pct": 100.0 * (pr - pf) / pf,
    }


HEAD = (
    "| showcase (window) | DOF full / reduced | simulation CPU full / reduced | wall full /"
    " reduced | CPU ratio | wall ratio | peak RSS full / reduced (simulation; set-up) |"
    " NCC | peak full / reduced |\n|---|---|---|---|---|---|---|---|---|"
)


def row(r: dict) -> str:
    if "error" in r:
        return f"| {r['scenario']} | failed: {r['error']} | | | | | | | |"
    f, m = r["full"], r["reduced"]
    return (
        f"| {r['scenario']} ({1e3 * r['t_end_s']:.3g} ms) | {f['dof']:,} / {m['dof']:,} |"
        f" {f['sim_cpu_s']:.1f} / {m['sim_cpu_s']:.1f} s | {f['sim_wall_s']:.1f} /"
        f" {m['sim_wall_s']:.1f} s | {r['cpu_ratio']:.1f} | {r['wall_ratio']:.1f} |"
        f" {f['sim_peak_mb']:,.0f} / {m['sim_peak_mb']:,.0f} MB; {f['setup_peak_mb']:,.0f} /"
        f" {m['setup_peak_mb']:,.0f} MB | {r['ncc']:.5f} | {r['peak_full_n']:.4g} /"
        f" {r['peak_reduced_n']:.4g} ({r['peak_diff_pct']:+.2f} %) {r['compared']} |"
    )


def main() -> None:
    from flexmvm.runs.provenance import script_stamp

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", action="append", default=None)
    ap.add_argument("--t-end-s", type=float, default=0.0, help="0: each scenario's window")
    ap.add_argument("--json", default=None, help="write the rows and the provenance here")
    ap.add_argument("--no-warm-up", action="store_true", help="skip the 10-step compile runs")
    args = ap.parse_args()
    paths = args.scenario or SHOWCASES
    if not args.no_warm_up:  # numba compiles on first use: not in the timed runs
        for path in paths:
            for model in ("full", "mvm"):
                _run(path, model, -1.0)
    load0 = os.getloadavg()
    print(f"CPU: {cpu_name()}; {os.cpu_count()} cores; load {load0}", flush=True)
    rows = []
    for path in paths:
        rows.append(compare(_run(path, "full", args.t_end_s), _run(path, "mvm", args.t_end_s)))
        print(row(rows[-1]), flush=True)
    load1 = os.getloadavg()
    print(f"load at the end {load1}\n\n{HEAD}\n" + "\n".join(row(r) for r in rows))
    if args.json:
        settings = {"scenarios": list(paths), "t_end_s": args.t_end_s}
        stamp = script_stamp([Path(__file__), ROOT / "benchmarks" / "bench_ring_body.py"], settings)
        record = {"cpu": cpu_name(), "load": [load0, load1], "rows": rows, "provenance": stamp}
        Path(args.json).write_text(json.dumps(record, indent=1))


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        path, model, t_end, out = sys.argv[2:6]
        child(path, model, float(t_end), Path(out))
    else:
        main()
