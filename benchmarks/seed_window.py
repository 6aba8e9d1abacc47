"""The seed case's energy over its shipped window, by phase, under the free-flight theta rules.

Runs scenarios/rod_impact.toml as shipped (2 ms: 0.5 us steps while the contact is active or
near, 2 us free flight, hf_damping_time_s tau = 12.5 us) and prints the energy at the end and
at the end of the contact, and the energy ledger's numerical dissipation split at the end of
the contact (the contact phase at 0.5 us, the free flight at 2 us). ``--rule`` replaces theta
of the steps above the contact step dt_c for the comparison (integrate/theta.py):

- shipped: the package's rule, 1/2 + dt_c^2 / (4 tau h) above dt_c (same damping of resolved
  motion as the contact step);
- per-step: 1/2 + h / (4 tau) at every h (the rule before 2026-11-29: 0.54 at 2 us);
- contact-theta: theta(dt_c) = 0.51 at every h (the rule before 2026-11-27);
- midpoint: 1/2 above dt_c (no damping in free flight).

The contact phase runs at dt_c under every rule, so it is the same in all. Numbers:
docs/notes/2026-11-29-seed-window.md.

    PYTHONPATH=src python benchmarks/seed_window.py [--rule per-step] [--t-end 2e-3] [--model full]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from flexmvm.integrate import theta as theta_module
from flexmvm.runs.run import run_scenario
from flexmvm.scenarios import load_scenario

ROOT = Path(__file__).resolve().parents[1]
SHIPPED_AT = theta_module.ThetaRule.at


def _rule(name: str, dt_c: float):
    """ThetaRule.at for rule ``name`` (module doc) with the contact step dt_c [s]."""

    def at(self, h):
        if self.damping_time_s is None or name == "shipped":
            return SHIPPED_AT(self, h)
        tau = self.damping_time_s
        if h <= dt_c * (1 + 1e-9):
            return min(1.0, 0.5 + h / (4 * tau))
        return {
            "per-step": min(1.0, 0.5 + h / (4 * tau)),
            "contact-theta": min(1.0, 0.5 + dt_c / (4 * tau)),
            "midpoint": 0.5,
        }[name]

    return at


def measure(rule: str, t_end: float | None, model: str | None = None) -> dict:
    """One run of the seed case under ``rule`` (every body's model ``model`` if given, e.g.
    "full"): energy and the ledger by phase."""
    sc = load_scenario(ROOT / "scenarios" / "rod_impact.toml")
    if model is not None:
        sc = sc.with_kind(model)
    if t_end is not None:
        sc = sc.with_time(t_end_s=t_end)
    theta_module.ThetaRule.at = _rule(rule, sc.time.dt_s)
    try:
        c0 = time.process_time()
        run = run_scenario(sc, warn=False)
        cpu = time.process_time() - c0
    finally:
        theta_module.ThetaRule.at = SHIPPED_AT
    res = run.result
    E, num = res.total_energy, res.energy_ledger.numerical
    end = res.contact_intervals[0][1] if res.contact_intervals else 0.0
    i = int(np.searchsorted(res.t, end - 1e-12))
    return {
        "rule": rule,
        "t_end_s": float(res.t[-1]),
        "energy_rel": float(E[-1] / E[0] - 1),
        "contact_end_s": end,
        "energy_rel_at_contact_end": float(E[i] / E[0] - 1),
        "numerical_contact_rel": float(num[i] / E[0]),
        "numerical_free_flight_rel": float((num[-1] - num[i]) / E[0]),
        "step_size_counts": run.summary["step_size_counts"],
        "peak_N": float(res.contact_force.max()),
        "cpu_s": cpu,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--rule", default="shipped", choices=("shipped", "per-step", "contact-theta", "midpoint")
    )
    ap.add_argument("--t-end", type=float, default=None, help="end time [s] (default: shipped)")
    ap.add_argument("--model", default=None, help="every body's model kind, e.g. full")
    args = ap.parse_args()
    print(json.dumps(measure(args.rule, args.t_end, args.model), indent=1))


if __name__ == "__main__":
    main()
