"""The shipped big-part scenario (scenarios/plate_impact.toml, 263,691 DOF) in full FE and
reduced (its own model, kind mvm-sparse), and a region of ~3,000 retained nodes on it.

    python benchmarks/bench_big_part.py [--work DIR] [--skip-full] [--big-radius-mm 1.25]
        [--t-end-us T]
        [--cases cold,warm,big-cold,big-warm] [--memory-limit-gb 8] [--allow-costly]
        [--json RECORD]

Every case is a process of its own, run one after the other (never two at once: full FE
takes ~10 GB): full FE (FLEXMVM_NO_CACHE=1); the reduced model cold (an empty setup cache in
--work: the basis built, factoring K_EE as full FE factors its W) and warm (the same cache:
the run loads its parts); with --cases big-cold,big-warm the big region (--big-radius-mm:
2,967 nodes, 944 on its ring, a corner of ~2,900 columns): region_estimate (in a process of
its own) is the cost guard's estimate of its cold set-up's peak (assembly/cost_sparse.py: the
largest of its stages, K_EE's factorization, its factor beside psi's exterior rows filled a
block of columns at a time, the parts summed over blocks of rows, the truncation guard, the
contact rows gathered) and big-cold runs only if it is under --memory-limit-gb; the run is
allow_costly only with --allow-costly, else the guard refuses it above half the machine's
memory). Prints the CPU,
the commit, per case the set-up and simulation wall and CPU times (time.process_time: every
thread of the process), the peak RSS after the set-up and at the end, the resident set when
the run starts, and against full FE the simulation ratio, the memory ratio, the force NCC and
the peak's error. The setup log (SETUP_LOG lines: basis and body build times) of each case
is printed under it. --json RECORD writes every case's figures (not its force history)
with the estimate, the machine and the provenance stamp (runs.provenance.script_stamp) for
the pages to read. docs/notes/ quotes the runs, docs/performance.md the ratios.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from bench_ring_body import commit_hash, cpu_name  # the same machine line

from flexmvm.mesh.plate_part import PLATE_MESHES

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = ROOT / "scenarios" / "plate_impact.toml"


def _rss_now_mb() -> float:
    """The process's resident set now [MB] (VmRSS)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return float(line.split()[1]) / 1024.0
    return float("nan")


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


class _StagePeak(logging.Filter):
    """Adds to each setup-log line the largest resident set sampled since the line before."""

    def __init__(self) -> None:
        super().__init__()
        self.peak = 0.0

    def filter(self, record: logging.LogRecord) -> bool:
        record.msg = f"{record.msg} (resident peak since the line before: {self.peak:,.0f} MB)"
        self.peak = 0.0
        return True


def _sample_rss(every_s: float = 0.05) -> None:
    """RSS sampling in a daemon thread: the set-up's stages' peaks (_StagePeak) on the root
    log handler."""
    stage = _StagePeak()
    for handler in logging.getLogger().handlers:
        handler.addFilter(stage)

    def sample() -> None:
        while True:
            stage.peak = max(stage.peak, _rss_now_mb())
            time.sleep(every_s)

    threading.Thread(target=sample, daemon=True).start()


