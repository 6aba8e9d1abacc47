"""The validation report: docs/validation.md written from the cases' numbers
(validation.json), never edited by hand. The prose is in templates/*.md (one per section,
string.Template placeholders); this module formats the numbers that fill them, and states each
acceptance from the one table of acceptance.py.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from string import Template

import numpy as np

from flexmvm.errors import InputError
from flexmvm.results.atomic import write_text_atomic
from tools.validation import acceptance as acc
from tools.validation.cases import DT, SHORT_FINE_MESH


def _template(name: str) -> Template:
    """templates/<name>.md without its surrounding newlines (sections are joined by one
    blank line)."""
    text = resources.files("tools.validation").joinpath("templates", f"{name}.md")
    return Template(text.read_text(encoding="utf-8").strip("\n"))


def _p(x: float | None, digits: int = 2) -> str:
    return "n/a" if x is None else f"{100 * x:+.{digits}f} %"


def _e(x: float | None) -> str:
    return "n/a" if x is None else f"{x:.1e}"


def _n(x: float | None, digits: int = 4) -> str:
    if x is None:
        return "n/a"
    # show NCCs close to 1 with enough nines
    if 0.99 <= x < 1.0:
        nines = int(np.floor(-np.log10(1.0 - x)))
        return f"{x:.{max(digits, nines + 2)}f}"
    return f"{x:.{digits}f}"


def _us(x: float) -> str:
    return f"{1e6 * x:g} us"


def _pct(x: float) -> str:
    """A relative bound as the report states it: 0.03 -> "3"."""
    return f"{100 * x:g}"


def _met(ok: bool) -> str:
    return "met" if ok else "NOT met"


def _row(label: str, c: dict) -> str:
    return (
        f"| {label} | {_n(c.get('ncc_force'))} | {_p(c.get('peak_err'))} | "
        f"{_p(c.get('impulse_err'))} | {_p(c.get('duration_err'))} | "
        f"{_n(c.get('ncc_b2_free_end'))} | {_n(c.get('ncc_b2_impact_end'), 3)} |"
    )


_HEAD = (
    "| comparison | force NCC | peak | impulse | contact duration | b2 free-end NCC "
    "| b2 impact-end NCC |\n|---|---|---|---|---|---|---|"
)

#: The rows of a conservation table: (label, format of one run's conservation dict).
_CONSERVATION_ROWS = (
    (
        "linear momentum as the steps converged (before the balance), relative",
        lambda s: _e(s["momentum_rel_error_converged"]),
    ),
    (
        "... after the balance of the steps' translational rows, relative",
        lambda s: _e(s["momentum_rel_error"]),
    ),
    ("energy (end vs start), relative", lambda s: _e(s["energy_rel_change"])),
    (
        "momentum the solves left unbalanced (their residuals summed, before the balance)",
        lambda s: _e(s.get("momentum_residual_rel")),
    ),
    ("max penetration (both surfaces, every step)", lambda s: f"{s['max_penetration_m']:.1e} m"),
    (
        "... per direction",
        lambda s: ", ".join(
            f"{k}: {v:.1e} m"
            for k, v in sorted((s.get("max_penetration_by_direction_m") or {}).items())
        ),
    ),
    ("LCP complementarity residual, max", lambda s: _e(s.get("lcp_residual_max"))),
    (
        "Newton steps not converged (worst residual)",
        lambda s: f"{s.get('steps_on_roundoff_floor')} ({_e(s.get('newton_residual_max'))})",
    ),
    (
        "contact intervals",
        lambda s: ", ".join(
            f"{1e6 * a:.1f}..{1e6 * b:.1f} us" for a, b in s["contact_intervals_s"]
        ),
    ),
    ("DOF (b1, b2), incl. 6 frame DOF each", lambda s: f"{s['dof']['b1']:,}, {s['dof']['b2']:,}"),
    ("steps, wall time", lambda s: f"{s['n_steps']:,}, {s['wall_time_s']:.0f} s"),
)


def _cons_table(cols: dict[str, dict]) -> str:
    names = list(cols)
    lines = ["| conservation | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
    for label, fmt in _CONSERVATION_ROWS:
        lines.append(f"| {label} | " + " | ".join(fmt(cols[n]) for n in names) + " |")
    return "\n".join(lines)


def _header(report: dict) -> str:
    meta = report["meta"]
    return _template("header").substitute(
        date=meta["date"], machine=meta["machine"], theta=report["theta"], h=_us(DT)
    )


def _energy_sentence(seed: dict) -> str:
    """The seed's energy over the shipped window against its bound (acceptance
    SEED_ENERGY_BOUND); a report stored before the validation ran the shipped window (no
    t_end_s) says so instead."""
    if "t_end_s" not in seed:
        return (
            "Energy over the shipped 2 ms window: not in these stored numbers (1 ms runs, "
            "before 2026-11-29); `python -m tools.validation` adds it."
        )
    bound = acc.SEED_ENERGY_BOUND
    met = acc.met(seed, "seed", "seed, energy over the shipped window")
    return (
        f"Energy over the shipped window ({1e3 * seed['t_end_s']:g} ms: 0.5 us steps through "
        f"the contact, 2 us free flight), |dE/E| < {_e(bound)}: full FE "
        f"{_e(seed['full']['energy_rel_change'])}, MVM {_e(seed['mvm']['energy_rel_change'])}: "
        f"**{_met(met)}**; the free-flight steps take theta = 0.5025, whose damping of the "
        "waves they resolve is the contact step's (theta = 1/2 + h / (4 tau) at every step "
        "size, 0.54 at 2 us, lost -1.7e-3 over the 2 ms: "
        "[note](notes/2026-11-29-seed-window.md))."
    )


def _mvm11_sentence(seed: dict) -> str:
    if "mvm11_vs_full" not in seed:
        return ""
    m11 = seed["mvm11_vs_full"]["ncc_force"]
    return f" The seed's 1-1 + 37 model: force\nNCC {_n(m11)} against this full-FE mesh, " + (
        "which meets 0.99."
        if m11 >= 0.99
        else "short of 0.99: one retained node cannot carry the Hertz pressure over the "
        "resolved contact patch (the seed's NCC 0.99 for 1-1 was against its own "
        "coarser full-FE mesh)."
    )


def _seed(seed: dict) -> str:
    theory, mvm = "seed, full FE vs theory", "seed, MVM vs full FE"
    # the window the stored runs ran (reports stored before 2026-11-29 have no t_end_s: 1 ms)
    window = f"{1e3 * seed.get('t_end_s', 1.0e-3):g} ms"
    row11 = ""
    if "mvm11_vs_full" in seed:
        row11 = (
            _row(
                f"MVM, the seed's 1-1 + 37 modes ({seed['mvm11']['dof']['b2']} DOF), vs full FE",
                seed["mvm11_vs_full"],
            )
            + "\n"
        )
    cols = {
        "full FE": seed["full"],
        f"MVM {seed['mvm_model']}": seed["mvm"],
        **({"MVM 1-1 + 37": seed["mvm11"]} if "mvm11" in seed else {}),
    }
    return _template("seed").substitute(
        head=_HEAD,
        row_full=_row(f"full FE vs wave-Hertz theory ({window})", seed["full_vs_theory"]),
        row_mvm=_row(
            f"MVM (b2 {seed['mvm_model']}, {seed['mvm_dof']['b2']} DOF incl. 6 of "
            "the frame) vs full FE",
            seed["mvm_vs_full"],
        ),
        row_mvm_theory=_row("MVM vs theory", seed["mvm_vs_theory"]),
        row_mvm11=row11,
        ncc_force=f"{acc.threshold('seed', ('full_vs_theory', 'ncc_force'), theory):g}",
        ncc_free_end=f"{acc.threshold('seed', ('full_vs_theory', 'ncc_b2_free_end'), theory):g}",
        peak=_pct(acc.threshold("seed", ("full_vs_theory", "peak_err"), theory)),
        duration=_pct(acc.threshold("seed", ("full_vs_theory", "duration_err"), theory)),
        met_theory=_met(acc.met(seed, "seed", theory)),
        mvm_ncc=f"{acc.threshold('seed', ('mvm_vs_full', 'ncc_force'), mvm):g}",
        mvm_dof=f"{acc.threshold('seed', ('mvm_dof', 'b2'), mvm) - 6:g}",
        met_mvm=_met(acc.met(seed, "seed", mvm)),
        energy_sentence=_energy_sentence(seed),
        mvm11_sentence=_mvm11_sentence(seed),
        conservation=_cons_table(cols),
    )


def _flat(flat: dict) -> str:
    stated = "flat variant"
    return _template("flat").substitute(
        plateau_mean=f"{flat['plateau_mean_N']:.2f}",
        F0=f"{flat['F0_N']:.2f}",
        plateau_err=_p(flat["plateau_err"], 3),
        peak=f"{flat['max_contact_force_interval_mean_N']:.2f}",
        peak_err=_p(flat["max_contact_force_interval_mean_N"] / flat["F0_N"] - 1.0, 1),
        jump=f"{1e6 * flat['free_end_jump_s']:.1f}",
        L_over_c=f"{1e6 * flat['L_over_c_s']:.1f}",
        jump_err=_p(flat["jump_err"]),
        momentum=_e(flat["momentum_rel_error_converged"]),
        momentum_balanced=_e(flat["momentum_rel_error"]),
        energy=_e(flat["energy_rel_change"]),
        penetration=f"{flat['max_penetration_m']:.1e}",
        plateau_bound=_pct(acc.threshold("flat_vs_st_venant", ("plateau_err",), stated)),
        jump_bound=_pct(acc.threshold("flat_vs_st_venant", ("jump_err",), stated)),
        met=_met(acc.met(flat, "flat_vs_st_venant", stated)),
    )


def _step(step: dict) -> str:
    c, stated = step["h_half_vs_h"], "time step"
    return _template("step").substitute(
        h=_us(step["h"]),
        h_half=_us(step["h"] / 2),
        t_end_ms=f"{1e3 * step['t_end']:g}",
        ncc_force=_n(c["ncc_force"]),
        peak=_p(c["peak_err"], 4),
        impulse=_p(c["impulse_err"], 4),
        duration=_p(c.get("duration_err"), 4),
        ncc_impact_end=_n(c.get("ncc_b2_impact_end"), 3),
        ncc_bound=f"{acc.threshold('step_convergence', ('h_half_vs_h', 'ncc_force'), stated):g}",
        peak_bound=_pct(acc.threshold("step_convergence", ("h_half_vs_h", "peak_err"), stated)),
        met=_met(acc.met(step, "step_convergence", stated)),
    )


def _fine_mesh_keys(short: dict) -> list[str]:
    """The refined mesh's settings in SHORT_FINE_MESH's order (validation.json keeps its keys
    sorted: a report from it reads as one from the run)."""
    return [
        *(k for k in SHORT_FINE_MESH if k in short["fine_mesh"]),
        *(k for k in short["fine_mesh"] if k not in SHORT_FINE_MESH),
    ]


def _short(short: dict) -> str:
    rows = [
        _row("full FE vs theory", short["full_vs_theory"]),
        _row("full FE, fine mesh, vs theory", short["fine_vs_theory"]),
        _row("full FE vs fine mesh", short["full_vs_fine"]),
        _row(f"full FE at h vs h/2 (h = {_us(short['dt'])})", short["full_vs_dt_half"]),
        _row(f"MVM (b2 {short['mvm_model']}) vs full FE", short["mvm_vs_full"]),
        _row("MVM vs theory", short["mvm_vs_theory"]),
    ]
    cols = {
        "full FE": short["full"],
        "fine mesh": short["fine"],
        "h/2": short["dt_half"],
        f"MVM {short['mvm_model']}": short["mvm"],
    }
    return _template("short").substitute(
        theory_peak=f"{short['theory_peak_N']:.1f}",
        theory_end=f"{1e6 * short['theory_end_s']:.1f}",
        fine_mesh=", ".join(f"{k} = {short['fine_mesh'][k]:g}" for k in _fine_mesh_keys(short)),
        fine_dof_b1=f"{short['fine']['dof']['b1']:,}",
        fine_dof_b2=f"{short['fine']['dof']['b2']:,}",
        head=_HEAD,
        rows="\n".join(rows),
        conservation=_cons_table(cols),
    )


def _pendulum(pend: dict) -> str:
    vs, mo, stated = pend["vs_seed"], pend["momenta"], "pendulum"
    steps = ", ".join(
        f"{int(n):,} at {_us(float(h))}"
        for h, n in sorted(pend["step_size_counts"].items(), key=lambda kv: float(kv[0]))
    )
    return _template("pendulum").substitute(
        model_b1=pend["models"]["b1"],
        model_b2=pend["models"]["b2"],
        release_mm=f"{1e3 * pend['release_height_m']:.4f}",
        past_ms=f"{1e3 * (mo['t_end_s'] - mo['t_separation_s']):.1f}",
        steps=steps,
        v=f"{pend['impact_speed_mps']:.6f}",
        v_theory=f"{pend['impact_speed_theory_mps']:.6f}",
        v_err=_p(pend["impact_speed_err"], 4),
        p1=f"{mo['b1']['p_end'][0]:.6f}",
        p1_rigid=f"{mo['b1']['p_end_rigid_pendulum_x']:.6f}",
        p1_err=_p(mo["b1"]["p_end_rel_err_x"], 4),
        p2=f"{mo['b2']['p_end'][0]:.6f}",
        p2_rigid=f"{mo['b2']['p_end_rigid_pendulum_x']:.6f}",
        p2_err=_p(mo["b2"]["p_end_rel_err_x"], 4),
        drift=f"{pend['max_joint_drift_m']:.1e}",
        energy_sep=_e(pend["energy_rel_at_separation"]),
        energy_end=_e(pend["energy_rel_change"]),
        ncc_force=_n(vs["ncc_force"], 5),
        peak=_p(vs["peak_err"]),
        impulse=_p(vs["impulse_err"]),
        duration=_p(vs["duration_err"]),
        ncc_free_end=_n(vs["ncc_b2_free_end"], 5),
        ncc_impact_end=_n(vs["ncc_b2_impact_end"], 3),
        v_bound=_pct(acc.threshold("pendulum", ("impact_speed_err",), stated)),
        ncc_bound=f"{acc.threshold('pendulum', ('vs_seed', 'ncc_force'), stated):g}",
        p_bound=_pct(acc.threshold("pendulum", ("momenta", "b1", "p_end_rel_err_x"), stated)),
        met=_met(acc.met(pend, "pendulum", stated)),
    )


def _hertz_block(hb: dict) -> str:
    rows = []
    for label in ("coarse", "fine"):
        c = hb[label]
        size = (
            "committed (0.3 mm)"
            if c["element_m"] == "committed"
            else f"{1e3 * c['element_m']:g} mm, meshed at run time"
        )
        rows.append(
            f"| {size} | {c['dof']:,} | {c['peak_N']:.1f} N | {_p(c['peak_err'])} | "
            f"{1e6 * c['duration_s']:.1f} us | {_p(c['duration_err'])} | "
            f"{_e(c['energy_rel_change'])} | {c['steps_on_roundoff_floor']} |"
        )
    c = hb["coarse"]
    return _template("hertz_block").substitute(
        hertz_peak=f"{c['hertz_peak_N']:.1f}",
        hertz_duration=f"{1e6 * c['hertz_duration_s']:.1f}",
        contact_radius=f"{1e3 * c['hertz_contact_radius_m']:.2f}",
        rows="\n".join(rows),
        bound=_pct(acc.threshold("hertz_block", ("fine", "peak_err"), "sphere on block")),
        met=_met(acc.met(hb, "hertz_block", "sphere on block")),
    )


def _arm_stop(arm: dict) -> str:
    f, m = arm["full"], arm["mvm"]
    lf, lm = arm["ledger"]["full"], arm["ledger"]["mvm"]
    rows = [
        ("DOF (arm)", f"{arm['dof']['full']:,}", f"{arm['dof']['mvm']:,}"),
        (
            "steps, not converged, cut",
            *(f"{r['n_steps']}, {r['steps_on_roundoff_floor']}, {r['step_cuts']}" for r in (f, m)),
        ),
        (
            "contacts [us]",
            *(
                ", ".join(f"{1e6 * a:.1f}-{1e6 * b:.1f}" for a, b in r["contact_intervals_s"])
                for r in (f, m)
            ),
        ),
        ("peak force", *(f"{r['max_contact_force_interval_mean_N']:.1f} N" for r in (f, m))),
        ("motor work", *(f"{1e3 * r['work_motor_J']:.3f} mJ" for r in (lf, lm))),
        (
            "numerical dissipation",
            *(f"{1e3 * r['dissipation_numerical_J']:.3f} mJ" for r in (lf, lm)),
        ),
        ("energy balance / input work", *(_e(r["balance_residual_rel_max"]) for r in (lf, lm))),
        ("wall time", *(f"{r['wall_time_s']:.0f} s" for r in (f, m))),
    ]
    c = arm["mvm_vs_full"]
    stated = "arm into a stop"
    return _template("arm_stop").substitute(
        drive_end=f"{1e3 * arm['drive_end_s']:g}",
        dof_full=f"{arm['dof']['full']:,}",
        dof_mvm=f"{arm['dof']['mvm']:,}",
        mvm_model=arm["mvm_model"],
        rows="\n".join(f"| {a} | {b} | {d} |" for a, b, d in rows),
        ncc_force=_n(c["ncc_force"]),
        peak_err=_p(c["peak_err"]),
        impulse_err=_p(c["impulse_err"]),
        ncc_tip=_n(c["ncc_tip_after_drive"]),
        cost=f"{arm['cost_ratio_full_over_mvm']:.1f}",
        ncc_bound=f"{acc.threshold('arm_stop', ('mvm_vs_full', 'ncc_force'), stated):g}",
        tip_bound=f"{acc.threshold('arm_stop', ('mvm_vs_full', 'ncc_tip_after_drive'), stated):g}",
        ledger_bound=_pct(
            acc.threshold("arm_stop", ("ledger", "full", "balance_residual_rel_max"), stated)
        ),
        met=_met(acc.met(arm, "arm_stop", stated)),
        full_loose=f["steps_on_roundoff_floor"],
        mvm_loose=m["steps_on_roundoff_floor"],
    )


#: The page's sections in order: (case key in the report, its renderer); a case the report
#: does not hold is left out.
SECTIONS = (
    ("seed", _seed),
    ("flat_vs_st_venant", _flat),
    ("step_convergence", _step),
    ("short", _short),
    ("pendulum", _pendulum),
    ("hertz_block", _hertz_block),
    ("arm_stop", _arm_stop),
)


def render(report: dict) -> str:
    """docs/validation.md's text from the report dict (validation.json)."""
    sections = [_header(report)]
    sections += [section(report[key]) for key, section in SECTIONS if report.get(key) is not None]
    sections.append(_template("closing").substitute())
    cases = "".join(
        f"| {name} | {m['computed_utc']} |\n" for name, m in sorted(report["cases"].items())
    )
    return "\n\n".join(sections) + "\n" + cases


