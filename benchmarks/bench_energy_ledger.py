"""What the energy ledger (integrate.energy_ledger) adds to a run: the same scenario run with
the ledger's per-step tally and without it, alternately, in one process.

    python benchmarks/bench_energy_ledger.py [--scenario tests/data/short_flat_impact.toml]
        [--t-end 20e-6] [--theta 0.51] [--repeats 2]

Prints the best wall time of each and their ratio (side by side, so machine load mostly
cancels). At theta = 1/2 the ledger makes no product with the bodies' matrices; above it
one with M_qq and one with k_hat per body and step (the numerical dissipation).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from flexmvm.integrate import energy_ledger
from flexmvm.runs.run import run_scenario
from flexmvm.scenarios import load_scenario

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default=str(ROOT / "tests/data/short_flat_impact.toml"))
    ap.add_argument("--t-end", type=float, default=20e-6)
    ap.add_argument("--theta", type=float, default=0.51)
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    sc = load_scenario(args.scenario).with_time(t_end_s=args.t_end, theta=args.theta)
    run_scenario(sc, warn=False)  # warm-up: meshes, factorizations, kernels
    tally = energy_ledger.EnergyLedger.add
    best = {"with ledger": float("inf"), "without": float("inf")}
    try:
        for _ in range(args.repeats):
            for mode in ("with ledger", "without"):
                energy_ledger.EnergyLedger.add = tally if mode == "with ledger" else _skip
                t0 = time.perf_counter()
                run = run_scenario(sc, warn=False)
                best[mode] = min(best[mode], time.perf_counter() - t0)
    finally:
        energy_ledger.EnergyLedger.add = tally
    steps = run.summary["n_steps"]
    for mode, t in best.items():
        print(f"{mode:12s} {t:8.3f} s  ({1e3 * t / steps:.2f} ms/step, {steps} steps)")
    print(f"ratio {best['with ledger'] / best['without']:.3f}")


def _skip(self, step) -> None:
    """The ledger's add, doing nothing."""


if __name__ == "__main__":
    main()
