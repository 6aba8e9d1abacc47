"""The PA6 runs of the material study, explained (issue 12 part 4; docs/studies.md, "Material
study"): b2 of PA6 (seed table 2) struck by the brass rod at 0.21 m/s, the material study's
settings (2 ms, 1 us, b1 MVM 3-5 + 40 modes), b2 reduced in several ways against b2 full FE.

    python benchmarks/pa6_chatter.py OUT_DIR [--quick]

For each b2 model and contact law it prints and writes (OUT_DIR/pa6_chatter.json) the force NCC
and peak error against the full-FE reference, the number of contact intervals (the reference
has one), the deepest penetration, the largest energy error and the validity guard's share of
the contact impulse on nodes the basis holds stiff. The models: Craig-Bampton selections 1-1,
1-3 (the material study's, inside PA6's 0.66 mm Hertz radius), 1-4 (its last ring, 0.63-0.75
mm, straddles it), 1-5 (covers it) and the interface kind with one patch at the Hertz radius;
the laws: velocity with the default penetration recovery (beta = 0.2), velocity with beta = 0,
and position. The reference (full FE, velocity law, beta 0.2) is computed once into OUT_DIR.
--quick: 1-3 + 43 and 1-4 + 43 only.

First it prints the effective axial mass 1 / (e psi M_qq^-1 psi^T e) [kg] of a contact row on
the innermost face node of rings 1, 3, 4, 5 of b2 (rod_impact.toml's aluminium; mass scales with
the density) for full FE and the selections 1-3, 1-4, 1-5 with 7 and 43 modes: what a row on a
node outside, or at the edge of, the retained set weighs.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
import warnings
from pathlib import Path

from flexmvm.materials import PA6
from flexmvm.results.atomic import write_json_atomic
from flexmvm.results.history import read_history
from flexmvm.runs.compare import compare_runs
from flexmvm.runs.run import run_scenario
from flexmvm.scenarios import interface, load_scenario, scenario_from_dict
from flexmvm.studies.grid import mvm_scenario, study_scenario
from flexmvm.studies.materials import material_scenario
from flexmvm.studies.reference_run import reference_history

ROOT = Path(__file__).resolve().parents[1]
MODELS = [("1-1", 43), ("1-3", 7), ("1-3", 43), ("1-4", 43), ("1-5", 43), ("if0.66", 10)]
LAWS = [("velocity", None), ("velocity", 0.0), ("position", None)]


def _commit() -> str:
    try:
        return subprocess.run(
            ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def row_masses() -> dict:
    """{model: {ring: effective axial mass [kg]}} (module doc)."""
    import numpy as np
    import scipy.sparse.linalg as sla

    from flexmvm.assembly.build import build_scenario
    from flexmvm.studies.grid import reference_scenario, rod_of

    sc = load_scenario(ROOT / "scenarios" / "rod_impact.toml")
    rod = rod_of(sc, "b2")
    X = rod.mesh.nodes
    face = np.flatnonzero(rod.node_layer == 1)
    nodes = {}
    for j in (1, 3, 4, 5):
        ring = face[rod.node_lap[face] == j]
        nodes[j] = int(ring[np.argmin(np.hypot(X[ring, 1], X[ring, 2]))])

    def masses(s2):
        built = build_scenario(s2)
        body = built.system.bodies[[i.name for i in built.info].index("b2")]
        M = body.inv.M_qq
        out = {}
        for j, n in nodes.items():
            rows = body.psi_rows(n)
            e = np.asarray(rows[0].todense()).ravel() if hasattr(rows, "todense") else rows[0]
            x = sla.spsolve(M.tocsc(), e) if hasattr(M, "tocsc") else np.linalg.solve(M, e)
            out[j] = 1.0 / float(e @ x)
        return out

    res = {"full FE": masses(reference_scenario(sc, "b2"))}
    for sel in ("1-3", "1-4", "1-5"):
        i, j = map(int, sel.split("-"))
        for m in (7, 43):
            res[f"{sel} + {m}"] = masses(mvm_scenario(sc, "b2", i, j, m))
    print("effective axial mass of a contact row on the face node of ring j [kg] (Al density):")
    for name, by_ring in res.items():
        print(f"  {name:>9}: " + "  ".join(f"ring {j} {v:.2e}" for j, v in by_ring.items()))
    return res


def main(out: Path, quick: bool) -> None:
    warnings.simplefilter("ignore")
    masses = row_masses()
    sc = study_scenario(
        load_scenario(ROOT / "scenarios" / "rod_impact.toml"),
        "b2",
        t_end_s=2e-3,
        dt_s=1e-6,
        other="mvm:3-5:40",
    )
    sc = material_scenario(sc, "b2", "PA6", PA6)
    t0 = time.perf_counter()
    hist, made = reference_history(sc, "b2", out)
    print(
        f"reference {'computed' if made else 'loaded'} ({time.perf_counter() - t0:.0f} s): {hist}"
    )
    ref = read_history(hist)
    ref_steps = json.loads((hist.parent / "reference.json").read_text())["summary"]
    rows = []
    models = [("1-3", 43), ("1-4", 43)] if quick else MODELS
    laws = LAWS[:2] if quick else LAWS
    print(
        f"{'b2 model':>10} {'law':>13} {'NCC':>8} {'peak':>8} {'intervals':>9} "
        f"{'pen. um':>8} {'energy':>8} {'guard':>6}"
    )
    for sel, modes in models:
        for law, beta in laws:
            if sel.startswith("if"):
                model = interface(
                    [float(sel[2:]) * 1e-3], modes, reference=sc.body("b2").model.reference
                )
                s2 = sc.with_model("b2", model)
            else:
                i, j = map(int, sel.split("-"))
                s2 = mvm_scenario(sc, "b2", i, j, modes)
            data = s2.model_dump(mode="json")
            data["contacts"][0]["law"] = law
            if beta is not None:
                data["contacts"][0]["penetration_recovery"] = beta
            run = run_scenario(scenario_from_dict(data, source="pa6_chatter"), warn=False)
            s = run.summary
            cmp = compare_runs(*ref, *run.result.curves())
            guard = s["reduced_contact_guard"].get("b2")
            row = {
                "b2": f"{sel}+{modes}",
                "law": law,
                "penetration_recovery": 0.2 if (law == "velocity" and beta is None) else beta,
                "ncc_force": cmp["ncc_force"],
                "peak_err": cmp["peak_err"],
                "contact_intervals": len(run.result.contact_intervals),
                "max_penetration_m": s["max_penetration_m"],
                "energy_rel_error_max": s["energy_rel_change_max"],
                "guard_outside_fraction": None
                if guard is None
                else guard["impulse_fraction_outside"],
                "wall_time_s": s["wall_time_s"],
            }
            rows.append(row)
            lab = law if law == "position" else f"velocity b{row['penetration_recovery']:g}"
            g = row["guard_outside_fraction"]
            print(
                f"{row['b2']:>10} {lab:>13} {row['ncc_force']:8.4f} {row['peak_err']:+8.3f} "
                f"{row['contact_intervals']:9d} {1e6 * row['max_penetration_m']:8.2f} "
                f"{row['energy_rel_error_max']:8.4f} {'-' if g is None else f'{g:.2f}':>6}",
                flush=True,
            )
    write_json_atomic(
        out / "pa6_chatter.json",
        {
            "commit": _commit(),
            "row_mass_kg": masses,
            "reference": {
                "peak_N": float(ref[1].max()),
                "max_penetration_m": ref_steps.get("max_penetration_m"),
                "energy_rel_error_max": ref_steps.get("energy_rel_error_max"),
            },
            "rows": rows,
        },
    )
    print(f"wrote {out / 'pa6_chatter.json'}")


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    if len(args) != 1:
        sys.exit("usage: python benchmarks/pa6_chatter.py OUT_DIR [--quick]")
    out_dir = Path(args[0])
    out_dir.mkdir(parents=True, exist_ok=True)
    main(out_dir, "--quick" in sys.argv[1:])
