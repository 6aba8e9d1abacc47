"""Run a scenario: build, simulate, summarise. No file I/O here (see results.output)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.integrate.driver import RunResult, simulate
from flexmvm.scenarios.build import BuiltScenario, build_scenario


@dataclass
class ScenarioRun:
    label: str
    built: BuiltScenario
    result: RunResult
    summary: dict


def run_scenario(sc, label: str = "run", progress: bool = False) -> ScenarioRun:
    """Build and simulate scenario sc; returns the run with its summary."""
    built = build_scenario(sc)
    res = simulate(built.system, built.states, built.grid, built.probes, progress=progress)
    return ScenarioRun(label, built, res, summarize(res, built))


def summarize(res: RunResult, built: BuiltScenario) -> dict:
    """Numbers every run reports (units in the keys)."""
    p0 = res.momentum[0]
    free = not built.system.joints and not np.any(built.system.gravity)
    scale = max(np.linalg.norm(p0), 1e-300)
    mom_err = float(np.abs(res.momentum - p0).max() / scale) if free else None
    E = res.total_energy
    e_err = float((E[-1] - E[0]) / E[0]) if E[0] != 0 else None
    e_err_max = float(np.abs(E - E[0]).max() / abs(E[0])) if E[0] != 0 else None
    return {
        "max_contact_force_N": float(res.contact_force.max()) if res.contact_force.size else 0.0,
        "min_contact_force_N": float(res.contact_force.min()) if res.contact_force.size else 0.0,
        "contact_intervals_s": [[float(a), float(b)] for a, b in res.contact_intervals],
        "dof": {i.name: int(i.dof) for i in built.info},
        "model": {i.name: i.model for i in built.info},
        "retained_nodes": {i.name: int(i.n_retained_nodes) for i in built.info},
        "modes": {i.name: int(i.n_modes) for i in built.info},
        "wall_time_s": float(res.wall_time_s),
        "n_steps": int(res.n_steps),
        # steps per step size {"<h [s]>": count} and the smallest / largest step taken
        "step_size_counts": {f"{h:.6g}": int(n) for h, n in res.step_counts.items()},
        "dt_min_taken_s": float(min(res.step_counts)) if res.step_counts else None,
        "dt_max_taken_s": float(max(res.step_counts)) if res.step_counts else None,
        "n_factorizations": int(res.n_factorizations),
        "momentum_rel_error": mom_err,
        "energy_rel_error": e_err,
        "energy_rel_error_max": e_err_max,
        "max_penetration_m": float(res.max_penetration_m),
        "max_penetration_at": res.max_penetration_at,
        "max_penetration_by_direction_m": dict(res.max_penetration_by_direction_m),
        "max_joint_drift": float(res.max_joint_drift),
        "steps_not_converged": int(res.steps_not_converged),
        "newton_residual_max": float(res.newton_residual_max),
        "lcp_residual_max": float(res.lcp_residual_max),
        # the momentum the solves left unbalanced, relative to the initial momentum: what
        # momentum_rel_error can be at most, from the residuals themselves (free systems)
        "momentum_residual_rel": (float(np.linalg.norm(res.momentum_residual) / scale)
                                  if free else None),
    }
