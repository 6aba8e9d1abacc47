"""The selection study's answer on the shipped scheme, side by side with the study's scheme.

A selection study (studies.grid.seed_scheme) runs b2's contact on the velocity law without mass
redistribution at a fixed theta = 0.55; rod_impact.toml ships the position law with massless
contact nodes and theta(h) = 1/2 + h / (4 tau). This script runs, on both schemes and with the
study's settings (docs/studies.md: window 0.8 ms, contact step 1 us, b1 MVM 3-5 + 40 modes),
b2's full-FE reference and the candidates that decide the study's answer for force NCC >= 0.99
(1-3 + 25 modes, 100 DOF): the answer itself and every selection of the grid that has a
model with fewer coordinates (3 x nodes + modes < 100), at its largest such mode count (the
140-run table's NCC rises with the modes, to 1e-3): 1-1, 2-1, 3-1, 4-1, 1-2, 2-2 + 43,
1-3 + 19, 3-2 + 13. It prints each candidate's force NCC over the contact window, peak error,
its DOF and CPU time on each scheme (the table of docs/notes/2026-11-29-study-scheme.md).

    PYTHONPATH=src python benchmarks/study_scheme.py [--quick] \
        [--json docs/studies/selection/scheme_side_by_side.json]

The record carries the provenance stamp of every run (runs.provenance.stamp: the references'
and each candidate's) and the script's own (script_stamp) in its meta.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from flexmvm.runs.provenance import script_stamp, stamp
from flexmvm.runs.run import run_scenario
from flexmvm.scenarios import load_scenario
from flexmvm.studies.grid import mvm_scenario, parse_model, reference_scenario, seed_scheme
from flexmvm.studies.reference_run import scored_row

ROOT = Path(__file__).resolve().parents[1]
T_END, DT, OTHER = 8e-4, 1e-6, "mvm:3-5:40"
SETTINGS = {"body": "b2", "t_end_s": T_END, "dt_s": DT, "other": OTHER}
#: (layers, laps, modes): the answer, then the largest model below 100 DOF of every selection
CANDIDATES = (
    (1, 3, 25),
    (1, 3, 19),
    (2, 2, 43),
    (1, 2, 43),
    (4, 1, 43),
    (3, 1, 43),
    (2, 1, 43),
    (1, 1, 43),
    (3, 2, 13),
)


def shipped(sc):
    """The study's settings on the scenario's own scheme: b1 MVM 3-5 + 40, 0.8 ms at 1 us."""
    sc = sc.with_model("b1", parse_model(OTHER))
    return sc.with_time(t_end_s=T_END, dt_s=DT)


def study(sc):
    """The same on the study's scheme (studies.grid.seed_scheme)."""
    return shipped(seed_scheme(sc, "b2"))


def _run(sc):
    c0 = time.process_time()
    run = run_scenario(sc, warn=False)
    return run, time.process_time() - c0


def side(sc, candidates) -> dict:
    """The reference and the candidates' rows on scheme ``sc``, each with its run's
    provenance stamp (runs.provenance.stamp of the scenario it ran)."""
    ref_sc = reference_scenario(sc, "b2")
    ref, cpu_ref = _run(ref_sc)
    t, f, p = ref.result.curves()
    rows = []
    for i, j, m in candidates:
        cand = mvm_scenario(sc, "b2", i, j, m)
        run, cpu = _run(cand)
        info = next(b for b in run.built.info if b.name == "b2")
        row = scored_row({"model": f"{i}-{j} + {m}", "dof": info.dof - 6}, run, "b2", t, f, p)
        extra = {"cpu_s": cpu, "energy_rel": run.summary["energy_rel_change"]}
        rows.append(row | extra | {"provenance": stamp(cand)})
    return {
        "reference_cpu_s": cpu_ref,
        "reference_peak_N": float(f.max()),
        "reference_energy_rel": ref.summary["energy_rel_change"],
        "reference_provenance": stamp(ref_sc),
        "rows": rows,
    }


def _print(name: str, numbers: dict) -> None:
    keys = ("ncc_force", "peak_err", "impulse_err", "duration_err", "dof", "cpu_s", "energy_rel")
    print(
        f"{name}: reference peak {numbers['reference_peak_N']:.1f} N, "
        f"CPU {numbers['reference_cpu_s']:.0f} s",
        flush=True,
    )
    for r in numbers["rows"]:
        print("  " + r["model"] + " " + " ".join(f"{k} {r.get(k)!s:.8}" for k in keys), flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the answer and 1-3 + 19 only")
    ap.add_argument("--json", type=Path, default=None, help="write the numbers here")
    args = ap.parse_args()
    cands = CANDIDATES[:2] if args.quick else CANDIDATES
    sc = load_scenario(ROOT / "scenarios" / "rod_impact.toml")
    sys.path.insert(0, str(ROOT))  # the repository's tools/ (this file runs as a script)
    from tools.validation.paths import git_commit
    from tools.validation.runs import now

    meta = {"commit": git_commit(), "computed_utc": now(), "settings": SETTINGS}
    meta["made_by"] = "benchmarks/study_scheme.py"
    meta["provenance"] = script_stamp(Path(__file__), {**SETTINGS, "quick": args.quick})
    out = {"meta": meta}
    for name, scheme in (("shipped scheme", shipped(sc)), ("study scheme", study(sc))):
        out[name] = side(scheme, cands)
        _print(name, out[name])
        if args.json is not None:
            args.json.write_text(json.dumps(out, indent=1, default=str))


if __name__ == "__main__":
    main()
