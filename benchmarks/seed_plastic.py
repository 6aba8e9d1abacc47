"""The seed case with yielding rods (issue 37): full FE plastic against full FE elastic, then
the MVM form of the struck rod against full FE plastic.

    python benchmarks/seed_plastic.py OUT [--scenario scenarios/rod_impact_short_plastic.toml]
        [--t-end S] [--body b2] [--mvm 5-5:37,3-5:37] [--skip-elastic] [--reuse OUT0]
        [--fine-mesh] [--progress]

The scenario has both rods full FE and plastic (scenarios/rod_impact_plastic.toml,
rod_impact_short_plastic.toml). Runs, one after another in this process:

- ``elastic``: the scenario with the plasticity tables removed (same E, nu, rho, mesh, contact
  law: the elastic seed model without mass redistribution, which plastic bodies refuse);
- ``plastic``: the scenario as given;
- ``mvm I-J:M`` for each of --mvm: BODY as MVM (the seed's selection: I node layers from the
  contact face, J laps from the axis retained; M modes; plastic in its whole retained cells;
  the rods' HEX27 cells span three node layers, so I >= 3: the elastic seed model's 1-3 holds
  no whole cell and is refused), the other rod full FE plastic.

--reuse OUT0 takes the elastic and plastic runs of an earlier OUT0 (their rows from its JSON,
their curves from its .npz files) and runs only the MVM forms; it refuses, in one line, a row
whose provenance stamp (runs.provenance.stamp: code, libraries, resolved scenario, mesh
files) is not the stamp of the run it stands for here.

--fine-mesh runs every rod of the scenario on the finer contact mesh of docs/plasticity.md's
mesh caveat (first element 0.15 mm instead of 0.3 mm, 4 core elements instead of 2: about 2.3
elements per contact radius on the short rods, against 1.2); the record of the short plastic
rods on it, docs/seed_plastic/short_rods_fine_mesh_plastic.json, is

    python benchmarks/seed_plastic.py OUT --fine-mesh --skip-elastic --mvm ''

``--mvm model`` is BODY with the scenario's own model table as kind mvm (its region and modes:
scenarios/sphere_block_plastic.toml's MVM form).

Each run: peak contact force, contact duration, impulse, the striker's velocity after the
contact (v0 - J / m1: momentum, rigid-body part), the coefficient of restitution
e = J / (m* v0) - 1 (m* = m1 m2 / (m1 + m2): the rods' centres of mass), per plastic body its
plastic work, permanent indentation, peak equivalent plastic strain and the retained-region
guard; every run against the elastic one and the MVM runs against the plastic one (force NCC
over the contact window, peak / impulse / duration errors: runs.compare.compare_runs),
and against the 1D wave-Hertz theory (elastic; `flexmvm theory`; its peak, contact span and
impulse kept as `theory`), the run's wall and CPU time (this process's, over the run). Printed
as a table; OUT gets seed_plastic.json (all numbers, each row with its provenance stamp), each
run's curves (LABEL.npz) and seed_plastic.png (the seed's fig. 5 layout: contact force, and
the axial velocities of BODY's impact end and free end; elastic, plastic, theory), all
rewritten as each run finishes: a process stopped late keeps the runs it finished, and
--reuse OUT takes up its elastic and plastic ones.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from flexmvm.errors import InputError, SimulationFailed
from flexmvm.materials import Material
from flexmvm.runs.compare import compare_runs
from flexmvm.runs.provenance import stamp, stamp_mismatch
from flexmvm.runs.run import run_scenario
from flexmvm.scenarios import ModelConfig, load_scenario
from flexmvm.theory.scenario import theory_histories

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ROOT / "scenarios" / "rod_impact_short_plastic.toml"
#: --fine-mesh: the [bodies.rod] grading of every rod (the defaults: 0.3 mm, 2 core elements)
FINE_MESH = {"first_element_m": 0.15e-3, "core_elements": 4}


def elastic_copy(sc):
    """The scenario with every body's plasticity table removed (its E, nu, rho kept)."""
    for b in sc.bodies:
        m = b.material
        if getattr(m, "plasticity", None) is not None:
            sc = sc.with_material(b.name, Material(E=m.E_pa, nu=m.nu, rho=m.rho_kg_m3, name=m.name))
    return sc


def fine_copy(sc):
    """The scenario with every rod body on the FINE_MESH grading (its other fields kept)."""
    for b in sc.bodies:
        if b.rod is not None:
            sc = sc.with_rod(b.name, **FINE_MESH)
    return sc


def _impulse(run) -> float:
    """Total normal contact impulse [N s] (sum of the steps' impulses)."""
    return float(np.sum(run.steps.contact_impulse_Ns))


