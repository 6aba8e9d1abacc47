"""The figure and numbers of docs/slider_crank.md: the connecting rod's mid-span deflection over
the first crank revolution of scenarios/slider_crank.toml, full FE on two meshes and two steps,
MVM, and the pinned-pinned beam reference (flexmvm.theory.slider_crank).

    python docs/slider_crank/figure.py            # runs what is not stored yet, then plots
    python docs/slider_crank/figure.py --rerun    # runs every case again

Each run's deflection history is stored in docs/slider_crank/<case>.npz (t [s], w [m], the
run's CPU time [s] (time.process_time, this process) and wall time [s], the summary entries of
SUMMARY_KEYS, and the run's provenance stamp, flexmvm.runs.provenance.stamp, as JSON), so the
figure can be remade without the runs; numbers.json carries every run's stamp and summary
entries, and a stored run whose stamp is not the current code's is named on stderr. The rod
meshes other than the shipped one are written to a temporary folder by flexmvm.mesh.link. The
four runs one after the other take ~20 min CPU on the project's 2-core machine.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

import flexmvm as fm
from flexmvm.mesh import link
from flexmvm.metrics.ncc import ncc
from flexmvm.runs.provenance import stamp, stamp_mismatch
from flexmvm.theory.slider_crank import SliderCrank, chord_deflection

HERE = Path(__file__).resolve().parent
SCENARIO = HERE.parents[1] / "scenarios" / "slider_crank.toml"
REVOLUTION_S = 2 * np.pi / 150.0
# case: (rod model kind, rod element size [m], step [s], window [s])
CASES = {
    "full_4mm_h100us": ("full", 4.0e-3, 1.0e-4, REVOLUTION_S),
    "full_8mm_h100us": ("full", 8.0e-3, 1.0e-4, REVOLUTION_S),
    "full_4mm_h50us": ("full", 4.0e-3, 5.0e-5, REVOLUTION_S),
    "mvm_4mm_h100us": ("mvm", 4.0e-3, 1.0e-4, REVOLUTION_S),
}
# Simeon's rod: steel 300 x 8 x 8 mm, crank 150 mm at 150 rad/s
ROD = SliderCrank(0.15, 0.30, 150.0, 200.0e9, 7870.0, 0.008**2, 0.008**4 / 12)
# the IVP test set's reference solution of the "crank" problem at t = 0.1 s (its y(4): the
# first lateral mode's coordinate = the mid-span deflection) from its initial values y(11)
SIMEON_Q1_T01_M = 1.893192460247178e-04
SIMEON_Q1_DOT0_MPS = 0.444896105
# the summary entries (flexmvm.runs.run.summarize, current names) each run's record keeps
SUMMARY_KEYS = (
    "status",
    "n_steps",
    "steps_on_roundoff_floor",
    "step_cuts",
    "max_joint_drift",
    "energy_rel_change",
    "numerical_dissipation_J",
    "newton_residual_max",
)


def case_scenario(kind: str, size_m: float, dt_s: float, t_end_s: float, mesh_dir: Path):
    """The shipped scenario with the rod's model kind, mesh size, step and window replaced."""
    with open(SCENARIO, "rb") as f:
        d = tomllib.load(f)
    for b in d["bodies"]:
        b["mesh_file"] = str(SCENARIO.parent / b["mesh_file"])
    rod = d["bodies"][1]
    rod["model"]["kind"] = kind
    if size_m != 4.0e-3:
        rod["mesh_file"] = str(
            link.slider_crank_rod(mesh_dir / f"rod_{size_m * 1e3:.2f}mm.msh", size_m)
        )
    d["time"].update(t_end_s=t_end_s, dt_s=dt_s, output_dt_s=max(dt_s, 1.0e-4))
    d.pop("compare", None)
    return fm.scenario_from_dict(d)


def run_case(sc) -> dict:
    """A run of ``sc``: its mid-span deflection history from its probes, its CPU and wall time,
    its SUMMARY_KEYS entries and its provenance stamp (both as JSON text)."""
    c0, t0 = time.process_time(), time.time()
    run = fm.run(sc)
    cpu_s, wall_s = time.process_time() - c0, time.time() - t0
    w = chord_deflection(*(run.probe(n).x for n in ("pin_a", "mid", "pin_b")))
    return {
        "t": run.t,
        "w": w,
        "cpu_s": cpu_s,
        "wall_s": wall_s,
        "steps": run.result.n_steps,
        "summary": json.dumps({k: run.summary.get(k) for k in SUMMARY_KEYS}),
        "provenance": json.dumps(stamp(sc)),
    }