def _generated_opening() -> str:
    """The text every report page opens with (the header template up to its first field)."""
    text = _template("header").template
    return text[: text.index("$")]


def claim_report_md(path: Path, what: str | None = None) -> None:
    """InputError unless ``path`` may receive the report page: it does not exist, is empty, or
    is a page this tool wrote (it opens with the generated header), the way ``run``
    claims its folder. ``what`` names the path in the message (default ``--md <path>``)."""
    path = Path(path)
    what = what or f"--md {path}"
    if not path.exists():
        return
    if not path.is_file():
        raise InputError(f"{what}: exists and is not a file; expected a report page file")
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            head = f.read(4096)
    except OSError as exc:
        raise InputError(f"{what}: cannot be read ({exc.strerror or exc})") from None
    if head and not head.startswith(_generated_opening()):
        raise InputError(
            f"{what}: holds a file the validation did not write (it does not open with the "
            "generated header); expected a new or empty file, or an earlier report page "
            "(which is replaced): move it or give --md another path"
        )


def write_report_md(path: Path, report: dict, what: str | None = None) -> None:
    """docs/validation.md (or ``path``) from the report dict (validation.json), after
    claim_report_md (a user's file that appeared during the run is not overwritten)."""
    claim_report_md(path, what)
    write_text_atomic(path, render(report))


__all__ = ["SECTIONS", "claim_report_md", "render", "write_report_md"]
