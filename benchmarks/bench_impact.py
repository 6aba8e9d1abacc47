"""The seed case as full FE and as MVM in the same run: wall time of each, ratio, NCC.

    python benchmarks/bench_impact.py [--t-end 2e-4] [--dt 0.25e-6]

Full FE: both rods full FE (25,000 DOF each). MVM: both rods MVM (b1 3-5 + 40 modes,
b2 1-1 + 37 modes). Wall times are of the simulation only (bodies built beforehand).
"""

from __future__ import annotations

import argparse

from flexmvm.runs.compare import compare_runs
from flexmvm.runs.run import run_scenario
from flexmvm.scenarios import load_scenario


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="scenarios/rod_impact.toml")
    ap.add_argument("--t-end", type=float, default=2e-4)
    ap.add_argument("--dt", type=float, default=None)
    args = ap.parse_args()
    sc = load_scenario(args.scenario).with_overrides(t_end_s=args.t_end, dt_s=args.dt)
    full = run_scenario(sc.with_overrides(model="full"))
    mvm = run_scenario(sc.with_overrides(model="mvm"))
    c = compare_runs(*full.result.curves(), *mvm.result.curves())
    tf, tm = full.result.wall_time_s, mvm.result.wall_time_s
    print(f"window {args.t_end * 1e3:.3f} ms, {full.result.n_steps} steps")
    print(
        f"full FE: {tf:.1f} s ({sum(full.summary['dof'].values())} DOF); "
        f"MVM: {tm:.2f} s ({sum(mvm.summary['dof'].values())} DOF); full/MVM = {tf / tm:.1f}"
    )
    print(
        "MVM vs full FE: " + ", ".join(f"{k} {v:.4f}" for k, v in c.items() if isinstance(v, float))
    )


if __name__ == "__main__":
    main()