def stored(name: str, rerun: bool, mesh_dir: Path) -> dict:
    """The stored run ``name`` (run and stored first if asked or absent); a stored run made
    under other code, libraries or inputs is named on stderr (stamp_mismatch)."""
    path = HERE / f"{name}.npz"
    sc = case_scenario(*CASES[name], mesh_dir)
    if rerun or not path.exists():
        np.savez(path, **run_case(sc))
    out = dict(np.load(path))
    why = stamp_mismatch(
        json.loads(str(out["provenance"])) if "provenance" in out else None, stamp(sc)
    )
    if why is not None:
        print(f"{name}.npz: {why}; rerun with --rerun", file=sys.stderr)
    return out


def numbers(runs: dict) -> dict:
    """NCC, peaks and their differences; the reference on the full-FE run's samples."""
    ref = runs["full_4mm_h100us"]
    t = ref["t"]
    theory = ROD.midspan_deflection(t, modes=3)
    out = {"peaks_mm": {}, "ncc": {}}
    for name, r in {**runs, "theory_3_modes": {"t": t, "w": theory}}.items():
        out["peaks_mm"][name] = [float(r["w"].max() * 1e3), float(r["w"].min() * 1e3)]
    for name, r in runs.items():
        if name != "full_4mm_h100us":
            out["ncc"][f"{name} vs full_4mm_h100us"] = ncc(t, ref["w"], r["t"], r["w"])
    out["ncc"]["full_4mm_h100us vs theory_3_modes"] = ncc(t, theory, t, ref["w"])
    for name in ("full_8mm_h100us", "full_4mm_h50us", "mvm_4mm_h100us"):
        r = runs[name]
        wi = np.interp(t, r["t"], r["w"], right=np.nan)
        ok = np.isfinite(wi)
        out.setdefault("max_difference_mm", {})[f"{name} - full_4mm_h100us"] = float(
            np.abs(wi[ok] - ref["w"][ok]).max() * 1e3
        )
    tt = np.linspace(0.0, 0.1, 20001)
    q1 = ROD.midspan_deflection(tt, modes=3, q0=np.zeros(3), q0_dot=[SIMEON_Q1_DOT0_MPS, 0, 0])
    out["simeon_check"] = {
        "published_w_t0.1_m": SIMEON_Q1_T01_M,
        "theory_3_modes_w_t0.1_m": float(q1[-1]),
    }
    out["wall_s"] = {name: float(r["wall_s"]) for name, r in runs.items()}
    out["steps"] = {name: int(r["steps"]) for name, r in runs.items()}
    out["cpu_s"] = {name: float(r["cpu_s"]) for name, r in runs.items()}
    out["summary"] = {name: json.loads(str(r["summary"])) for name, r in runs.items()}
    out["provenance"] = {name: json.loads(str(r["provenance"])) for name, r in runs.items()}
    return out


def figure(runs: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = runs["full_4mm_h100us"]["t"]
    fig, ax = plt.subplots(figsize=(8.0, 4.2))
    ax.plot(
        t * 1e3,
        ROD.midspan_deflection(t, modes=3) * 1e3,
        "k-",
        lw=2.5,
        alpha=0.35,
        label="pinned-pinned beam, 3 modes (theory)",
    )
    styles = {
        "full_4mm_h100us": ("C0-", "full FE, 4 mm, h = 100 us"),
        "full_8mm_h100us": ("C1--", "full FE, 8 mm, h = 100 us"),
        "full_4mm_h50us": ("C2:", "full FE, 4 mm, h = 50 us"),
        "mvm_4mm_h100us": ("C3-.", "MVM (end faces + 8 modes), 4 mm, h = 100 us"),
    }
    for name, (style, label) in styles.items():
        ax.plot(runs[name]["t"] * 1e3, runs[name]["w"] * 1e3, style, lw=1.2, label=label)
    ax.set_xlabel("t [ms] (one crank revolution: 41.9 ms)")
    ax.set_ylabel("mid-span deflection [mm]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(argv: list[str]) -> int:
    rerun = "--rerun" in argv
    with tempfile.TemporaryDirectory() as tmp:
        runs = {name: stored(name, rerun, Path(tmp)) for name in CASES}
    out = numbers(runs)
    (HERE / "numbers.json").write_text(json.dumps(out, indent=2) + "\n")
    figure(runs, HERE / "deflection.png")
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
