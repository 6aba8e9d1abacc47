"""The user-part showcases as full FE and as MVM in the same run: wall time of each (the
simulation; bodies built beforehand), their ratio, the force NCC and the peak error.

    python benchmarks/bench_showcases.py [--t-end 1e-3] [--scenario scenarios/sphere_beam.toml]

Default: scenarios/sphere_block.toml and scenarios/sphere_beam.toml over 1 ms each (the
beam's first impact, the separation and the later contacts on the vibrating beam). The MVM
model is the scenario's own `region` and `modes` (`--model mvm`). Prints the machine's CPU.
"""

from __future__ import annotations

import argparse
import platform
import subprocess

from flexmvm.metrics.ncc import ncc
from flexmvm.runs.run import run_scenario
from flexmvm.scenarios import load_scenario

SHOWCASES = ("scenarios/sphere_block.toml", "scenarios/sphere_beam.toml")


def _cpu() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=False).stdout
        for line in out.splitlines():
            if line.startswith("Model name:"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def bench(path: str, t_end: float) -> None:
    sc = load_scenario(path).with_time(t_end_s=t_end)
    full = run_scenario(sc.with_overrides(model="full"), warn=False)
    mvm = run_scenario(sc.with_overrides(model="mvm"), warn=False)
    tf, tm = full.result.wall_time_s, mvm.result.wall_time_s
    pf, pm = full.contact_force.max(), mvm.contact_force.max()
    print(
        f"{sc.name}, {t_end * 1e3:.3g} ms: full FE {tf:.1f} s ({full.summary['dof']}), "
        f"MVM {tm:.1f} s ({mvm.summary['dof']}); full/MVM time {tf / tm:.1f}"
    )
    print(
        f"  force NCC {ncc(full.t, full.contact_force, mvm.t, mvm.contact_force):.5f}, peak "
        f"{pf:.1f} N (full) {pm:.1f} N (MVM), {100 * (pm - pf) / pf:+.2f} %; contacts "
        f"{len(full.summary['contact_intervals_s'])} (full) "
        f"{len(mvm.summary['contact_intervals_s'])} (MVM); steps not converged "
        f"{full.summary['steps_not_converged']} / {mvm.summary['steps_not_converged']}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", action="append", default=None)
    ap.add_argument("--t-end", type=float, default=1e-3)
    args = ap.parse_args()
    print(f"CPU: {_cpu()}")
    for path in args.scenario or SHOWCASES:
        bench(path, args.t_end)


if __name__ == "__main__":
    main()