def _row(label: str, run, sc, refs: dict, cpu_s: float) -> dict:
    """The run's numbers (module doc); cpu_s: this process's CPU time over the run [s]."""
    s = run.summary
    masses = [b.inv.mass for b in run.built.system.bodies]  # [kg], b1 the striker
    v0 = float(np.linalg.norm(sc.bodies[0].placement.velocity_mps))
    j = _impulse(run)
    m_star = masses[0] * masses[1] / (masses[0] + masses[1])
    row = {
        "run": label,
        "status": s["status"],
        "dof": s["dof"],
        "peak_force_N": s["max_contact_force_interval_mean_N"],
        "contact_intervals_s": s["contact_intervals_s"],
        "impulse_Ns": j,
        "striker_velocity_after_mps": v0 - j / masses[0],  # + along the impact direction
        "restitution": j / (m_star * v0) - 1.0,
        "energy_rel_error": s["energy_rel_change"],
        "steps_not_converged": s["steps_on_roundoff_floor"],
        "step_cuts": s["step_cuts"],
        "n_steps": s["n_steps"],
        "wall_time_s": s["wall_time_s"],
        "cpu_time_s": cpu_s,
        "plastic": s.get("plastic", {}),
        "provenance": stamp(sc),
    }
    curves = run.result.curves()
    for name, ref in refs.items():
        row[f"vs_{name}"] = compare_runs(*ref, *curves)
    return row


def _theory_numbers(theory) -> dict | None:
    """The 1D theory's peak force [N], contact span (first to last instant of positive force,
    [s]) and impulse [N s] (trapezoidal), for the page's theory columns."""
    if theory is None:
        return None
    t, f = theory[0], theory[1]
    on = np.flatnonzero(f > 0.0)
    span = float(t[on[-1]] - t[on[0]]) if on.size else 0.0
    impulse = float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(t)))
    return {"peak_force_N": float(np.max(f)), "contact_s": span, "impulse_Ns": impulse}


def reused_rows(record: Path, scenarios: dict) -> list[dict]:
    """The rows of a stored seed_plastic.json named in ``scenarios`` ({run label: the scenario
    it stands for now}), each checked against that scenario's provenance stamp; SystemExit with
    one line naming the run and what differs (runs.provenance.stamp_mismatch) if any
    row is not the same run."""
    rows = [r for r in json.loads(record.read_text())["rows"] if r["run"] in scenarios]
    for row in rows:
        why = stamp_mismatch(row.get("provenance"), stamp(scenarios[row["run"]]))
        if why is not None:
            raise SystemExit(f"--reuse {record}: its {row['run']} run was {why}: rerun it")
    return rows


def _duration_us(row: dict) -> float:
    iv = row["contact_intervals_s"]
    return 1e6 * (iv[-1][1] - iv[0][0]) if iv else float("nan")


def _fmt(row: dict, body: str) -> str:
    p = row["plastic"]
    wp = sum(e.get("plastic_work_J", 0.0) for e in p.values())
    alpha = " ".join(f"{e.get('peak_equivalent_plastic_strain', 0.0):.4f}" for e in p.values())
    dent = p.get(body, {}).get("permanent_indentation_m", 0.0)
    guard = p.get(body, {}).get("steps_yield_outside_retained", "-")
    ncc = {k[3:]: v.get("ncc_force", float("nan")) for k, v in row.items() if k.startswith("vs_")}
    nccs = " ".join(f"{k} {v:.5f}" for k, v in ncc.items())
    return (
        f"{row['run']:12s} {row['dof'].get(body, 0):6d} {row['peak_force_N']:8.1f} "
        f"{_duration_us(row):7.1f} {1e3 * row['impulse_Ns']:8.4f} "
        f"{row['striker_velocity_after_mps']:+8.4f} {row['restitution']:6.3f} "
        f"{1e6 * wp:9.2f} {1e6 * dent:7.3f} {alpha:>15s} {guard!s:>5s} "
        f"{row['wall_time_s']:7.1f}  {nccs}"
    )


HEAD = (
    f"{'run':12s} {'DOF':>6s} {'F_max N':>8s} {'dur us':>7s} {'J mNs':>8s} {'v1 m/s':>8s} "
    f"{'e':>6s} {'W_p uJ':>9s} {'dent um':>7s} {'alpha b1 b2':>15s} {'guard':>5s} "
    f"{'wall s':>7s}  force NCC"
)


def _figure(out: Path, curves: dict, theory, body: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    styles = {"elastic": "C0-", "plastic": "C3-"}
    for k, (label, (t, f, probes)) in enumerate(curves.items()):
        st = styles.get(label, f"C{k + 2}:")
        ax[0].plot(1e3 * t, f, st, lw=1.2, label=label)
        if label in styles:
            for k, (name, v) in enumerate(probes.items()):
                ax[1].plot(1e3 * t, v, st, lw=1.2 if k == 0 else 0.8, label=f"{label} {name}")
    if theory is not None:
        t, f, probes = theory
        ax[0].plot(1e3 * t, f, "k--", lw=0.8, label="1D theory (elastic)")
        for name, v in probes.items():
            ax[1].plot(1e3 * t, v, "k--", lw=0.8, label=f"theory {name}")
    ax[0].set(xlabel="t [ms]", ylabel="contact force [N]", title="contact force")
    ax[1].set(xlabel="t [ms]", ylabel="axial velocity [m/s]", title=f"{body}: end velocities")
    for a in ax:
        a.legend(fontsize=7)
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "seed_plastic.png", dpi=130)
    plt.close(fig)


