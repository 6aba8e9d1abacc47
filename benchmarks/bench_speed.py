"""Speed of the seed case (issue 10): simulation walls, end-to-end commands, basis builds.

    python benchmarks/bench_speed.py [--quick] [--vs REV] [--main-job] [--scaling]
                                     [--figure PNG] [--out benchmarks/results] [--write-docs]

Every figure comes from a fresh Python process, as a user would see it (after one warm-up
process that compiles the numba kernels, reported apart). Prints a table and writes
speed_<commit>.json (with the machine: CPU model, cores, memory, load average, versions).
With --write-docs it also rewrites the "Current figures" block of docs/performance.md from
this run (speed_page.py: ratios of walls measured side by side here, absolute times, the
machine; no code version on the page). Items:

- all-MVM seed run (both rods MVM, the scenario's selections), 2 ms: simulation wall, ms per
  step; full FE over the same 2 ms and the ratio of the two walls (same run, same machine);
- the scenario as shipped (b1 full FE, b2 MVM 1-3 + 37), 2 ms;
- `flexmvm run scenarios/rod_impact.toml --model mvm --no-fields` end to end, first run (empty
  setup cache) and second run;
- one Craig-Bampton basis (b2, 1-3 + 43 modes) built cold (no disk cache);
- --main-job: README command 1 after install (both runs, theory, files, figure), and the
  walls of its shipped model and full-FE reference, run side by side (its summary.json);
- --scaling: time per contact step against b2's retained nodes and modes, and a full-FE
  step against the mesh size;
- --vs REV: the all-MVM, shipped-scenario and full-FE runs (over --vs-t-end, default 0.2 ms)
  of another commit, checked out in a temporary git worktree, next to this code's in the same
  run; and this code's full-FE run on one thread (FLEXMVM_THREADS=1) against two.
--quick shortens the 2 ms runs to 0.4 ms (for a look, not for the record).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from speed_page import load_average, machine_facts, write_page

from flexmvm.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "rod_impact.toml"

# run in a child process: build a scenario variant, simulate, print one JSON line
_SIM = r"""
import json, sys, time
from flexmvm.scenarios import load_scenario
from flexmvm.assembly.build import build_scenario
from flexmvm.integrate.driver import simulate
path, model, t_end = sys.argv[1], sys.argv[2], float(sys.argv[3])
sc = load_scenario(path).with_overrides(model=None if model == "scenario" else model,
                                         t_end_s=t_end, dt_s=None)
t0 = time.perf_counter()
built = build_scenario(sc)
t_build = time.perf_counter() - t0
res = simulate(built.system, built.states, built.grid, built.probes)
print(json.dumps({"build_s": t_build, "wall_s": res.wall_time_s, "n_steps": res.n_steps,
                  "peak_N": float(res.contact_force.max()),
                  "dof": [6 + b.nq for b in built.system.bodies],
                  "nonrotating_steps": getattr(res, "n_nonrotating_steps", None)}))
"""

_BASIS = r"""
import json, time
import numpy as np
from flexmvm.fe.assembly import assemble
from flexmvm.materials import ALUMINIUM
from flexmvm.mesh.rod import RodSpec, rod_mesh
from flexmvm.reduction.basis import BasisKind, build_basis
from flexmvm.reduction.rod_reference import rod_reference
rod = rod_mesh(RodSpec())
fe = assemble(rod.mesh, ALUMINIUM)
t0 = time.perf_counter()
b = build_basis(fe, BasisKind.CRAIG_BAMPTON, rod_reference(rod), retained_nodes=rod.selection(1, 3),
                n_modes=43)
