"""The DOF / force-NCC front of the interface basis on the seed case (issue 12, docs/interface_basis.md).

Settings of docs/studies.md: window 0.8 ms, contact step 1 us, b1 as MVM 3-5 + 40 modes in
the reference and in every run; the reference (b2 full FE) is stored as `flexmvm select`
stores it (DIR/reference/history.csv), so a selection study with --out DIR reuses it.

    python benchmarks/interface_front.py --out out/interface_front [--models NAME ...]

Each candidate b2 model is a name of MODELS below; a finished one is kept in
DIR/front.json and not rerun. Prints and writes (DIR/front.csv) DOF (elastic coordinates of
b2), force NCC, peak / impulse / duration errors, the NCC of the two b2 probe velocities and
the wall time.
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import time
from pathlib import Path

import flexmvm as fm
from flexmvm.results.history import read_history
from flexmvm.scenarios.compare import compare_runs
from flexmvm.scenarios.run import run_scenario
from flexmvm.studies.grid import study_scenario
from flexmvm.studies.reference import reference_history

ROOT = Path(__file__).resolve().parents[1]
SEED = ROOT / "scenarios" / "rod_impact.toml"
MM = 1e-3


def _radii(*mm: float) -> list[float]:
    return [a * MM for a in mm]


#: name -> b2 model
MODELS = {
    "mvm-1-1+37": lambda: fm.mvm("1-1", 37),
    "mvm-1-3+25": lambda: fm.mvm("1-3", 25),
    "mvm-1-3+37": lambda: fm.mvm("1-3", 37),
}
for _n in (5, 10, 15, 20, 25, 30, 35, 40):
    MODELS[f"part-{_n}"] = (lambda n: lambda: fm.interface((), n))(_n)
for _radii_mm, _tag in (((0.15, 0.3, 0.46, 0.7, 1.0), "p5"),
                        ((0.1, 0.2, 0.3, 0.46, 0.6, 0.8, 1.0, 1.4), "p8"),
                        ((0.46,), "p1"), ((0.2, 0.46, 0.9), "p3")):
    for _n in (5, 10, 15, 20, 25, 30, 32, 35):
        MODELS[f"{_tag}+{_n}"] = (lambda r, n: lambda: fm.interface(_radii(*r), n))(_radii_mm, _n)
        MODELS[f"{_tag}+{_n}f"] = (lambda r, n: lambda: fm.interface(
            _radii(*r), n, mode_choice="frequency"))(_radii_mm, _n)


def _commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, text=True,
                              capture_output=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--models", nargs="+", default=["mvm-1-1+37", "p5+20", "p5+35"])
    ap.add_argument("--t-end", type=float, default=8e-4)
    ap.add_argument("--dt", type=float, default=1e-6)
    ap.add_argument("--other", default="mvm:3-5:40")
    ap.add_argument("--scenario", type=Path, default=SEED)
    args = ap.parse_args()
    unknown = [m for m in args.models if m not in MODELS]
    if unknown:
        raise SystemExit(f"unknown models {unknown}; known: {', '.join(MODELS)}")
    sc = study_scenario(fm.load_scenario(args.scenario), "b2", t_end_s=args.t_end,
                        dt_s=args.dt, other=args.other)
    args.out.mkdir(parents=True, exist_ok=True)
    hist, fresh = reference_history(sc, "b2", args.out, progress=False)
    print(f"reference {hist} ({'computed' if fresh else 'stored'})", flush=True)
    t_ref, f_ref, probes_ref = read_history(hist)
    store = args.out / "front.json"
    rows = json.loads(store.read_text()) if store.is_file() else {}
    for name in args.models:
        if name in rows:
            continue
        model = MODELS[name]()
        t0 = time.perf_counter()
        run = run_scenario(sc.with_model("b2", model))
        info = next(b for b in run.built.info if b.name == "b2")
        cmp = compare_runs(t_ref, f_ref, probes_ref, *run.result.curves())
        row = {"model": model.label, "dof": info.dof - 6, "commit": _commit(),
               "wall_time_s": round(time.perf_counter() - t0, 1)}
        row |= {k: v for k, v in cmp.items() if isinstance(v, float)}
        guard = run.summary.get("reduced_contact_guard")
        if guard is not None:
            row["guard_outside_fraction"] = guard.get("b2", {}).get("impulse_fraction_outside")
        rows[name] = row
        store.write_text(json.dumps(rows, indent=1))
        print(name, json.dumps(row), flush=True)
    keys = ["name", "model", "dof", "ncc_force", "peak_err", "impulse_err", "duration_err",
            "ncc_b2_impact_end", "ncc_b2_free_end", "wall_time_s", "commit"]
    with open(args.out / "front.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, keys, extrasaction="ignore")
        w.writeheader()
        for name, row in sorted(rows.items(), key=lambda kv: (kv[1]["dof"], kv[0])):
            w.writerow({"name": name} | row)
    for name, row in sorted(rows.items(), key=lambda kv: (kv[1]["dof"], kv[0])):
        print(f"{name:14s} {row['dof']:4d}  NCC {row.get('ncc_force', float('nan')):.4f}  "
              f"peak {100 * row.get('peak_err', float('nan')):+.2f} %  "
              f"impact end {row.get('ncc_b2_impact_end', float('nan')):.4f}  "
              f"free end {row.get('ncc_b2_free_end', float('nan')):.4f}")


if __name__ == "__main__":
    main()
