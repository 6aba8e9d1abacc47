"""Benchmark of the selection study on the seed scenario (scenarios/rod_impact.toml).

Times (1) the brute-force selection study (140 runs: layers 1..4 x laps 1..5 x modes 7:43:6)
and (2) the --search for the same target, and prints the number of MVM runs each needed and
the time per run. Defaults (the seed-scale settings of docs/studies.md): window 0.8 ms (the
contact lasts 0.66 ms), contact step 1 us (force NCC 0.99998 against 0.5 us), the striker b1
as MVM 3-5 + 40 modes in the reference and in every run (``--other full`` keeps the seed's
full-FE striker: ~50 ms per step instead of ~14, see docs/studies.md).

    python benchmarks/bench_studies.py [--t-end 8e-4] [--dt 1e-6] [--other mvm:3-5:40]
        [--workers 2] [--subset] [--target ncc>=0.99] [--out DIR] [--record DIR]
        [--setup-cache empty|user]

The study builds its meshes and Craig-Bampton bases in a new, empty setup cache, as a first
study on a machine does, and the search reuses what the brute force built (``--setup-cache
user``: the user's cache, where earlier runs may have left them: the 20 bases are ~95 s of
the brute force on two workers). The record (default benchmarks/results/studies_<commit>.json)
holds the commit, the settings, the wall times and the machine's load average before and
after (a loaded machine makes every time here longer: quote a record only with its load).

``--subset`` runs the brute force on layers 1..2 x laps 1..2 x modes 7:43:6 (28 runs) instead
of the 140; the extrapolation uses the measured mean wall time per run. The search runs in
a fresh directory that shares only the reference (copied), so its runs are all computed.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

from flexmvm.metrics.ncc import Target
from flexmvm.setup_cache import ENV_DIR
from flexmvm.studies.options import BasisSpec, StudyOptions
from flexmvm.studies.selection import run_selection_study

ROOT = Path(__file__).resolve().parents[1]
SEED = ROOT / "scenarios" / "rod_impact.toml"


def _commit() -> str:
    out = (
        subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            cwd=ROOT,
            check=False,
        ).stdout.strip()
        or "unknown"
    )
    dirty = subprocess.run(
        ["git", "status", "--porcelain", "--untracked-files=no"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    ).stdout.strip()
    return out + ("-dirty" if dirty else "")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=8e-4)
    ap.add_argument("--dt", type=float, default=1e-6)
    ap.add_argument("--other", default="mvm:3-5:40")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--target", default="ncc>=0.99")
    ap.add_argument("--subset", action="store_true")
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--record", type=Path, default=ROOT / "benchmarks" / "results")
    ap.add_argument(
        "--setup-cache",
        choices=("empty", "user"),
        default="empty",
        help="empty (default): a new setup cache in the output directory, so the "
        "study builds its bases as a first study on a machine does; user: "
        "the user's cache ($FLEXMVM_CACHE_DIR or the platform's), bases "
        "built by earlier runs reused",
    )
    a = ap.parse_args()
    load0 = os.getloadavg()
    out = a.out or Path(tempfile.mkdtemp(prefix="bench_studies_"))
    if a.setup_cache == "empty":  # inherited by the cluster's worker processes
        os.environ[ENV_DIR] = str(out / "setup_cache")
    layers, laps = ([1, 2], [1, 2]) if a.subset else (range(1, 5), range(1, 6))
    modes = range(7, 44, 6)
    target = Target.parse(a.target)
    print(
        f"seed scenario, t_end = {a.t_end:g} s, dt = {a.dt:g} s, other body {a.other}, "
        f"target {a.target}, out {out}"
    )
    options = StudyOptions(
        n_workers=a.workers, progress=True, t_end_s=a.t_end, dt_s=a.dt, other=a.other, echo=print
    )
    t0 = time.perf_counter()
    brute = run_selection_study(
        SEED,
        "b2",
        out / "brute",
        BasisSpec(layers=layers, laps=laps, modes=modes),
        target,
        search=False,
        options=options,
    )
    t_brute = time.perf_counter() - t0
    rows = (out / "brute" / "ncc.csv").read_text().splitlines()[1:]
    per_run = sum(float(r.split(",")[-1]) for r in rows) / max(len(rows), 1)
    print(
        f"brute force: {brute['runs']} runs ({brute['runs_made']} made) in {t_brute:.1f} s "
        f"wall (incl. reference), {per_run:.2f} s per run (solver wall time); full grid of "
        f"140 runs ~ {140 * per_run:.0f} s of run time"
    )
    (out / "search").mkdir(parents=True, exist_ok=True)
    shutil.copytree(out / "brute" / "reference", out / "search" / "reference", dirs_exist_ok=True)
    t0 = time.perf_counter()
    found = run_selection_study(
        SEED,
        "b2",
        out / "search",
        BasisSpec(layers=layers, laps=laps, modes=modes),
        target,
        search=True,
        options=options,
    )
    t_search = time.perf_counter() - t0
    print(f"search: {found['runs']} runs in {t_search:.1f} s wall")
    keys = ("passed", "layers", "laps", "modes", "dof", "ncc_force")
    ref = json.loads((out / "brute" / "reference" / "reference.json").read_text())["summary"]
    print(f"reference run (study body full FE): {ref['wall_time_s']:.1f} s solver wall time")
    record = {
        "commit": _commit(),
        "settings": {
            "t_end_s": a.t_end,
            "dt_s": a.dt,
            "other": a.other,
            "workers": a.workers,
            "target": a.target,
            "subset": a.subset,
            "setup_cache": a.setup_cache,
        },
        "brute": {k: brute.get(k) for k in keys},
        "search": {k: found.get(k) for k in keys},
        "runs": {"brute": brute["runs"], "search": found["runs"]},
        "wall_s": {"brute": t_brute, "search": t_search},
        "solver_s_per_run": per_run,
        "reference_solver_s": ref["wall_time_s"],
        "load_average_1_5_15": {"start": load0, "end": os.getloadavg()},
        "cpus": os.cpu_count(),
    }
    print(json.dumps(record, indent=1))
    a.record.mkdir(parents=True, exist_ok=True)
    path = a.record / f"studies_{record['commit']}.json"
    path.write_text(json.dumps(record, indent=1))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
