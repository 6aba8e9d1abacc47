"""Physics validation report: `python -m flexmvm.validation --out docs/validation`.

Runs (long: the full-FE seed runs are two 25,000-DOF rods) and writes docs/validation.md-style
numbers and figures:
1. flat variant, full FE, against St Venant: plateau mean force, free-end velocity jump time;
2. seed case, full FE, against the 1D wave-Hertz solution: NCC of force and of the free-end
   velocity, peak force and contact-end errors;
3. seed case, MVM (b2 1-1 + 37 modes) against full FE: NCC, peak/impulse/duration errors;
4. time-step convergence of the seed full-FE force (h and h/2);
5. conservation: momentum and energy errors, penetration, no tensile force.
Each finished run is stored (DIR/<case>/history.csv + summary.json) and reused on a rerun.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from flexmvm.materials import ALUMINIUM, BRASS
from flexmvm.plots.figures import plot_run
from flexmvm.results.atomic import write_json_atomic, write_text_atomic
from flexmvm.results.history import read_history, write_history
from flexmvm.scenarios.compare import compare_runs, run_curves
from flexmvm.scenarios.run import run_scenario
from flexmvm.scenarios.schema import load_scenario
from flexmvm.theory.scenario import theory_histories
from flexmvm.theory.wave import Rod1D, st_venant_force

ROOT = Path(__file__).resolve().parents[2]


def _case(out: Path, name: str, sc, model: str | None):
    """Run (or load) one case; returns (t, force, probes, summary)."""
    d = out / name
    if (d / "summary.json").exists() and (d / "history.csv").exists():
        t, f, p = read_history(d / "history.csv")
        return t, f, p, json.loads((d / "summary.json").read_text())
    r = run_scenario(sc.with_overrides(model=model) if model else sc, progress=True)
    d.mkdir(parents=True, exist_ok=True)
    t, f, p = run_curves(r.result)
    write_history(d / "history.csv", t, f, p)
    write_json_atomic(d / "summary.json", r.summary)
    return t, f, p, r.summary


def flat_vs_st_venant(out: Path, t_end: float, dt: float | None) -> dict:
    sc = load_scenario(ROOT / "scenarios" / "rod_impact_flat.toml").with_overrides(t_end_s=t_end, dt_s=dt)
    t, f, p, s = _case(out, "flat_full", sc, "full")
    b1, b2 = sc.body("b1"), sc.body("b2")
    r1 = Rod1D.from_material(BRASS, b1.rod.length_m, b1.rod.radius_m)
    r2 = Rod1D.from_material(ALUMINIUM, b2.rod.length_m, b2.rod.radius_m)
    F0 = st_venant_force(r1, r2, 0.21)
    T2 = 2 * r2.length_m / r2.c
    mid = (t > 0.2 * T2) & (t < 0.8 * T2)
    v = p["b2_free_end"]
    vp = 2 * F0 / r2.impedance
    jump = float(t[np.argmax(v > 0.5 * vp)])
    return {"F0_N": F0, "plateau_mean_N": float(f[mid].mean()),
            "plateau_err": float(f[mid].mean() / F0 - 1), "free_end_jump_s": jump,
            "L_over_c_s": r2.length_m / r2.c, "jump_err": jump / (r2.length_m / r2.c) - 1, **_cons(s)}


def _cons(s: dict) -> dict:
    return {k: s.get(k) for k in ("momentum_rel_error", "energy_rel_error", "max_penetration_m",
                                  "max_penetration_at", "max_penetration_by_direction_m",
                                  "min_contact_force_N", "wall_time_s", "n_steps")}


def seed_vs_theory(out: Path, t_end: float, dt: float | None) -> dict:
    sc = load_scenario(ROOT / "scenarios" / "rod_impact.toml").with_overrides(t_end_s=t_end, dt_s=dt)
    tt, ft, pt, _ = theory_histories(sc)
    full = _case(out, "seed_full", sc, "full")
    mvm = _case(out, "seed_mvm", sc, None)
    plot_run(out / "seed_fig5.png", {"FE": full[:3], "MVM": mvm[:3]}, theory=(tt, ft, pt),
             title="seed case: full FE, MVM (b2 1-3 + 37 modes, 112 DOF), 1D wave-Hertz")
    return {"full_vs_theory": compare_runs(tt, ft, pt, *full[:3]),
            "mvm_vs_full": compare_runs(*full[:3], *mvm[:3]),
            "mvm_vs_theory": compare_runs(tt, ft, pt, *mvm[:3]),
            "full": _cons(full[3]), "mvm": _cons(mvm[3]), "mvm_dof": mvm[3]["dof"]}


def step_convergence(out: Path, t_end: float, dt: float) -> dict:
    sc = load_scenario(ROOT / "scenarios" / "rod_impact.toml").with_overrides(t_end_s=t_end)
    a = _case(out, f"seed_full_dt{dt:g}", sc.with_overrides(dt_s=dt), "full")
    b = _case(out, f"seed_full_dt{dt / 2:g}", sc.with_overrides(dt_s=dt / 2), "full")
    return {"h": dt, "h_half_vs_h": compare_runs(*b[:3], *a[:3])}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description="Run the physics validation and write its report.")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "validation")
    ap.add_argument("--t-end", type=float, default=1.0e-3)
    ap.add_argument("--dt", type=float, default=0.5e-6)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    report = {"flat_vs_st_venant": flat_vs_st_venant(args.out, 0.5e-3, args.dt),
              "seed": seed_vs_theory(args.out, args.t_end, args.dt),
              "step_convergence": step_convergence(args.out, 2e-4, args.dt)}
    write_json_atomic(args.out / "validation.json", report)
    write_text_atomic(args.out / "validation_numbers.md",
                      "```json\n" + json.dumps(report, indent=2, sort_keys=True) + "\n```\n")
    print(json.dumps(report, indent=2, sort_keys=True))


if __name__ == "__main__":
    main()
