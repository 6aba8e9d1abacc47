"""The validation cases: what each one runs and which numbers it reports.

1. flat variant, full FE, against St Venant: plateau mean force, free-end velocity jump time;
2. seed case, full FE, against the 1D wave-Hertz solution: NCC of force and probes, peak,
   impulse and contact-duration errors; the scenario's MVM (b2 1-3 + 37 modes) and the seed's
   1-1 + 37 against full FE;
3. time-step convergence of the seed full-FE force (h and h/2);
4. the short seed case (0.1 m rods, rod_impact_short.toml) that the default test run checks
   live: full FE and MVM against theory, and its mesh and step convergence;
5. the pendulum release (pendulum_release.toml), the whole event: impact speed, the impact
   against the seed case, the momenta after it against the rigid pendulum;
6. a rigid sphere on a meshed block (sphere_block.toml) against Hertz at two element sizes at
   the contact: the committed block and one meshed finer by gmsh at run time;
7. the arm spun up by a motor and swung into a stop (arm_stop.toml): MVM against full FE, the
   energy ledger's balance (validation/arm_stop.py).
Every run also reports its conservation (runs.conservation).

To add a case: a function ``(out, recompute) -> dict`` of its numbers (each stored run through
runs.run_case, its meta under "cases"), an entry in CASES, its rows in acceptance.ACCEPTANCE,
and its section of the page: a template in templates/ and its renderer in report.SECTIONS.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from flexmvm.errors import InputError
from flexmvm.materials import ALUMINIUM, BRASS
from flexmvm.runs.compare import compare_runs
from flexmvm.scenarios import ModelKind, Scenario, load_scenario
from flexmvm.scenarios import mvm as mvm_model
from flexmvm.theory.scenario import theory_histories
from flexmvm.theory.wave import Rod1D, st_venant_force
from tools.validation.arm_stop import arm_stop_case
from tools.validation.paths import scenario_path
from tools.validation.runs import Case, case_meta, conservation, run_case, truncate

#: The seed runs' settings (docs/validation.md): contact step, seed window, flat window, step
#: convergence window [s]. The seed and flat windows are their scenario files' own (2 ms, 2 us
#: free-flight steps after the contact): the figures the README's command prints.
DT = 0.5e-6
T_SEED = 2.0e-3
T_FLAT = 2.0e-3
T_STEP = 2.0e-4
#: The short case: its own file's t_end covers the contact (0..185 us) and the release.
SHORT_FINE_MESH = {"first_element_m": 0.15e-3, "core_elements": 4}


def _with_rod(sc: Scenario, **rod) -> Scenario:
    """A copy with the given [bodies.rod] keys set on every body."""
    for b in sc.bodies:
        sc = sc.with_rod(b.name, **rod)
    return sc


def _plot(path: Path, runs: dict, theory, title: str) -> None:
    from flexmvm.plots.figures import plot_run

    plot_run(path, runs, theory=theory, title=title)


def flat_vs_st_venant(
    out: Path, t_end: float | None = None, dt: float | None = None, recompute: bool = False
) -> dict:
    """Flat-ended rods, full FE, against St Venant's plateau force v0 Z1 Z2 / (Z1 + Z2) and
    the free end's jump at L / c2 (timed at half the 1D amplitude 2 F0 / Z2); the scenario as
    shipped (rod_impact_flat.toml, 2 ms) unless t_end or the contact step dt [s] are given."""
    sc = load_scenario(scenario_path("rod_impact_flat.toml")).with_kind(ModelKind.FULL)
    if t_end is not None or dt is not None:
        sc = sc.with_time(t_end_s=t_end, dt_s=dt)
    c = run_case(out, "flat_full", sc, recompute)
    t, f, p = c.curves
    rod1, rod2 = sc.body("b1").rod, sc.body("b2").rod
    if rod1 is None or rod2 is None:
        raise InputError("rod_impact_flat.toml: bodies b1 and b2 must be rods")
    r1 = Rod1D.from_material(BRASS, rod1.length_m, rod1.radius_m)
    r2 = Rod1D.from_material(ALUMINIUM, rod2.length_m, rod2.radius_m)
    F0 = st_venant_force(r1, r2, 0.21)
    T2 = 2 * r2.length_m / r2.c
    mid = (t > 0.2 * T2) & (t < 0.8 * T2)
    v = p["b2_free_end"]
    vp = 2 * F0 / r2.impedance
    jump = float(t[np.argmax(v > 0.5 * vp)])
    return {
        "F0_N": F0,
        "plateau_mean_N": float(f[mid].mean()),
        "plateau_err": float(f[mid].mean() / F0 - 1),
        "free_end_jump_s": jump,
        "L_over_c_s": r2.length_m / r2.c,
        "jump_err": jump / (r2.length_m / r2.c) - 1,
        **conservation(c.summary),
        "case": case_meta(c),
    }


def seed_scenario(t_end: float | None = None, dt: float | None = None) -> Scenario:
    """The seed case as users run it: rod_impact.toml as shipped (its 2 ms window, 0.5 us
    contact step, 2 us free-flight step and damping time), or with t_end and the contact step
    dt [s] overridden where given."""
    sc = load_scenario(scenario_path("rod_impact.toml"))
    if t_end is None and dt is None:
        return sc
    return sc.with_time(t_end_s=t_end, dt_s=dt)


def seed_vs_theory(
    out: Path,
    t_end: float | None = None,
    dt: float | None = None,
    recompute: bool = False,
    with_1_1: bool = False,
    plot: bool = False,
) -> dict:
    """The seed case (seed_scenario: as shipped unless t_end or dt are given): full FE and
    the scenario's MVM against the 1D wave-Hertz solution and each other; with_1_1: the
    seed's own 1-1 + 37 model against full FE too."""
    sc = seed_scenario(t_end, dt)
    tt, ft, pt, _ = theory_histories(sc)
    full = run_case(out, "seed_full", sc.with_kind(ModelKind.FULL), recompute)
    mvm = run_case(out, "seed_mvm", sc, recompute)
    b2 = sc.body("b2").model
    rep = {
        "full_vs_theory": compare_runs(tt, ft, pt, *full.curves),
        "mvm_vs_full": compare_runs(*full.curves, *mvm.curves),
        "mvm_vs_theory": compare_runs(tt, ft, pt, *mvm.curves),
        "full": conservation(full.summary),
        "mvm": conservation(mvm.summary),
        "mvm_dof": mvm.summary["dof"],
        "mvm_model": f"{b2.selection} + {b2.modes} modes",
        "t_end_s": sc.time.t_end_s,
        "cases": {"full": case_meta(full), "mvm": case_meta(mvm)},
    }
    runs = {"FE": full.curves, f"MVM {b2.selection} + {b2.modes}": mvm.curves}
    if with_1_1:
        m11 = mvm_model("1-1", b2.modes, reference=b2.reference)
        s11 = run_case(out, "seed_mvm_1-1", sc.with_model("b2", m11), recompute)
        rep["mvm11_vs_full"] = compare_runs(*full.curves, *s11.curves)
        rep["mvm11"] = conservation(s11.summary)
        rep["cases"]["mvm11"] = case_meta(s11)
        runs[f"MVM 1-1 + {b2.modes}"] = s11.curves
    if plot:  # the report's figure; the pytest checks leave the case folder as it is
        _plot(
            out / "seed_fig5.png",
            runs,
            (tt, ft, pt),
            f"seed case: full FE, MVM (b2 {b2.selection} + {b2.modes} modes, "
            f"{mvm.summary['dof']['b2']} DOF), 1D wave-Hertz",
        )
    return rep