def region_estimate(radius_m: float) -> dict:
    """The cost guard's estimate (assembly/cost_sparse.py, through assembly.body_build's
    body_cost: the ring read off the mesh, the full-FE factor's fill from the setup cache or
    its symbolic analysis) of the plate with the ball region of ``radius_m`` about the top
    face's centre: its nodes, ring, corner, exterior DOFs and the cold set-up's peak with
    the FE model [bytes] (the figure the guard refuses a run on: more than half the
    machine's memory)."""
    import numpy as np

    import flexmvm as fm
    from flexmvm.assembly.body_build import body_cost
    from flexmvm.assembly.build_cache import default_setup
    from flexmvm.assembly.cache_keys import mesh_key
    from flexmvm.assembly.cost import step_sizes
    from flexmvm.assembly.cost_sparse import ring_shape
    from flexmvm.assembly.mesh_lookup import contact_surfaces, retained_nodes
    from flexmvm.assembly.supports import bedded_key, clamp_label

    sc = fm.load_scenario(SCENARIO)
    region = {"ball": {"centre_m": [0.0, 0.0, 0.0], "radius_m": radius_m}}
    cfg = sc.with_model("plate", _with_region(sc.body("plate").model, region)).body("plate")
    setup = default_setup()
    mesh = setup.mesh(mesh_key(cfg))
    nodes = tuple(int(i) for i in retained_nodes(cfg.model, mesh, None, "plate"))
    label = clamp_label(cfg, mesh, sc.supports, nodes)
    key = bedded_key(mesh_key(cfg), cfg, sc.supports)
    sizes = step_sizes(sc.time.dt_s, sc.time.dt_max_s)
    where = (mesh, key, key, label)
    surfaces = contact_surfaces(sc, "plate")
    cost = body_cost(cfg, setup, where, nodes, cfg.model.modes, None, sizes, surfaces)
    fixed = setup.reference_condition(key, mesh, label).fixed_dofs
    shape = ring_shape(mesh, np.asarray(nodes), fixed, cfg.model.modes)
    assert cost is not None
    return {
        "nodes": shape.region_nodes,
        "ring": shape.ring_nodes,
        "corner": shape.corner,
        "exterior_dof": shape.exterior_dof,
        "peak_bytes": cost.fit_bytes,
        "held_bytes": cost.bytes,
        "full_fe_bytes": cost.full_bytes,
    }


def _estimate_apart(radius_m: float) -> dict:
    """region_estimate in a process of its own: the cases' peak RSS (ru_maxrss, which a
    child starts from its parent's resident set at the fork) not raised by the estimate's."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "estimate.json"
        cmd = [sys.executable, __file__, "--estimate", str(radius_m), str(out)]
        subprocess.run(cmd, capture_output=True, text=True, check=True)
        return json.loads(out.read_text())


def _with_region(model, region: dict, allow: bool = False):
    """``model`` (a ModelConfig) with ``region`` (and allow_costly when ``allow``), validated."""
    fields = {"region": region, "selection": None} | ({"allow_costly": True} if allow else {})
    return type(model).model_validate({**model.model_dump(), **fields})


def child(kind: str, radius_m: float, t_end: float, out: Path, allow: bool = False) -> None:
    """One case: build, simulate, write its numbers as JSON to ``out``; ``allow``: the region
    allow_costly (built whatever the cost guard's refusal)."""
    import numpy as np

    import flexmvm as fm
    from flexmvm.assembly.build import build_scenario
    from flexmvm.integrate.driver import simulate

    logging.basicConfig(level=logging.INFO, format="    %(message)s", stream=sys.stderr)
    _sample_rss()
    sc = fm.load_scenario(SCENARIO)
    if t_end > 0:
        sc = sc.with_time(t_end_s=t_end)
    if kind == "full":
        sc = sc.with_model("plate", fm.full())
    elif radius_m > 0:
        region = {"ball": {"centre_m": [0.0, 0.0, 0.0], "radius_m": radius_m}}
        # without allow: the cost guard refuses a region whose set-up would not fit
        sc = sc.with_model("plate", _with_region(sc.body("plate").model, region, allow))
    w0, c0 = time.perf_counter(), time.process_time()
    built = build_scenario(sc)
    w1, c1 = time.perf_counter(), time.process_time()
    setup_peak, start_rss = _peak_mb(), _rss_now_mb()
    res = simulate(built.system, built.states, built.grid, built.probes)
    w2, c2 = time.perf_counter(), time.process_time()
    body = built.system.bodies[1]
    corner = getattr(body, "corner", None)
    info = {
        "kind": kind,
        "radius_mm": radius_m * 1e3,
        "dof": int(body.nv),
        "retained": int(built.info[1].n_retained_nodes),
        "corner": int(corner.size) if corner is not None else None,
        "build_wall_s": w1 - w0,
        "build_cpu_s": c1 - c0,
        "sim_wall_s": w2 - w1,
        "sim_cpu_s": c2 - c1,
        "steps": int(res.n_steps),
        "setup_peak_mb": setup_peak,
        "start_rss_mb": start_rss,
        "peak_rss_mb": _peak_mb(),
        "t": np.asarray(res.t).tolist(),
        "force": np.asarray(res.contact_force).tolist(),
    }
    out.write_text(json.dumps(info))


def _run(
    kind: str, radius_m: float, t_end: float, env: dict, label: str, allow: bool = False
) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "case.json"
        cmd = [sys.executable, __file__, "--child", kind, str(radius_m), str(t_end), str(out)]
        cmd += ["allow"] if allow else []
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False, env=env)
        log = [ln for ln in proc.stderr.splitlines() if ln.startswith("    ")]
        if proc.returncode != 0:
            tail = (proc.stderr.strip().splitlines() or ["?"])[-1]
            return {"label": label, "error": tail, "log": log}
        return json.loads(out.read_text()) | {"label": label, "log": log}