def _save_curves(path: Path, curves) -> None:
    t, f, probes = curves
    np.savez(path, t=t, f=f, **{f"probe_{k}": v for k, v in probes.items()})


def _load_curves(path: Path):
    with np.load(path) as z:
        probes = {k[6:]: z[k] for k in z.files if k.startswith("probe_")}
        return z["t"], z["f"], probes


def _cases(args, plastic, elastic, reused: set) -> list:
    cases = [] if args.skip_elastic or "elastic" in reused else [("elastic", elastic)]
    if "plastic" not in reused:
        cases.append(("plastic", plastic))
    given = plastic.body(args.body).model  # its reference condition and allow_costly
    for text in [m for m in args.mvm.split(",") if m.strip()]:
        if text.strip() == "model":  # the scenario's own MVM form
            cfg = ModelConfig(**{**given.model_dump(), "kind": "mvm"})
            cases.append(("mvm model", plastic.with_model(args.body, cfg)))
            continue
        sel, modes = text.split(":")
        cfg = ModelConfig(
            kind="mvm",
            selection=sel,
            modes=int(modes),
            reference=given.reference,
            allow_costly=given.allow_costly,
        )
        cases.append((f"mvm {text}", plastic.with_model(args.body, cfg)))
    return cases


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--scenario", type=Path, default=DEFAULT)
    ap.add_argument("--t-end", type=float, default=None, help="end time [s]")
    ap.add_argument("--body", default="b2")
    ap.add_argument("--mvm", default="5-5:37", help="MVM forms of BODY, I-J:M, comma separated")
    ap.add_argument("--skip-elastic", action="store_true")
    ap.add_argument("--fine-mesh", action="store_true", help=f"every rod with {FINE_MESH}")
    ap.add_argument("--progress", action="store_true", help="a progress bar per run (stderr)")
    ap.add_argument(
        "--reuse", type=Path, default=None, help="an earlier OUT: its elastic and plastic runs"
    )
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    plastic = load_scenario(args.scenario)
    if args.t_end is not None:
        plastic = plastic.with_time(t_end_s=args.t_end)
    if args.fine_mesh:
        plastic = fine_copy(plastic)
    elastic = elastic_copy(plastic)
    try:
        theory = theory_histories(elastic)[:3]
    except Exception as exc:  # noqa: BLE001 - report, go on without theory
        print(f"no theory comparison: {exc}")
        theory = None
    refs = {} if theory is None else {"theory": theory}
    rows, curves = [], {}
    if args.reuse is not None:  # the same runs, stored with their stamps
        runs = {"elastic": elastic, "plastic": plastic}
        for row in reused_rows(args.reuse / "seed_plastic.json", runs):
            rows.append(row)
            curves[row["run"]] = refs[row["run"]] = _load_curves(args.reuse / f"{row['run']}.npz")
    print(f"{args.scenario.name}: t_end {plastic.time.t_end_s:g} s, dt {plastic.time.dt_s:g} s")
    print(HEAD, flush=True)
    for row in rows:
        print(_fmt(row, args.body), "(reused)", flush=True)
    t0 = time.perf_counter()
    for label, sc in _cases(args, plastic, elastic, set(curves)):
        c0 = time.process_time()
        try:
            run = run_scenario(sc, label=label, progress=args.progress)
        except (InputError, SimulationFailed) as exc:  # e.g. a region holding no whole cell
            print(f"{label:12s} not run: {exc}", flush=True)
            rows.append({"run": label, "status": "refused or failed", "reason": str(exc)})
            continue
        row = _row(label, run, sc, refs, time.process_time() - c0)
        rows.append(row)
        curves[label] = run.result.curves()
        _save_curves(args.out / f"{label.replace(' ', '_').replace(':', '_')}.npz", curves[label])
        if label in ("elastic", "plastic"):
            refs[label] = curves[label]
        print(_fmt(row, args.body), flush=True)
        out = {
            "scenario": str(args.scenario),
            "rod_mesh": FINE_MESH if args.fine_mesh else "the scenario's",
            "t_end_s": plastic.time.t_end_s,
            "dt_s": plastic.time.dt_s,
            "body": args.body,
            "theory": _theory_numbers(theory),
            "rows": rows,
            "wall_time_total_s": time.perf_counter() - t0,
        }
        (args.out / "seed_plastic.json").write_text(json.dumps(out, indent=1))
        _figure(args.out, curves, theory, args.body)  # after each run: a late stop keeps it


if __name__ == "__main__":
    main()