print(json.dumps({"basis_s": time.perf_counter() - t0, "nq": b.nq}))
"""


def _child(code: str, args: list[str], env: dict | None = None) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", code, *args],
        capture_output=True,
        text=True,
        env={**os.environ, **(env or {})},
        cwd=ROOT,
        check=False,
    )
    if out.returncode != 0:
        raise SystemExit(f"benchmark child failed: {out.stderr.strip().splitlines()[-1:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def _sim(model: str, t_end: float, env: dict | None = None, path: Path = SCENARIO) -> dict:
    r = _child(_SIM, [str(path), model, repr(t_end)], env)
    r["ms_per_step"] = 1e3 * r["wall_s"] / max(r["n_steps"], 1)
    return r


def _command(args: list[str], env: dict) -> float:
    t0 = time.perf_counter()
    out = subprocess.run(
        ["flexmvm", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env={**os.environ, **env},
        check=False,
    )
    if out.returncode != 0:
        raise SystemExit(f"flexmvm {' '.join(args)} failed: {out.stderr.strip()[-300:]}")
    return time.perf_counter() - t0


def _commit(repo: Path = ROOT) -> str:
    return (
        subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            cwd=repo,
            check=False,
        ).stdout.strip()
        or "unknown"
    )


def _seed_runs(t_end: float, cache: dict) -> dict:
    out = {
        "all_mvm": _sim("mvm", t_end, cache),
        "full": _sim("full", t_end, cache),
        "shipped": _sim("scenario", t_end, cache),
    }
    out["full_over_mvm"] = out["full"]["wall_s"] / out["all_mvm"]["wall_s"]
    return out


def _commands(tmp: Path) -> dict:
    cache = {"FLEXMVM_CACHE_DIR": str(tmp / "cmd_cache")}
    args = ["run", str(SCENARIO), "--model", "mvm", "--no-fields", "--out", str(tmp / "cmd")]
    first = _command(args, cache)
    return {"all_mvm_command_first_s": first, "all_mvm_command_second_s": _command(args, cache)}


def _scaling(t_end: float, cache: dict, tmp: Path) -> dict:
    """ms per step of the all-MVM case with b2's selection/modes varied (b1 as shipped), and
    of the full-FE flat case against the rods' mesh (O-grid rings 1, 2, 3)."""
    return {
        "b2_selection_modes": _scaling_selection(t_end, cache, tmp),
        "full_fe_mesh": _scaling_mesh(cache, tmp),
    }


def _scaling_mesh(cache: dict, tmp: Path) -> list[dict]:
    flat = ROOT / "scenarios" / "rod_impact_flat.toml"
    rows = []
    for rings in (1, 2, 3):
        path = tmp / f"mesh_rings{rings}.toml"
        text = flat.read_text().replace('end_b = "flat"\n', f'end_b = "flat"\nn_rings = {rings}\n')
        path.write_text(text)
        r = _sim("full", 1e-4, cache, path)
        rows.append(
            {
                "n_rings": rings,
                "dof": r["dof"],
                "ms_per_step": r["ms_per_step"],
                "nonrotating_steps": r["nonrotating_steps"],
                "n_steps": r["n_steps"],
            }
        )
    return rows


def _scaling_selection(t_end: float, cache: dict, tmp: Path) -> list[dict]:
    rows = []
    for sel, modes in (
        ("1-1", 37),
        ("1-3", 37),
        ("2-4", 37),
        ("4-5", 37),
        ("1-3", 7),
        ("1-3", 19),
        ("1-3", 43),
    ):
        path = tmp / f"scaling_{sel}_{modes}.toml"
        text = SCENARIO.read_text().replace('selection = "1-3"', f'selection = "{sel}"')
        text = text.replace("modes = 37", f"modes = {modes}")
        path.write_text(text)
        r = _sim("mvm", t_end, cache, path)
        rows.append(
            {
                "b2_selection": sel,
                "b2_modes": modes,
                "dof": r["dof"],
                "ms_per_step": r["ms_per_step"],
            }
        )
    return rows


