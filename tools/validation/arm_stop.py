"""The arm-into-a-stop showcase as a validation case (issue 35): scenarios/arm_stop.toml, a
flexible arm spun up from rest by a motor torque on its revolute joint, the torque off before
the impact, swung into a grounded rigid sphere; full FE (the reference) and the scenario's MVM
(`flexmvm run --model mvm`) side by side.

Numbers reported: the MVM against full FE (contact force NCC over the contact window, peak,
impulse and duration errors: runs.compare.compare_runs; the tip's swing velocity NCC from
the motor's end on, where the coast, the impact, the rebound and the vibration are: over the
whole run the spin-up's rise alone would make it near 1), each run's energy ledger (its
balance residual relative to the input work, the motor's work, the numerical dissipation),
steps not converged and cut, DOF, steps, wall time and the cost ratio full / MVM.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from flexmvm.errors import InputError
from flexmvm.metrics.ncc import ncc
from flexmvm.runs.compare import compare_runs
from flexmvm.scenarios import ModelKind, Scenario, load_scenario
from tools.validation.paths import scenario_path
from tools.validation.runs import Case, case_meta, conservation, run_case

#: The probe whose swing velocity (global x at the arm's free end) is compared.
TIP = "tip"


def _ledger(c: Case) -> dict:
    """What the report keeps of a run's energy ledger (summary.json ``energy_ledger``)."""
    led = c.summary["energy_ledger"]
    return {
        "balance_residual_rel_max": led["balance_residual_rel_max"],
        "balance_reference": led["balance_reference"],
        "input_work_J": led["balance_reference_J"],
        "work_motor_J": led["work_loads_J"]["motor"],
        "work_joints_J": float(sum(led["work_joints_J"].values())),
        "work_contact_J": led["work_contact_J"],
        "dissipation_numerical_J": led["dissipation_numerical_J"],
        "total_end_J": led["total_end_J"],
    }


def _after(c: Case, t0: float) -> tuple[np.ndarray, np.ndarray]:
    """The tip's swing velocity from t0 [s] on."""
    keep = c.t >= t0
    return c.t[keep], c.probes[TIP][keep]


def _figures(out: Path, full: Case, mvm: Case, mvm_label: str) -> None:
    """out/arm_stop_fig.png (the whole run: contact force, tip swing velocity) and
    out/arm_stop_impact.png (the full-FE run's contacts, 20 us either side)."""
    from flexmvm.plots.figures import plot_run

    runs = {"full FE": full.curves, mvm_label: mvm.curves}
    plot_run(out / "arm_stop_fig.png", runs, title="arm spun up into a stop: full FE and MVM")
    spans = full.summary["contact_intervals_s"]
    t0, t1 = spans[0][0] - 20e-6, spans[-1][1] + 20e-6

    def window(c: Case) -> tuple:
        keep = (c.t >= t0) & (c.t <= t1)
        return c.t[keep], c.force[keep], {k: v[keep] for k, v in c.probes.items()}

    plot_run(
        out / "arm_stop_impact.png",
        {k: window(c) for k, c in (("full FE", full), (mvm_label, mvm))},
        title="arm into a stop: the impacts",
    )


def arm_stop_case(out: Path, recompute: bool = False, plot: bool = False) -> dict:
    """Full FE and MVM of scenarios/arm_stop.toml (stored as arm_stop_full, arm_stop_mvm);
    plot: the figures of the report and of docs/arm_stop.md (_figures)."""
    sc = load_scenario(scenario_path("arm_stop.toml"))
    full = run_case(out, "arm_stop_full", sc.with_kind(ModelKind.FULL), recompute)
    mvm = run_case(out, "arm_stop_mvm", sc.with_kind(ModelKind.MVM), recompute)
    return arm_stop_numbers(sc, full, mvm, out if plot else None)


def arm_stop_numbers(sc: Scenario, full: Case, mvm: Case, fig_dir: Path | None = None) -> dict:
    """The case's numbers from its two runs (full FE, MVM) of scenario ``sc``; with fig_dir,
    the figures there too."""
    (motor,) = (ld for ld in sc.loads if ld.name == "motor")
    t_drive = float(motor.times_s[-1])
    model = sc.body("arm").model
    runs = {"full": full, "mvm": mvm}
    ball = model.region.ball if model.region is not None else None
    if ball is None:
        raise InputError("arm_stop.toml: the arm's model needs its ball region")
    label = f"MVM ball {1e3 * ball.radius_m:g} mm + {model.modes} modes"
    if fig_dir is not None:
        _figures(fig_dir, full, mvm, label)
    return {
        "mvm_vs_full": {
            **compare_runs(*full.curves, *mvm.curves),
            "ncc_tip_after_drive": float(ncc(*_after(full, t_drive), *_after(mvm, t_drive))),
        },
        **{
            k: {**conservation(c.summary), "step_cuts": c.summary["step_cuts"]}
            for k, c in runs.items()
        },
        "ledger": {k: _ledger(c) for k, c in runs.items()},
        "drive_end_s": t_drive,
        "mvm_model": label[4:],
        "dof": {k: c.summary["dof"]["arm"] for k, c in runs.items()},
        "cost_ratio_full_over_mvm": full.summary["wall_time_s"] / mvm.summary["wall_time_s"],
        "cases": {k: case_meta(c) for k, c in runs.items()},
    }


__all__ = ["TIP", "arm_stop_case", "arm_stop_numbers"]