def _line(r: dict, ref: dict | None) -> str:
    if "error" in r:
        return f"{r['label']}: failed: {r['error']}"
    import numpy as np

    from flexmvm.metrics.ncc import ncc

    peak = max(r["force"])
    text = (
        f"{r['label']}: {r['dof']:,} DOF ({r['retained']:,} retained nodes"
        + (f", corner {r['corner']:,}" if r["corner"] is not None else "")
        + f"); set-up {r['build_wall_s']:.1f} s wall {r['build_cpu_s']:.1f} s CPU, peak RSS"
        f" {r['setup_peak_mb']:,.0f} MB; run starts at {r['start_rss_mb']:,.0f} MB;"
        f" simulation {r['sim_wall_s']:.1f} s wall {r['sim_cpu_s']:.1f} s CPU ({r['steps']}"
        f" steps, {1e3 * r['sim_cpu_s'] / max(r['steps'], 1):.1f} ms CPU a step); peak RSS"
        f" {r['peak_rss_mb']:,.0f} MB; peak force {peak:.2f} N"
    )
    if ref is not None and "error" not in ref:
        rho = ncc(np.array(ref["t"]), np.array(ref["force"]), np.array(r["t"]), r["force"])
        err = peak / max(ref["force"]) - 1.0
        text += (
            f"\n    against full FE: simulation CPU {ref['sim_cpu_s'] / r['sim_cpu_s']:.1f} x,"
            f" wall {ref['sim_wall_s'] / r['sim_wall_s']:.1f} x; peak RSS"
            f" {r['peak_rss_mb'] / ref['peak_rss_mb']:.3f} of full FE's; force NCC {rho:.6f},"
            f" peak {100 * err:+.3f} %"
        )
    return "\n".join([text, *r["log"]])


def _record_case(r: dict, ref: dict | None) -> dict:
    """A case's figures for the --json record: its numbers without the force history and
    log, with its force peak [N] and, against full FE, the simulation ratios, the memory
    ratio, the force NCC and the peak's error."""
    import numpy as np

    from flexmvm.metrics.ncc import ncc

    row = {k: v for k, v in r.items() if k not in ("t", "force", "log")}
    if "error" in r:
        return row
    row["peak_force_n"] = max(r["force"])
    if ref is not None and "error" not in ref and r is not ref:
        row["vs_full"] = {
            "sim_cpu_ratio": ref["sim_cpu_s"] / r["sim_cpu_s"],
            "sim_wall_ratio": ref["sim_wall_s"] / r["sim_wall_s"],
            "peak_rss_fraction": r["peak_rss_mb"] / ref["peak_rss_mb"],
            "force_ncc": ncc(
                np.array(ref["t"]), np.array(ref["force"]), np.array(r["t"]), r["force"]
            ),
            "peak_error": max(r["force"]) / max(ref["force"]) - 1.0,
        }
    return row