def _figure(scaling: dict, path: Path) -> None:
    """Time per step against b2's DOF (selection and modes) and against full-FE DOF."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    for rows, mark, lab in (
        (scaling["b2_selection_modes"][:4], "o-", "37 modes, selection 1-1..4-5"),
        (
            scaling["b2_selection_modes"][4:] + scaling["b2_selection_modes"][1:2],
            "s--",
            "selection 1-3, modes 7..43",
        ),
    ):
        rows = sorted(rows, key=lambda r: r["dof"][1])
        a.plot([r["dof"][1] for r in rows], [r["ms_per_step"] for r in rows], mark, label=lab)
    a.set_xlabel("b2 DOF (b1 MVM 3-5 + 40 fixed)")
    a.set_ylabel("ms per step")
    a.set_title("all-MVM seed case")
    a.legend()
    rows = scaling["full_fe_mesh"]
    b.plot([sum(r["dof"]) for r in rows], [r["ms_per_step"] for r in rows], "o-")
    b.set_xlabel("DOF of both rods (full FE, rings 1, 2, 3)")
    b.set_ylabel("ms per step")
    b.set_title("flat case, full FE")
    for ax in (a, b):
        ax.grid(True, alpha=0.3)
        ax.set_ylim(bottom=0)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _vs(rev: str, t_end: float, tmp: Path) -> dict:
    wt = tmp / "vs_worktree"
    subprocess.run(["git", "worktree", "add", "-q", "--detach", str(wt), rev], cwd=ROOT, check=True)
    try:
        env = {"PYTHONPATH": str(wt / "src"), "FLEXMVM_CACHE_DIR": str(tmp / "vs_cache")}
        _warm(env)  # the worktree's numba kernels compile here, not inside its timed runs
        old = {k: _sim(model, t_end, env) for k, model in _VS_CASES}
        old["commit"] = _commit(wt)
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(wt)], cwd=ROOT, check=False)
    cache = {"FLEXMVM_CACHE_DIR": str(tmp / "vs_cache_new")}
    _warm(cache)
    new = {k: _sim(model, t_end, cache) for k, model in _VS_CASES}
    # the two full-FE bodies' work on one thread (FLEXMVM_THREADS=1): what the threads give
    new["full_one_thread"] = _sim("full", t_end, {**cache, "FLEXMVM_THREADS": "1"})
    out = {"t_end_s": t_end, "old": old, "new": new}
    for k, _ in _VS_CASES:
        out[f"speedup_{k}"] = old[k]["wall_s"] / new[k]["wall_s"]
    out["threads_gain_full"] = new["full_one_thread"]["wall_s"] / new["full"]["wall_s"]
    return out


_VS_CASES = (("all_mvm", "mvm"), ("shipped", "scenario"), ("full", "full"))
TINY = ROOT / "tests" / "data" / "tiny_impact.toml"


def _warm(env: dict) -> None:
    """Compile (or load) every numba kernel of the code on PYTHONPATH: tiny runs of every
    model kind the timed runs use (each kernel compiles on its first call, in the loop)."""
    for model in ("mvm", "full"):
        _sim(model, 5e-6, env, TINY)


def _main_job(tmp: Path) -> dict:
    """README command 1 end to end, and the simulation walls of its two runs (the shipped
    model and the full-FE reference, side by side in two processes) from its summary.json."""
    out = tmp / "main"
    wall = _command(
        ["run", str(SCENARIO), "--out", str(out)], {"FLEXMVM_CACHE_DIR": str(tmp / "mc")}
    )
    summary = json.loads((out / "summary.json").read_text())
    if "reference_full" not in summary:
        raise SystemExit(f"bench_speed: {SCENARIO.name}'s main job ran no full-FE reference")
    runs = {
        "shipped_wall_s": summary["wall_time_s"],
        "full_wall_s": summary["reference_full"]["wall_time_s"],
    }
    return {"main_job_s": wall, "main_job_runs": runs}


def _print(res: dict) -> None:
    s = res["seed_runs"]
    print(f"commit {res['commit']}, t_end {res['t_end_s'] * 1e3:g} ms, {res['machine']['cpu']}")
    print(f"{'quantity':58s} {'value':>12s}")
    for key, label in (
        ("all_mvm", "all-MVM seed run, simulation wall [s]"),
        ("full", "full-FE reference, simulation wall [s]"),
        ("shipped", "seed run as shipped (b1 full, b2 MVM) [s]"),
    ):
        r = s[key]
        print(
            f"{label:58s} {r['wall_s']:12.2f}   ({r['ms_per_step']:.2f} ms/step, "
            f"{r['n_steps']} steps, build {r['build_s']:.1f} s)"
        )
    print(f"{'full FE / all-MVM wall-time ratio':58s} {s['full_over_mvm']:12.1f}")
    for key, label in (
        ("kernel_compile_s", "numba kernels, first-run compilation (once) [s]"),
        ("all_mvm_command_first_s", "all-MVM command end to end, first run [s]"),
        ("all_mvm_command_second_s", "all-MVM command end to end, second run [s]"),
        ("basis_s", "one CB basis (1-3 + 43 modes), cold [s]"),
        ("main_job_s", "main job (README command 1, after install) [s]"),
    ):
        if key in res:
            print(f"{label:58s} {res[key]:12.2f}")
    if "main_job_runs" in res:
        mj = res["main_job_runs"]
        print(
            f"  inside it, side by side: shipped model {mj['shipped_wall_s']:.2f} s, full-FE "
            f"reference {mj['full_wall_s']:.2f} s"
        )
    if "vs" in res:
        v = res["vs"]
        print(f"vs {v['old']['commit']} over {v['t_end_s'] * 1e3:g} ms (simulation walls):")
        for k, _ in _VS_CASES:
            print(
                f"  {k:10s} {v['old'][k]['wall_s']:8.2f} s -> {v['new'][k]['wall_s']:8.2f} s "
                f"({v[f'speedup_{k}']:.2f}x)"
            )
        print(
            f"  full FE on one thread {v['new']['full_one_thread']['wall_s']:.2f} s: two "
            f"threads {v['threads_gain_full']:.2f}x"
        )
    for row in res.get("scaling", {}).get("b2_selection_modes", []):
        print(
            f"  b2 {row['b2_selection']} + {row['b2_modes']:2d} modes, DOF {row['dof']}: "
            f"{row['ms_per_step']:.2f} ms/step"
        )
    for row in res.get("scaling", {}).get("full_fe_mesh", []):
        print(
            f"  full FE flat case, {row['n_rings']} rings, DOF {row['dof']}: "
            f"{row['ms_per_step']:.1f} ms/step"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="0.4 ms instead of 2 ms")
    ap.add_argument("--vs", metavar="REV", help="also run the quick cases on this git revision")
    ap.add_argument("--vs-t-end", type=float, default=2e-4)
    ap.add_argument("--main-job", action="store_true")
    ap.add_argument("--scaling", action="store_true")
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    ap.add_argument("--figure", type=Path, help="scaling figure (PNG), with --scaling")
    ap.add_argument(
        "--write-docs",
        action="store_true",
        help="rewrite the Current figures block of docs/performance.md from this run",
    )
    args = ap.parse_args()
    t_end = 4e-4 if args.quick else 2e-3
    res: dict = {"commit": _commit(), "t_end_s": t_end, "cpu_count": os.cpu_count()}
    res["machine"] = machine_facts()
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        cache = {"FLEXMVM_CACHE_DIR": str(tmp / "cache")}
        # every child process's numba cache in an empty directory of this run: the first
        # process compiles every kernel (cache=True keeps them), whatever the source tree's
        # own __pycache__ holds from earlier runs; pay it here, on the tiny case, and report
        # it apart
        os.environ["NUMBA_CACHE_DIR"] = str(tmp / "numba")
        first = _sim("mvm", 5e-6, cache, TINY)
        second = _sim("mvm", 5e-6, cache, TINY)
        _warm(cache)
        res["kernel_compile_s"] = first["wall_s"] - second["wall_s"]
        res["seed_runs"] = _seed_runs(t_end, cache)
        res.update(_commands(tmp))
        res.update(_child(_BASIS, [], {"FLEXMVM_NO_CACHE": "1"}))
        if args.main_job:
            res.update(_main_job(tmp))
        if args.scaling:
            res["scaling"] = _scaling(min(t_end, 4e-4), cache, tmp)
        if args.vs:
            res["vs"] = _vs(args.vs, args.vs_t_end, tmp)
    res["machine"]["load_avg_end"] = load_average()
    _print(res)
    if args.figure and "scaling" in res:
        _figure(res["scaling"], args.figure)
        print(f"wrote {args.figure}")
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / f"speed_{res['commit']}.json"
    path.write_text(json.dumps(res, indent=1))
    print(f"wrote {path}")
    if args.write_docs:
        _write_docs(res, args)


def _write_docs(res: dict, args: argparse.Namespace) -> None:
    """The Current figures block of docs/performance.md from ``res``; the command it names is
    the one that made it (its flags that change the figures, not local paths)."""
    flags = [f for f, on in (("--quick", args.quick), ("--main-job", args.main_job)) if on]
    command = " ".join(["python benchmarks/bench_speed.py", *flags, "--write-docs"])
    page = ROOT / "docs" / "performance.md"
    try:
        write_page(page, res, command)
    except InputError as exc:
        raise SystemExit(f"bench_speed: {exc}") from None
    print(f"wrote {page}")


if __name__ == "__main__":
    main()
