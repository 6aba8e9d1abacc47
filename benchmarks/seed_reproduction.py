"""The seed's section 3.2 claims on a given mesh: reduced models of b2 against b2 full FE.

    python benchmarks/seed_reproduction.py [SCENARIO] [--body b2] [--t-end 8e-4] [--dt S]
        [--other scenario|full|mvm:I-J:M]
        [--models mvm-seed:1-1:37,mvm-seed-fixed:1-1:37,mvm:1-1:37]
        [--grid-kinds mvm-seed,mvm --grid-layers 1,2 --grid-laps 1,2,5 --grid-modes 7,19,37]
        [--json FILE] [--csv FILE]

SCENARIO defaults to scenarios/rod_impact_seed_mesh.toml. One reference run (BODY full FE, the
other bodies as --other says), then one run per model of BODY: those of --models and the grid
(every kind x layers x laps x modes). Each row carries its run's provenance stamp
(runs.provenance.stamp: code, libraries, resolved scenario, mesh files). Each is compared with the reference (force NCC, peak,
impulse and duration errors: runs.compare.compare_runs) and with the 1D wave-Hertz theory
of the scenario (flexmvm theory); the reference too. Printed as a table and written to --json
(numbers, settings, the git commit of the code). The grids of one kind are also
`flexmvm select --kind K` and `flexmvm study materials --kind K` (Dask, resumable); this script
runs any list of models of any kinds, one process, no resume.

With --csv, the model rows go to a CSV table (one line per model: kind, layers, laps, retained
nodes, modes, DOF with the frame, force NCC over the reference's contact window and over the
whole window, the errors, probes' NCC, peak force, penetration, the impulse share outside the
retained nodes, wall and CPU time) and the JSON keeps the reference row (its full stamp) and
each model's run key (`run_keys`, runs.provenance.run_key: code, libraries, resolved scenario,
meshes): the record of docs/seed_reproduction/grid_eq4_meta.json + grid_eq4_ncc.csv.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import time
from pathlib import Path

from flexmvm.results.atomic import write_table_csv
from flexmvm.runs.compare import compare_runs
from flexmvm.runs.provenance import stamp
from flexmvm.runs.run import run_scenario
from flexmvm.scenarios import ModelConfig, full, load_scenario
from flexmvm.studies.grid import study_scenario
from flexmvm.theory.scenario import theory_histories

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ROOT / "scenarios" / "rod_impact_seed_mesh.toml"


def _ints(text: str) -> list[int]:
    return [int(x) for x in text.split(",") if x.strip()]


def _model(text: str, reference: str) -> ModelConfig:
    kind, sel, modes = text.split(":")
    return ModelConfig(kind=kind, selection=sel, modes=int(modes), reference=reference)


def _row(label: str, sc, run, ref_curves, theory) -> dict:
    s = run.summary
    curves = run.result.curves()
    row = {
        "model": label,
        "dof": s["dof"],
        "max_contact_force_N": s["max_contact_force_interval_mean_N"],
        "contact_intervals_s": s["contact_intervals_s"],
        "max_penetration_m": s["max_penetration_m"],
        "max_penetration_at": s["max_penetration_at"],
        "max_penetration_by_direction_m": s["max_penetration_by_direction_m"],
        "energy_rel_error": s["energy_rel_change"],
        "wall_time_s": s["wall_time_s"],
        "n_steps": s["n_steps"],
        # per reduced body: the share of its contact impulse on nodes its basis holds stiff
        "reduced_contact_guard": s.get("reduced_contact_guard"),
        "provenance": stamp(sc),
    }
    if ref_curves is not None:
        row["vs_full"] = compare_runs(*ref_curves, *curves)
    if theory is not None:
        row["vs_theory"] = compare_runs(*theory, *curves)
    return row


CSV_COLUMNS = [
    "kind",
    "layers",
    "laps",
    "nodes",
    "modes",
    "dof_total",
    "ncc_force",
    "ncc_force_whole",
    "peak_err",
    "impulse_err",
    "duration_err",
    "ncc_b2_impact_end",
    "ncc_b2_free_end",
    "max_contact_force_N",
    "max_penetration_m",
    "guard_outside_fraction",
    "wall_time_s",
    "cpu_time_s",
]


def _csv_row(row: dict, body: str) -> dict:
    """A model row as a CSV line: its grid fields from the label kind:i-j:m, retained nodes
    from the DOF (3 per node + modes + 6 frame coordinates), vs_full's metrics."""
    kind, sel, modes = row["model"].split(":")
    i, j = (int(x) for x in sel.split("-"))
    dof_total = row["dof"][body]
    guard = (row.get("reduced_contact_guard") or {}).get(body) or {}
    return {
        "kind": kind,
        "layers": i,
        "laps": j,
        "nodes": (dof_total - 6 - int(modes)) // 3,
        "modes": int(modes),
        "dof_total": dof_total,
        **row.get("vs_full", {}),
        "max_contact_force_N": row["max_contact_force_N"],
        "max_penetration_m": row["max_penetration_m"],
        "guard_outside_fraction": guard.get("impulse_fraction_outside"),
        "wall_time_s": row["wall_time_s"],
        "cpu_time_s": row["cpu_time_s"],
    }


