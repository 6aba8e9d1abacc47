"""The DOF / force-NCC front of the interface basis on the seed case (issue 12, docs/interface_basis.md).

Settings of docs/studies.md: window 0.8 ms, contact step 1 us, b1 as MVM 3-5 + 40 modes in
the reference and in every run; the reference (b2 full FE) is stored as `flexmvm select`
stores it (DIR/reference/history.csv), so a selection study with --out DIR reuses it.

    python benchmarks/interface_front.py --out out/interface_front [--models NAME ...]

Each candidate b2 model is a name (model_of: 'mvm:1-3:25', 'interface:0.46:10' = one patch
of radius 0.46 mm + 10 modes by participation, 'interface:0.2,0.46,0.9:20:frequency', or an
alias of ALIASES, e.g. p1+10); a finished one is kept in
DIR/front.json with its provenance stamp (flexmvm.runs.provenance: package source,
numpy/scipy/numba, resolved scenario, mesh files) and the reference's SHA-256, and not rerun
while both are the same; a row of another code version or reference is rerun, said in one
line. Prints and writes (DIR/front.csv) DOF (elastic coordinates of
b2), force NCC, peak / impulse / duration errors, the NCC of the two b2 probe velocities, the
guard's outside fraction and the run's CPU (time.process_time, basis build included) and wall
time. DIR/front.json is the CSV's stamped record: docs/interface_basis/ keeps both.
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import time
from pathlib import Path

import flexmvm as fm
from flexmvm.results.atomic import file_sha256
from flexmvm.results.history import read_history
from flexmvm.runs.compare import compare_runs
from flexmvm.runs.provenance import stamp, stamp_mismatch
from flexmvm.runs.run import run_scenario
from flexmvm.studies.grid import study_scenario
from flexmvm.studies.reference_run import reference_history

ROOT = Path(__file__).resolve().parents[1]
SEED = ROOT / "scenarios" / "rod_impact.toml"
MM = 1e-3


#: the names of the first measurements (docs/interface_basis.md) -> model text
ALIASES = {"mvm-1-1+37": "mvm:1-1:37", "mvm-1-3+25": "mvm:1-3:25", "mvm-1-3+37": "mvm:1-3:37"}
_SETS = {
    "p1": "0.46",
    "p3": "0.2,0.46,0.9",
    "p5": "0.15,0.3,0.46,0.7,1.0",
    "p8": "0.1,0.2,0.3,0.46,0.6,0.8,1.0,1.4",
}
for _tag, _r in _SETS.items():
    for _n in range(41):
        ALIASES[f"{_tag}+{_n}"] = f"interface:{_r}:{_n}"
        ALIASES[f"{_tag}+{_n}f"] = f"interface:{_r}:{_n}:frequency"
for _n in range(1, 41):
    ALIASES[f"part-{_n}"] = f"interface::{_n}"


def model_of(name: str):
    """The b2 model of a name: an alias above, 'mvm:I-J:M' or
    'interface:<radii in mm, comma-separated>:<modes>[:frequency]'."""
    text = ALIASES.get(name, name)
    bits = text.split(":")
    if bits[0] == "mvm" and len(bits) == 3:
        return fm.mvm(bits[1], int(bits[2]))
    if bits[0] == "interface" and len(bits) in (3, 4):
        radii = [float(a) * MM for a in bits[1].split(",") if a.strip()]
        choice = bits[3] if len(bits) == 4 else "participation"
        return fm.interface(radii, int(bits[2]), mode_choice=choice)
    raise SystemExit(
        f"unknown model {name!r}: expected one of the aliases, 'mvm:I-J:M' or "
        "'interface:R1,R2,...(mm):MODES[:frequency]'"
    )


def _commit() -> str:
    """HEAD at the start of this process (the code it runs), '-dirty' if src/ has changes."""
    try:
        head = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            cwd=ROOT,
            text=True,
            capture_output=True,
            check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "src"],
            cwd=ROOT,
            text=True,
            capture_output=True,
            check=True,
        ).stdout.strip()
        return head + ("-dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def _stale(row: dict, current: dict) -> str | None:
    """Why a stored front.json row cannot be reused, or None (same code, scenario, reference)."""
    if row.get("reference_sha256") != current["reference_sha256"]:
        return "compared with another reference history"
    return stamp_mismatch(row.get("provenance"), current["provenance"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--models", nargs="+", default=["mvm-1-1+37", "p5+20", "p5+35"])
    ap.add_argument("--t-end", type=float, default=8e-4)
    ap.add_argument("--dt", type=float, default=1e-6)
    ap.add_argument("--other", default="mvm:3-5:40")
    ap.add_argument("--scenario", type=Path, default=SEED)
    ap.add_argument(
        "--figure",
        type=Path,
        default=None,
        help="write the NCC-DOF front figure here (interface rows of DIR/front.json "
        "beside the node selections of --nodes)",
    )
    ap.add_argument(
        "--nodes",
        type=Path,
        default=ROOT / "docs" / "studies" / "selection" / "ncc.csv",
        help="ncc.csv of the 140-run selection study at the same settings",
    )
    args = ap.parse_args()
    models = {name: model_of(name) for name in args.models}
    sc = study_scenario(
        fm.load_scenario(args.scenario), "b2", t_end_s=args.t_end, dt_s=args.dt, other=args.other
    )
    args.out.mkdir(parents=True, exist_ok=True)
    hist, fresh = reference_history(sc, "b2", args.out, progress=False)
    print(f"reference {hist} ({'computed' if fresh else 'stored'})", flush=True)
    t_ref, f_ref, probes_ref = read_history(hist)
    commit = _commit()
    store = args.out / "front.json"
    rows = json.loads(store.read_text()) if store.is_file() else {}
    ref_sha = file_sha256(hist)
    for name in args.models:
        model = models[name]
        current = {"provenance": stamp(sc.with_model("b2", model)), "reference_sha256": ref_sha}
        if name in rows:
            why = _stale(rows[name], current)
            if why is None:
                continue
            print(f"{store.name} row {name}: {why}: recomputed", flush=True)
        t0, c0 = time.perf_counter(), time.process_time()
        run = run_scenario(sc.with_model("b2", model))
        info = next(b for b in run.built.info if b.name == "b2")
        cmp = compare_runs(t_ref, f_ref, probes_ref, *run.result.curves())
        row = {
            "model": model.label,
            "dof": info.dof - 6,
            "commit": commit,
            "wall_time_s": round(time.perf_counter() - t0, 1),
            "cpu_time_s": round(time.process_time() - c0, 1),
        } | current
        row |= {k: v for k, v in cmp.items() if isinstance(v, float)}
        guard = run.summary.get("reduced_contact_guard")
        if guard is not None:
            row["guard_outside_fraction"] = guard.get("b2", {}).get("impulse_fraction_outside")
        rows[name] = row
        store.write_text(json.dumps(rows, indent=1))
        print(name, json.dumps(row), flush=True)
    keys = [
        "name",
        "model",
        "dof",
        "ncc_force",
        "peak_err",
        "impulse_err",
        "duration_err",
        "ncc_b2_impact_end",
        "ncc_b2_free_end",
        "guard_outside_fraction",
        "cpu_time_s",
        "wall_time_s",
        "commit",
    ]
    with open(args.out / "front.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, keys, extrasaction="ignore")
        w.writeheader()
        for name, row in sorted(rows.items(), key=lambda kv: (kv[1]["dof"], kv[0])):
            w.writerow({"name": name} | row)
    if args.figure is not None:
        _figure(args.figure, rows, args.nodes)
    for name, row in sorted(rows.items(), key=lambda kv: (kv[1]["dof"], kv[0])):
        print(
            f"{name:14s} {row['dof']:4d}  NCC {row.get('ncc_force', float('nan')):.4f}  "
            f"peak {100 * row.get('peak_err', float('nan')):+.2f} %  "
            f"impact end {row.get('ncc_b2_impact_end', float('nan')):.4f}  "
            f"free end {row.get('ncc_b2_free_end', float('nan')):.4f}"
        )


def _figure(path: Path, rows: dict, nodes_csv: Path) -> None:
    from flexmvm.plots.study_figures import plot_ncc_dof_fronts

    with open(nodes_csv, newline="") as fh:
        nodes = [
            (int(r["dof"]), float(r["ncc_force"])) for r in csv.DictReader(fh) if r.get("ncc_force")
        ]
    kinds = {
        "node selections (mvm, Craig-Bampton)": nodes,
        "interface, modes by participation": [
            (r["dof"], r["ncc_force"])
            for r in rows.values()
            if r["model"].startswith("interface") and "frequency" not in r["model"]
        ],
        "interface, modes by frequency": [
            (r["dof"], r["ncc_force"])
            for r in rows.values()
            if r["model"].startswith("interface") and "frequency" in r["model"]
        ],
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    plot_ncc_dof_fronts(
        path,
        kinds,
        target=0.995,
        title="seed case, b2: force NCC against b2 full FE (0.8 ms, 1 us)",
    )
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