def step_convergence(
    out: Path,
    t_end: float = T_STEP,
    dt: float = DT,
    t_end_h: float | None = None,
    recompute: bool = False,
) -> dict:
    """Full-FE seed force at h = dt and h/2 over [0, t_end]. The h run may be a longer one
    (``t_end_h``, e.g. the seed_full case: the same steps up to t_end), truncated to t_end."""
    sc = seed_scenario().with_kind(ModelKind.FULL)
    t_h = t_end if t_end_h is None else t_end_h
    shipped = t_h == sc.time.t_end_s and dt == sc.time.dt_s  # the seed case's own full FE run
    a = run_case(
        out,
        "seed_full" if shipped else f"seed_full_dt{dt:g}",
        sc if shipped else sc.with_time(t_end_s=t_h, dt_s=dt),
        recompute,
    )
    b = run_case(
        out, f"seed_full_dt{dt / 2:g}", sc.with_time(t_end_s=t_end, dt_s=dt / 2), recompute
    )
    return {
        "h": dt,
        "t_end": t_end,
        "h_half_vs_h": compare_runs(*b.curves, *truncate(a, t_end)),
        "cases": {"h": case_meta(a), "h_half": case_meta(b)},
    }


def short_scenario() -> Scenario:
    """The short seed case (0.1 m rods): rod_impact_short.toml."""
    return load_scenario(scenario_path("rod_impact_short.toml"))


