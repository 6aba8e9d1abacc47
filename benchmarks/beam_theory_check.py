"""The beam theory of scenarios/sphere_beam.toml side by side with flexmvm's full FE and MVM
runs of it (docs/beam_impact.md): contact windows, peaks and NCC against the full FE, and a
figure. It runs the scenario's full FE and MVM models (about a minute of CPU) and computes the
theory (seconds); the record carries each run's provenance stamp:

    python benchmarks/beam_theory_check.py --run --out docs/beam_impact

or reads two finished runs (the record then has no stamp: not for docs/):

    flexmvm run scenarios/sphere_beam.toml --out /tmp/sb-full --no-fields --no-theory
    flexmvm run scenarios/sphere_beam.toml --model mvm --out /tmp/sb-mvm --no-fields --no-theory
    python benchmarks/beam_theory_check.py /tmp/sb-full /tmp/sb-mvm --out /tmp/sb-theory

Five theories, to tell what separates the FE model from beam theory + Hertz:
- "Hertz": the theory as shipped (flexmvm.theory.sphere_beam);
- "FE bending": the beam's E scaled by (f_FE / f_T)^2, f the first free-free bending
  frequency in the impact plane of the FE beam (its mesh) and of the Timoshenko beam;
- "FE local law": Hertz's law replaced by F = k s^p fitted (least squares in log-log) to the
  full FE run's own force against approach over its first contact (F above 10 % of its peak),
  the approach being the sphere's displacement (v0 - int F / m) minus the probe
  beam_mid_bottom's (bottom face, 5 mm from mid-span: the beam's deflection there);
- "FE bending + local law": both;
- "Hertz less depth": Hertz's approach less what the half-space gives way below the beam's
  mid-depth, the Boussinesq displacement of the axis at depth h/2 under a point load,
  F (1 + nu)(3 - 2 nu) / (2 pi E h/2) (Johnson 1985, sect. 3.2): beam theory's w of the axis
  holds that part already (the sum u - w = s_Hertz + w counts it twice); the law s_H(F) - c F
  is fitted by F = k s^p (least squares in log-log over 10-300 N, within 1 % of it).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

import numpy as np
from scipy.integrate import cumulative_trapezoid

from flexmvm.metrics.ncc import contact_intervals
from flexmvm.runs.compare import compare_runs
from flexmvm.scenarios.load import load_scenario
from flexmvm.theory.sphere_beam import case_histories, sphere_beam_case

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "sphere_beam.toml"
PROBE = "beam_mid_bottom"


def read_run(run_dir: Path):
    h = np.genfromtxt(run_dir / "history.csv", delimiter=",", names=True)
    probes = {n[: -len("_vx_mps")]: h[n] for n in h.dtype.names if n.endswith("_vx_mps")}
    return h["t_s"], h["contact_force_N"], probes


def run_models(sc) -> tuple[tuple, tuple, dict]:
    """The scenario's full FE and MVM runs in this process: (t, force, probes) of each and
    their provenance stamps."""
    from flexmvm.runs.provenance import stamp
    from flexmvm.runs.run import run_scenario

    out, stamps = [], {}
    for kind in ("full", "mvm"):
        run_sc = sc.with_kind(kind)
        srun = run_scenario(run_sc, label=kind)
        names = [p.name for p in run_sc.probes]
        probes = {n: srun.probe(n).v[:, 0] for n in names}
        out.append((np.asarray(srun.t), np.asarray(srun.contact_force), probes))
        stamps[kind] = stamp(run_sc)
    return out[0], out[1], stamps


def fe_bending_ratio(sc, case) -> tuple[float, float]:
    """(f_FE, f_T) [Hz]: the first free-free bending frequency in the impact plane of the FE
    beam (the mode whose displacement lies most along the impact normal) and of the
    Timoshenko beam."""
    from flexmvm.assembly.build_cache import default_setup

    cfg = sc.body(case.beam)
    _, source = default_setup().free_modes_source(cfg)
    freqs, modes = source(16)
    normal = cfg.placement.rotation.matrix().T @ np.asarray(
        sc.body(case.sphere).placement.velocity_mps, dtype=float
    )
    normal = np.abs(normal) / np.linalg.norm(normal)
    for f, phi in zip(freqs[6:], modes[:, 6:].T):
        share = (phi.reshape(-1, 3) ** 2).sum(axis=0)
        if share @ normal > 0.9 * share.sum():
            return float(f), float(case.impact.modes().omega[2] / (2.0 * np.pi))
    raise SystemExit("no bending mode in the impact plane among the FE beam's first 10")


def fit_local_law(t, force, probes, m_sphere: float, v0: float) -> tuple[float, float]:
    """(k, p) of F = k s^p fitted to the run's first contact (module doc)."""
    v_sphere = v0 - cumulative_trapezoid(force, t, initial=0.0) / m_sphere
    approach = cumulative_trapezoid(v_sphere + probes[PROBE], t, initial=0.0)  # w_t = -v_x
    first = contact_intervals(t, force, 0.01 * force.max())[0]
    inside = (t >= first[0]) & (t <= first[1])
    ok = inside & (force > 0.1 * force[inside].max()) & (approach > 0)
    p, log_k = np.polyfit(np.log(approach[ok]), np.log(force[ok]), 1)
    return float(np.exp(log_k)), float(p)