def _fmt(row: dict, body: str) -> str:
    v = row.get("vs_full", {})
    t = row.get("vs_theory", {})
    end = row["contact_intervals_s"][0][1] * 1e6 if row["contact_intervals_s"] else float("nan")

    def pct(d, k):
        return f"{100 * d[k]:+7.2f} %" if k in d else "      -  "

    ncc = f"{v['ncc_force']:.4f}" if "ncc_force" in v else "     - "
    return (
        f"{row['model']:22s} {row['dof'][body]:6d} {ncc:>7s} {pct(v, 'peak_err')} "
        f"{pct(v, 'impulse_err')} {pct(v, 'duration_err')} {row['max_contact_force_N']:8.1f} "
        f"{end:7.1f} {1e6 * row['max_penetration_m']:8.3f} "
        f"{t.get('ncc_force', float('nan')):7.4f} {pct(t, 'peak_err')} {pct(t, 'duration_err')} "
        f"{row['wall_time_s']:6.1f}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario", nargs="?", type=Path, default=DEFAULT)
    ap.add_argument("--body", default="b2")
    ap.add_argument("--t-end", type=float, default=8e-4)
    ap.add_argument("--dt", type=float, default=None)
    ap.add_argument("--other", default="scenario")
    ap.add_argument("--models", default="mvm-seed:1-1:37,mvm-seed-fixed:1-1:37,mvm:1-1:37")
    ap.add_argument("--grid-kinds", default="")
    ap.add_argument("--grid-layers", default="1,2")
    ap.add_argument("--grid-laps", default="1,2,5")
    ap.add_argument("--grid-modes", default="7,19,37")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--csv", type=Path, default=None)
    args = ap.parse_args()

    base = study_scenario(
        load_scenario(args.scenario), args.body, t_end_s=args.t_end, dt_s=args.dt, other=args.other
    )
    ref_set = base.body(args.body).model.reference
    models = [m for m in args.models.split(",") if m.strip()]
    for kind in [k for k in args.grid_kinds.split(",") if k.strip()]:
        for i in _ints(args.grid_layers):
            for j in _ints(args.grid_laps):
                models += [f"{kind}:{i}-{j}:{m}" for m in _ints(args.grid_modes)]
    models = list(dict.fromkeys(models))
    try:
        t_th, f_th, p_th, _ = theory_histories(base)
        theory = (t_th, f_th, p_th)
    except Exception as exc:  # noqa: BLE001 - report, go on without theory
        print(f"no theory comparison: {exc}")
        theory = None
    commit = subprocess.run(
        ["git", "-C", str(ROOT), "describe", "--always", "--dirty"],
        capture_output=True,
        text=True,
        check=False,
    ).stdout.strip()
    t0, c0 = time.perf_counter(), time.process_time()
    ref_sc = base.with_model(args.body, full(reference=ref_set))
    ref = run_scenario(ref_sc, label="full")
    ref_curves = ref.result.curves()
    rows = [_row("full", ref_sc, ref, None, theory)]
    head = (
        f"{'model of ' + args.body:22s} {'DOF':>6s} {'NCC':>7s} {'peak':>9s} {'impulse':>9s} "
        f"{'duration':>9s} {'F_max N':>8s} {'end us':>7s} {'pen um':>8s} "
        f"{'NCC th':>7s} {'peak th':>9s} {'dur th':>9s} {'wall s':>6s}"
    )
    print(
        f"{args.scenario.name}: t_end {base.time.t_end_s:g} s, dt {base.time.dt_s:g} s, "
        f"other bodies: {args.other}; code {commit}"
    )
    print(head)
    print(_fmt(rows[0], args.body), flush=True)
    for text in models:
        sc = base.with_overrides(body_models={args.body: _model(text, ref_set)})
        c_run = time.process_time()
        run = run_scenario(sc, label=text)
        row = _row(text, sc, run, ref_curves, theory)
        row["cpu_time_s"] = time.process_time() - c_run
        rows.append(row)
        print(_fmt(row, args.body), flush=True)
    out = {
        "scenario": str(args.scenario),
        "body": args.body,
        "t_end_s": base.time.t_end_s,
        "dt_s": base.time.dt_s,
        "other": args.other,
        "commit": commit,
        "wall_time_total_s": time.perf_counter() - t0,
        "cpu_time_total_s": time.process_time() - c0,
        "rows": rows,
    }
    if args.csv is not None:
        args.csv.parent.mkdir(parents=True, exist_ok=True)
        write_table_csv(args.csv, CSV_COLUMNS, [_csv_row(r, args.body) for r in rows[1:]])
        out["reference"] = rows[0]
        out["run_keys"] = {r["model"]: r["provenance"]["key"] for r in rows[1:]}
        out["rows_csv"] = args.csv.name
        del out["rows"]
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