def short_case(out: Path, recompute: bool = False, plot: bool = False) -> dict:
    """Short seed case: full FE and the scenario's MVM against theory and each other; the full
    FE with the contact zone refined (SHORT_FINE_MESH) and with h/2 against full FE at h."""
    sc = short_scenario()
    tt, ft, pt, _ = theory_histories(sc)
    full = run_case(out, "short_full", sc.with_kind(ModelKind.FULL), recompute)
    mvm = run_case(out, "short_mvm", sc, recompute)
    fine = run_case(
        out,
        "short_full_fine",
        _with_rod(sc.with_kind(ModelKind.FULL), **SHORT_FINE_MESH),
        recompute,
    )
    half = run_case(
        out,
        "short_full_dt_half",
        sc.with_kind(ModelKind.FULL).with_time(dt_s=sc.time.dt_s / 2),
        recompute,
    )
    b2 = sc.body("b2").model
    if plot:
        _plot(
            out / "short_fig.png",
            {
                "FE": full.curves,
                "FE fine": fine.curves,
                f"MVM {b2.selection} + {b2.modes}": mvm.curves,
            },
            (tt, ft, pt),
            "short case (0.1 m rods): full FE, refined FE, MVM, 1D wave-Hertz",
        )
    return {
        "full_vs_theory": compare_runs(tt, ft, pt, *full.curves),
        "fine_vs_theory": compare_runs(tt, ft, pt, *fine.curves),
        "mvm_vs_theory": compare_runs(tt, ft, pt, *mvm.curves),
        "mvm_vs_full": compare_runs(*full.curves, *mvm.curves),
        "full_vs_fine": compare_runs(*fine.curves, *full.curves),
        "full_vs_dt_half": compare_runs(*half.curves, *full.curves),
        "theory_peak_N": float(ft.max()),
        "theory_end_s": float(tt[ft > 0].max()),
        "full": conservation(full.summary),
        "mvm": conservation(mvm.summary),
        "fine": conservation(fine.summary),
        "dt_half": conservation(half.summary),
        "mvm_model": f"{b2.selection} + {b2.modes} modes",
        "fine_mesh": SHORT_FINE_MESH,
        "dt": sc.time.dt_s,
        "t_end": sc.time.t_end_s,
        "cases": {
            k: case_meta(c)
            for k, c in (("full", full), ("mvm", mvm), ("fine", fine), ("dt_half", half))
        },
    }


def _as_run(c: Case) -> SimpleNamespace:
    """A stored case as runs.showcases.pendulum.impact_comparison reads a run: times, force,
    contact intervals and the probes' axial velocities."""
    names = list(c.probes)
    v = np.stack([c.probes[n] for n in names], axis=1)[:, :, None] if names else None
    return SimpleNamespace(
        t=c.t,
        contact_force=c.force,
        probe_names=names,
        probe_v=v,
        contact_intervals=[tuple(iv) for iv in c.summary.get("contact_intervals_s") or []],
    )


def pendulum_case(out: Path, recompute: bool = False) -> dict:
    """The seed's experiment, the whole event (pendulum_release.toml on its defaults:
    release, swing, impact, separation, 4.5 ms past it): impact speed against sqrt(2 g h) (h:
    b1's start height), the impact phase against the seed case with the same models and
    scheme (the seed_mvm case: rod_impact.toml as shipped) aligned at first contact, the momenta
    after the separation against the rigid pendulum, the strings' drift."""
    from flexmvm.runs.showcases.pendulum import impact_comparison

    sc = load_scenario(scenario_path("pendulum_release.toml"))
    c = run_case(out, "pendulum", sc, recompute)  # its summary's "pendulum": runs.run
    ref = run_case(out, "seed_mvm", seed_scenario(), recompute)
    ev = c.summary["pendulum"]
    g = float(np.linalg.norm(sc.gravity_mps2))
    h = float(sc.body("b1").placement.position_m[2])
    v_th = float(np.sqrt(2.0 * g * h))
    v = ev["impact_speed"]["v_mps"]
    return {
        "impact_speed_mps": v,
        "impact_speed_theory_mps": v_th,
        "release_height_m": h,
        "impact_speed_err": v / v_th - 1.0,
        "vs_seed": impact_comparison(_as_run(c), _as_run(ref)),
        "momenta": ev["momenta_after_separation"],
        "energy_rel_at_separation": ev["energy_rel_at_separation"],
        "max_joint_drift_m": c.summary["max_joint_drift"],
        "step_size_counts": c.summary["step_size_counts"],
        "models": c.summary["model"],
        **conservation(c.summary),
        "cases": {"pendulum": case_meta(c), "seed": case_meta(ref)},
    }


#: The Hertz block case's element sizes at the contact [m]: the committed block's and a finer
#: one meshed at run time (mesh/parts.py hertz_block_part).
HERTZ_BLOCK_SIZES_M = {"coarse": None, "fine": 0.2e-3}