def _write_record(path: Path, settings: dict, cases: list, estimate, ref) -> None:
    """The --json record (module doc), written atomically."""
    from flexmvm.runs.provenance import script_stamp

    record = {
        "cpu": cpu_name(),
        "cores": os.cpu_count(),
        "load": list(os.getloadavg()),
        "full": None if ref is None else _record_case(ref, None),
        "cases": [_record_case(r, ref) for r in cases],
        "estimate": estimate,
        "provenance": script_stamp(
            [Path(__file__), ROOT / "benchmarks" / "bench_ring_body.py"], settings
        ),
    }
    tmp = path.with_name(path.name + ".partial")
    tmp.write_text(json.dumps(record, indent=1) + "\n")
    os.replace(tmp, path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", default=None, help="setup cache of the reduced cases")
    ap.add_argument("--skip-full", action="store_true", help="use --work's stored full FE case")
    ap.add_argument("--cases", default="cold,warm", help="of cold,warm,big-cold,big-warm")
    ap.add_argument("--big-radius-mm", type=float, default=1.25)  # ~3,000 nodes
    ap.add_argument("--t-end-us", type=float, default=0.0, help="0: the scenario's")
    ap.add_argument("--memory-limit-gb", type=float, default=8.0, help="big-cold above: no run")
    ap.add_argument("--json", type=Path, default=None, help="write the stamped record here")
    ap.add_argument(
        "--allow-costly",
        action="store_true",
        help="build the big region allow_costly (the guard refuses it above half the machine)",
    )
    args = ap.parse_args()
    work = Path(args.work or tempfile.mkdtemp(prefix="flexmvm-bigpart-"))
    work.mkdir(parents=True, exist_ok=True)
    for name, make in PLATE_MESHES:  # the plate's mesh is made, not kept in git
        if not (SCENARIO.parent / "meshes" / name).exists():
            print(f"meshing {name} (gmsh)", flush=True)
            make(SCENARIO.parent / "meshes" / name)
    print(
        f"CPU: {cpu_name()}; commit {commit_hash()}; {os.cpu_count()} cores;"
        f" load {os.getloadavg()}; setup cache {work}",
        flush=True,
    )
    t_end = args.t_end_us * 1e-6
    stored = work / "full.json"  # the full-FE case of an earlier call on this --work
    if args.skip_full:
        ref = json.loads(stored.read_text()) if stored.exists() else None
        if ref is not None:
            print("(stored) " + _line(ref, None), flush=True)
    else:
        env = dict(os.environ, FLEXMVM_NO_CACHE="1")
        ref = _run("full", 0.0, t_end, env, "full FE")
        stored.write_text(json.dumps(ref))
        print(_line(ref, None), flush=True)
    cases = [
        ("reduced cold", 0.0, "cold"),
        ("reduced warm", 0.0, "warm"),
        (f"region {args.big_radius_mm:g} mm cold", args.big_radius_mm * 1e-3, "big"),
        (f"region {args.big_radius_mm:g} mm warm", args.big_radius_mm * 1e-3, "big"),
    ]
    chosen, est, done = args.cases.split(","), None, []
    if "big-cold" in chosen:
        est = _estimate_apart(args.big_radius_mm * 1e-3)
        print(f"region {args.big_radius_mm:g} mm estimated: {est}", flush=True)
        if est["peak_bytes"] > args.memory_limit_gb * 1e9:
            print(f"  over --memory-limit-gb {args.memory_limit_gb:g}: not run", flush=True)
            chosen = [c for c in chosen if not c.startswith("big")]
    names = ("cold", "warm", "big-cold", "big-warm")
    for name, (label, radius, cache) in zip(names, cases, strict=True):
        if name not in chosen:
            continue
        if name.endswith("cold"):  # an empty setup cache
            shutil.rmtree(work / cache, ignore_errors=True)
        env = dict(os.environ, FLEXMVM_CACHE_DIR=str(work / cache))
        env.pop("FLEXMVM_NO_CACHE", None)
        if cache == "warm":
            env["FLEXMVM_CACHE_DIR"] = str(work / "cold")
        allow = args.allow_costly and name.startswith("big")
        done.append(_run("mvm-sparse", radius, t_end, env, label, allow))
        print(_line(done[-1], ref), flush=True)
    if args.json is not None:
        settings = {
            "cases": args.cases,
            "big_radius_mm": args.big_radius_mm,
            "t_end_us": args.t_end_us,
            "memory_limit_gb": args.memory_limit_gb,
            "allow_costly": args.allow_costly,
        }
        _write_record(args.json, settings, done, est, ref)
        print(f"record: {args.json}", flush=True)


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        kind, radius, t_end, out = sys.argv[2:6]
        child(kind, float(radius), float(t_end), Path(out), sys.argv[6:7] == ["allow"])
    elif len(sys.argv) > 1 and sys.argv[1] == "--estimate":
        Path(sys.argv[3]).write_text(json.dumps(region_estimate(float(sys.argv[2]))))
    else:
        main()