def depth_corrected_law(impact) -> tuple[float, float, float]:
    """(k, p, c): F = k s^p fitted to s = (F / k_Hertz)^(2/3) - c F on 10-300 N, c [m/N] the
    Boussinesq compliance of a half-space at depth h/2 on the load's axis (module doc)."""
    b = impact.beam
    c = (1.0 + b.nu) * (3.0 - 2.0 * b.nu) / (2.0 * np.pi * b.E_pa * b.depth_m / 2.0)
    force = np.linspace(10.0, 300.0, 200)
    s = (force / impact.hertz_k) ** (2.0 / 3.0) - c * force
    p, log_k = np.polyfit(np.log(s), np.log(force), 1)
    return float(np.exp(log_k)), float(p), float(c)


def row(name: str, t, f, probes, ref) -> dict:
    c = compare_runs(*ref, t, f, probes)
    windows = [
        (round(a * 1e6, 1), round(b * 1e6, 1)) for a, b in contact_intervals(t, f, 0.01 * f.max())
    ]
    return {
        "model": name,
        "contacts_us": windows,
        "peak_N": round(float(f.max()), 1),
        **{k: round(v, 4) for k, v in c.items() if isinstance(v, float)},
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("full", type=Path, nargs="?")
    ap.add_argument("mvm", type=Path, nargs="?")
    ap.add_argument("--run", action="store_true", help="run full FE and MVM here (stamped)")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    if args.run == (args.full is not None):
        ap.error("give either --run or the two run folders FULL MVM")
    sc = load_scenario(SCENARIO)
    t_end = sc.time.t_end_s
    case = sphere_beam_case(sc)
    if args.run:
        full, mvm, stamps = run_models(sc)
    else:
        full, mvm, stamps = read_run(args.full), read_run(args.mvm), {}
    f_fe, f_t = fe_bending_ratio(sc, case)
    k, p = fit_local_law(*full, case.impact.sphere_mass_kg, case.impact.speed_mps)
    k_d, p_d, c_d = depth_corrected_law(case.impact)
    beam = case.impact.beam
    stiffer = dataclasses.replace(beam, E_pa=beam.E_pa * (f_fe / f_t) ** 2)
    variants = {
        "theory, Hertz": case.impact,
        "theory, FE bending": dataclasses.replace(case.impact, beam=stiffer),
        "theory, FE local law": dataclasses.replace(case.impact, local_law=(k, p)),
        "theory, FE bending + local law": dataclasses.replace(
            case.impact, beam=stiffer, local_law=(k, p)
        ),
        "theory, Hertz less depth": dataclasses.replace(case.impact, local_law=(k_d, p_d)),
    }
    rows = [row("full FE", *full, full), row("MVM", *mvm, full)]
    curves = {"full FE": full, "MVM": mvm}
    for name, imp in variants.items():
        t, f, probes, _ = case_histories(dataclasses.replace(case, impact=imp), t_end)
        rows.append(row(name, t, f, probes, full))
        curves[name] = (t, f, probes)
    info = {
        "fe_first_bending_hz": f_fe,
        "timoshenko_first_bending_hz": f_t,
        "modulus_scale": (f_fe / f_t) ** 2,
        "local_law_k": k,
        "local_law_p": p,
        "depth_compliance_m_per_n": c_d,
        "depth_law_k": k_d,
        "depth_law_p": p_d,
        "hertz_k": case.impact.hertz_k,
        "sphere_mass_kg": case.impact.sphere_mass_kg,
    }
    print(json.dumps(info, indent=1))
    print(
        "| model | contacts [us] | peak [N] | force NCC (windows / whole) | peak err | "
        "impulse err | NCC beam_mid_bottom / beam_end_a |"
    )
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['model']} | {', '.join(f'{a}-{b}' for a, b in r['contacts_us'])} | "
            f"{r['peak_N']} | {r['ncc_force']:.4f} / {r['ncc_force_whole']:.4f} | "
            f"{100 * r['peak_err']:+.1f} % | {100 * r['impulse_err']:+.1f} % | "
            f"{r['ncc_beam_mid_bottom']:.3f} / {r['ncc_beam_end_a']:.3f} |"
        )
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "sphere_beam_theory.json").write_text(
            json.dumps({"info": info, "rows": rows, "provenance": stamps}, indent=1) + "\n"
        )
        plot(args.out / "sphere_beam_theory.png", curves)


def plot(path: Path, curves: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    shown = ("full FE", "MVM", "theory, Hertz", "theory, Hertz less depth")
    style = {
        "full FE": ("k", "-", 2.2),
        "MVM": ("tab:orange", "--", 1.4),
        "theory, Hertz": ("tab:blue", "-", 1.2),
        "theory, Hertz less depth": ("tab:green", ":", 1.6),
    }
    fig, axes = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
    for name in shown:
        t, f, probes = curves[name]
        color, ls, lw = style[name]
        axes[0].plot(t * 1e6, f, color=color, ls=ls, lw=lw, label=name)
        axes[1].plot(t * 1e6, probes["beam_end_a"], color=color, ls=ls, lw=lw)
    axes[0].set_ylabel("contact force [N]")
    axes[1].set_ylabel("beam end A, v_x [m/s]")
    axes[1].set_xlabel("t [us]")
    axes[0].legend(fontsize=8)
    axes[0].set_title("sphere on a free beam: full FE, MVM and Timoshenko beam + contact law")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    main()