def _hertz_block_mesh(out: Path, fine_m: float) -> Path:
    """The block meshed at fine_m under out/meshes/, made once (written beside and renamed:
    a run killed while gmsh writes leaves no partial mesh to be read next time)."""
    from flexmvm.mesh.parts import hertz_block_part

    path = out / "meshes" / f"block_{fine_m * 1e6:.0f}um.msh"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = hertz_block_part(path.with_suffix(".partial.msh"), fine_m)
        tmp.replace(path)
    return path


def hertz_block_case(out: Path, recompute: bool = False) -> dict:
    """A rigid steel sphere (R 10 mm, 0.5 m/s) on a free aluminium block (sphere_block.toml
    as shipped: 0.2 ms) against Hertz with the block's recoil (runs.showcases.hertz_block): peak
    force and duration of the first contact, with the committed block (coarse) and one meshed
    finer at run time."""
    from flexmvm.runs.showcases.hertz_block import (
        hertz_comparison,
        hertz_reference,
        sphere_block_scenario,
    )

    numbers: dict = {"cases": {}}
    for label, fine_m in HERTZ_BLOCK_SIZES_M.items():
        block = None if fine_m is None else _hertz_block_mesh(out, fine_m)
        sc = sphere_block_scenario(block, path=scenario_path("sphere_block.toml"))
        c = run_case(out, f"hertz_block_{label}", sc, recompute)
        numbers[label] = {
            **conservation(c.summary),
            **hertz_comparison(hertz_reference(sc), c.force, c.summary),
            "element_m": fine_m if fine_m is not None else "committed",
        }
        numbers["cases"][label] = case_meta(c)
    return numbers


@dataclass(frozen=True)
class ValidationCase:
    """A case of the report: its key in validation.json, how the full report runs it
    (out, recompute) -> numbers, and the names of its stored runs in the report's table of
    cases {name: key of numbers["cases"]} (or of numbers["case"] for a single run)."""

    key: str
    run: Callable[[Path, bool], dict]
    stored: dict[str, str]


#: The report's cases, in the order they run (validation.json's keys).
CASES: tuple[ValidationCase, ...] = (
    ValidationCase(
        "flat_vs_st_venant", lambda out, rc: flat_vs_st_venant(out, recompute=rc), {"flat_full": ""}
    ),
    ValidationCase(
        "seed",
        lambda out, rc: seed_vs_theory(out, recompute=rc, with_1_1=True, plot=True),
        {"seed_full": "full", "seed_mvm": "mvm", "seed_mvm_1-1": "mvm11"},
    ),
    ValidationCase(
        "step_convergence",
        lambda out, rc: step_convergence(out, t_end_h=T_SEED, recompute=rc),
        {"seed_full_dt_half": "h_half"},
    ),
    ValidationCase(
        "short",
        lambda out, rc: short_case(out, recompute=rc, plot=True),
        {
            "short_full": "full",
            "short_mvm": "mvm",
            "short_fine": "fine",
            "short_dt_half": "dt_half",
        },
    ),
    ValidationCase(
        "pendulum", lambda out, rc: pendulum_case(out, recompute=rc), {"pendulum": "pendulum"}
    ),
    ValidationCase(
        "hertz_block",
        lambda out, rc: hertz_block_case(out, recompute=rc),
        {"hertz_block_coarse": "coarse", "hertz_block_fine": "fine"},
    ),
    ValidationCase(
        "arm_stop",
        lambda out, rc: arm_stop_case(out, recompute=rc, plot=True),
        {"arm_stop_full": "full", "arm_stop_mvm": "mvm"},
    ),
)


def stored_cases(report: dict) -> dict:
    """{name: case meta} of every stored run behind the report's numbers (its table of
    cases)."""
    out = {}
    for case in CASES:
        numbers = report.get(case.key)
        if numbers is None:
            continue
        for name, which in case.stored.items():
            meta = numbers["case"] if not which else numbers["cases"].get(which)
            if meta is not None:
                out[name] = meta
    return out


def case(key: str) -> ValidationCase:
    """The case of CASES with this key."""
    return next(c for c in CASES if c.key == key)


__all__ = [
    "CASES",
    "DT",
    "HERTZ_BLOCK_SIZES_M",
    "SHORT_FINE_MESH",
    "T_FLAT",
    "T_SEED",
    "T_STEP",
    "ValidationCase",
    "case",
    "flat_vs_st_venant",
    "hertz_block_case",
    "pendulum_case",
    "seed_scenario",
    "seed_vs_theory",
    "short_case",
    "short_scenario",
    "step_convergence",
    "stored_cases",
]
