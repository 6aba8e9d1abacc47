"""Material study (seed section 3.3, table 2): accuracy of the MVM against the target's material.

The target body (b2 in the seed) is made in turn of tungsten, copper, aluminium and PA6
(table 2: E 344.70, 96.50, 72.71, 2.32 GPa; nu 0.28, 0.36, 0.33, 0.34; rho 19250, 8390, 2700,
1140 kg/m^3, flexmvm.materials); the striker keeps the scenario's model and material (brass,
full FE) and speed (0.21 m/s). For each material a full-FE reference (the target full FE) and
reduced runs at the given selections x modes are made, every run a case of
flexmvm.studies.runner (parallel on Dask, resumable). The reduced model is of any kind that
retains the selection's nodes (studies.grid.study_kind): ``mvm`` (Craig-Bampton, the default),
``mvm-seed`` or ``mvm-seed-fixed`` (the seed's eq. (4) readings). As in the selection study
(studies.grid.selection_cases) a case carries ``kind`` in its params only when it is not
``mvm``, so the keys and params of the Craig-Bampton studies stored before stay valid; a study
directory holds one kind (a rerun with another kind is refused: its stored params differ).

- ``DIR/<material>/reference/history.csv``: the reference of each material (case ``ref-<mat>``;
  one that fails its check, studies.reference_run.reference_problem, is announced and recomputed);
- ``DIR/cases/<mat>-l<i>-j<j>-m<m>.json``: the MVM runs (studies.selection.run_selection_case),
  keyed by the material scenario's provenance stamp and its reference's SHA-256 (a case of
  another code version or reference is recomputed, said in one line);
- ``DIR/materials.csv``: ``material,kind,E_pa,nu,rho_kg_m3,selection,nodes,modes,dof,ncc_force,
  ncc_<probe>...,peak_err,impulse_err,duration_err,guard_outside_fraction,energy_gain_rel_max,
  wall_time_s``
  (guard_outside_fraction: the share of the contact impulse on surface nodes the reduced basis
  holds stiff, runs/guard.py; energy_gain_rel_max: the largest rise of the total energy);
- ``DIR/materials.json``: the model ``kind``, per-material mean NCC of the force over the runs
  (the same selections x modes for every material; ``n_cases`` = the runs the mean covers,
  ``failed`` the runs without an NCC), ``failures`` (``{"case", "reason"}``: failed
  references, whose material then has no MVM run, and failed runs; also printed),
  ``seed_ordering_holds`` = the mean NCCs decrease in the seed's order W > Cu > Al > PA6
  (restricted to the materials run), and the observed order; the same over the runs the
  validity checks accept for every material (``valid_models``; ``mean_ncc_force_valid``,
  ``n_valid``, ``seed_ordering_holds_valid``) and the runs they do not (``guard_outside_validity``
  with the reason, runs.guard.invalid_reason: a contact patch wider than the retained
  nodes, as PA6's on selections up to 1-3, or an energy rise; docs/studies.md "Material
  study"); ``provenance``: per material, its study scenario's and its reference's stamps
  (reference_run.study_provenance), so that a copy of the file is stamped on its own;
- ``DIR/fig9_materials.png``: NCC against modes per material and selection.

A material is set by rebuilding the scenario dict with an inline material table
{E_pa, nu, rho_kg_m3, name} validated by scenario_from_dict.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

from flexmvm.errors import InputError, SolverError, announce_recompute
from flexmvm.materials import ALUMINIUM, COPPER, PA6, TUNGSTEN, Material
from flexmvm.results.atomic import file_sha256, write_json_atomic, write_table_csv
from flexmvm.results.outdir import claim_study_dir
from flexmvm.runs.guard import WARN_FRACTION
from flexmvm.runs.provenance import stamp
from flexmvm.scenarios import ModelKind, Scenario, load_scenario, scenario_from_dict
from flexmvm.studies.grid import (
    SEED_SCHEME_NOTE,
    check_grid,
    redistributing_contacts,
    rod_of,
    seed_scheme,
    study_kind,
    study_scenario,
)
from flexmvm.studies.material_report import (
    material_case_key,
    material_columns,
    material_rows,
    material_summary,
)
from flexmvm.studies.options import StudyOptions, with_settings
from flexmvm.studies.reference_run import reference_history, reference_problem, study_provenance
from flexmvm.studies.report import echo_failures
from flexmvm.studies.runner import (
    Case,
    case_path,
    check_cluster_options,
    run_cases,
    study_cluster,
)
from flexmvm.studies.selection import run_selection_case

__all__ = [
    "SEED_MATERIALS",
    "SEED_ORDER",
    "MaterialStudy",
    "material_scenario",
    "material_study",
    "parse_selections",
    "run_material_case",
    "run_materials_study",
    "run_reference_case",
]

#: Seed table 2, in the seed's order of decreasing accuracy.
SEED_MATERIALS: dict[str, Material] = {"W": TUNGSTEN, "Cu": COPPER, "Al": ALUMINIUM, "PA6": PA6}
SEED_ORDER = ("W", "Cu", "Al", "PA6")


def material_scenario(sc: Scenario, body: str, name: str, material: Material) -> Scenario:
    """``sc`` with body ``body`` made of ``material`` (inline table named ``name``)."""
    return sc.with_material(
        body, Material(E=material.E, nu=material.nu, rho=material.rho, name=name)
    )


def parse_selections(text: str | Sequence[tuple[int, int]]) -> list[tuple[int, int]]:
    """'1-1,2-2' -> [(1, 1), (2, 2)]; InputError on anything else."""
    if not isinstance(text, str):
        return [(int(i), int(j)) for i, j in text]
    out = []
    for part in text.split(","):
        bits = part.strip().split("-")
        if len(bits) != 2 or not all(b.isdigit() and int(b) >= 1 for b in bits):
            raise InputError(f"selections: expected 'i-j' items like '1-1,2-2', got {text!r}")
        out.append((int(bits[0]), int(bits[1])))
    return out


def run_reference_case(case: Case, out_dir: str) -> dict:
    """Case function: the full-FE reference of one material, written to
    ``out_dir/<material>/reference/history.csv``; returns its SHA-256."""
    p = case.params
    sc = scenario_from_dict(p["scenario"], source=f"case {case.key}")
    path, made = reference_history(sc, p["body"], Path(out_dir) / p["material"])
    return {"sha256": file_sha256(path), "computed": made}


def run_material_case(case: Case, references: dict[str, str]) -> dict:
    """Case function: an MVM run of one material against that material's reference."""
    return run_selection_case(case, reference=references[case.params["material"]])


@dataclass(frozen=True)
class MaterialStudy:
    """The outcome of a material study: ``rows`` (materials.csv's rows), ``summary``
    (materials.json's content), ``columns`` (materials.csv's columns)."""

    rows: list[dict]
    summary: dict
    columns: list[str]


def _drop_failing_reference(sc: Scenario, body: str, mat_dir: Path, record: Path) -> None:
    """A stored reference of one material that fails its check (studies.reference_run
    reference_problem: another code version, cut short, edited) is announced and removed with
    its case record, so that its case computes it again."""
    problem = reference_problem(sc, body, mat_dir)
    if problem is None:
        return
    announce_recompute(f"{mat_dir.name}/{problem}: recomputed")
    for name in ("reference.json", "history.csv"):
        (mat_dir / "reference" / name).unlink(missing_ok=True)
    record.unlink(missing_ok=True)


def material_study(
    sc: Scenario,
    out_dir: str | Path,
    body: str = "b2",
    materials: Iterable[str] = SEED_ORDER,
    selections: Sequence[tuple[int, int]] | str = ((1, 1), (2, 2)),
    modes: Iterable[int] = range(7, 44, 12),
    kind: ModelKind | str = ModelKind.MVM,
    options: StudyOptions | None = None,
    **settings: Any,
) -> MaterialStudy:
    """The material study of ``body`` in scenario ``sc`` (module doc), its cases and references
    stored in ``out_dir`` (a rerun resumes); no table, figure or console output (see
    :func:`run_materials_study`). ``kind``: the reduced model (module doc); ``options``
    (studies.options.StudyOptions: scheduler, n_workers, serial, progress) where the cases
    run, its fields also accepted as keyword arguments (``settings``).

    Raises InputError for an unknown material name (keys of SEED_MATERIALS), a kind that
    retains no nodes, a bad body or a selection beyond the mesh. A reference or a case that
    fails is listed in ``failures``, not raised.
    """
    opts = with_settings(options, StudyOptions(), settings, "material_study")
    scheduler, n_workers, serial = opts.scheduler, opts.n_workers, opts.serial
    out = Path(out_dir).resolve()
    materials = _check_materials(materials)
    selections = parse_selections(selections)
    kind = study_kind(kind)
    rod = rod_of(sc, body)
    sc = seed_scheme(sc, body)
    _, _, _, modes = check_grid(
        sc, body, [s[0] for s in selections], [s[1] for s in selections], modes
    )
    check_cluster_options(scheduler, n_workers, serial)
    claim_study_dir(
        out,
        "flexmvm study materials",
        own={"cases", "materials.csv", "materials.json", "fig9_materials.png", *materials},
    )
    scen = {m: material_scenario(sc, body, m, SEED_MATERIALS[m]) for m in materials}
    cases, results, case_failed, ref_failed = _run_material_cases(
        scen, body, out, selections, modes, kind, (scheduler, n_workers, serial), opts.progress
    )
    rows = material_rows(cases, results, case_failed, rod, kind, SEED_MATERIALS)
    result = material_summary(
        rows,
        ref_failed,
        scen,
        SEED_MATERIALS,
        SEED_ORDER,
        body=body,
        kind=kind,
        selections=selections,
        modes=list(modes),
        rod=rod,
    )
    result["provenance"] = {m: study_provenance(scen[m], body, out / m) for m in scen}
    return MaterialStudy(rows, result, material_columns([p.name for p in sc.probes]))


def _run_material_cases(scen, body, out, selections, modes, kind, cluster, progress):
    """The references, then the grid, of every material's scenario ``scen`` on one cluster
    (``cluster`` = (scheduler, n_workers, serial), as studies.runner.study_cluster), stored in
    ``out``. Returns (the grid's cases, their results, the failed cases' and failed
    references' reasons by key)."""
    scheduler, n_workers, serial = cluster
    ref_cases = _reference_cases(scen, body, out)
    ref_paths = {m: str(out / m / "reference" / "history.csv") for m in scen}
    stamps = {m: stamp(sc) for m, sc in scen.items()}
    with study_cluster(scheduler, n_workers, serial) as address:
        kw: dict[str, Any] = {"serial": True} if serial else {"scheduler": address}
        ref_failed: dict[str, str] = {}
        refs = run_cases(
            ref_cases,
            partial(run_reference_case, out_dir=str(out)),
            out,
            progress=progress,
            failures=ref_failed,
            version=lambda c: {"provenance": stamps[c.params["material"]]},
            **kw,
        )
        cases = _material_cases(scen, body, selections, modes, refs, kind)
        case_failed: dict[str, str] = {}
        results = run_cases(
            cases,
            partial(run_material_case, references=ref_paths),
            out,
            progress=progress,
            failures=case_failed,
            version=lambda c: {
                "provenance": stamps[c.params["material"]],
                "reference_sha256": c.params["reference_sha256"],
            },
            **kw,
        )
    return cases, results, case_failed, ref_failed


def _check_materials(materials: Iterable[str]) -> list[str]:
    """The material names, checked: InputError unless some, all keys of SEED_MATERIALS."""
    materials = list(materials)
    unknown = [m for m in materials if m not in SEED_MATERIALS]
    if unknown or not materials:
        raise InputError(
            f"materials: unknown {unknown or 'none given'}; expected some of "
            f"{', '.join(SEED_MATERIALS)}"
        )
    return materials


def _reference_cases(scen: dict[str, Scenario], body: str, out: Path) -> list[Case]:
    """The reference step: case ``ref-<material>`` of every material's scenario ``scen``; a
    stored reference that fails its check is removed first (_drop_failing_reference)."""
    ref_cases = [
        Case(f"ref-{m}", {"body": body, "material": m, "scenario": sc.model_dump(mode="json")})
        for m, sc in scen.items()
    ]
    for (m, sc), case in zip(scen.items(), ref_cases, strict=True):
        _drop_failing_reference(sc, body, out / m, case_path(out, case.key))
    return ref_cases


def _material_cases(
    scen: dict[str, Scenario],
    body: str,
    selections: Sequence[tuple[int, int]],
    modes: Sequence[int],
    refs: dict[str, dict],
    kind: ModelKind,
) -> list[Case]:
    """The grid step: selections x modes of every material whose reference ``refs`` holds
    (by case key ``ref-<material>``; its SHA-256 is in the case's params); ``kind`` in the
    params only when not mvm, as studies.grid.selection_cases."""
    kind_param = {} if kind is ModelKind.MVM else {"kind": kind.value}
    return [
        Case(
            f"{m}-l{i}-j{j}-m{n}",
            {
                "body": body,
                "layers": i,
                "laps": j,
                "modes": n,
                "material": m,
                "modes_max": max(modes),
                "scenario": sc.model_dump(mode="json"),
                "reference_sha256": refs[f"ref-{m}"]["sha256"],
            }
            | kind_param,
        )
        for m, sc in scen.items()
        if f"ref-{m}" in refs
        for (i, j) in selections
        for n in modes
    ]


def _echo_summary(
    echo: Callable[[str], Any], result: dict, kind: ModelKind, n_per: int, where: Path
) -> None:
    """The study's console lines: its failures (see ``where``), the mean force NCC of every
    material with the seed ordering's verdict, and the runs outside their model's validity
    with the means over the models valid for every material."""
    materials, per, failures = list(result["materials"]), result["materials"], result["failures"]
    holds = result["seed_ordering_holds"]
    echo_failures(echo, failures, len(materials) * (1 + n_per), where)
    echo(
        f"mean NCC of the force ({kind.value}): "
        + ", ".join(
            f"{m} {per[m]['mean_ncc_force']:.6f} (over {per[m]['n_cases']} of {n_per} runs)"
            if per[m]["mean_ncc_force"] is not None
            else f"{m} (no run compared)"
            for m in materials
        )
        + f"; seed ordering W > Cu > Al > PA6 {'holds' if holds else 'does not hold'}"
    )
    if result["guard_outside_validity"]:
        bad = result["guard_outside_validity"]
        echo(
            f"validity: {len(bad)} run(s) outside their model's validity (more than "
            f"{100 * WARN_FRACTION:g} % of the contact impulse on nodes the basis holds stiff, "
            "or the energy rose: chatter), "
            "e.g. "
            + ", ".join(f"{b['case']} ({b['reason']})" for b in bad[:3])
            + f"; over the {len(result['valid_models'])} models valid for every material: "
            + ", ".join(
                f"{m} {per[m]['mean_ncc_force_valid']:.6f} ({per[m]['n_valid']} runs)"
                if per[m]["mean_ncc_force_valid"] is not None
                else f"{m} (none)"
                for m in materials
            )
            + f"; seed ordering {'holds' if result['seed_ordering_holds_valid'] else 'does not hold'}"
        )


#: run_materials_study's options when none are given: progress bars, console lines printed.
_COMMAND = StudyOptions(progress=True, echo=print)


def run_materials_study(
    scenario: str | Path | Scenario,
    out_dir: str | Path,
    body: str = "b2",
    materials: Iterable[str] = SEED_ORDER,
    selections: Sequence[tuple[int, int]] | str = ((1, 1), (2, 2)),
    modes: Iterable[int] = range(7, 44, 12),
    kind: ModelKind | str = ModelKind.MVM,
    options: StudyOptions | None = None,
    **settings: Any,
) -> dict:
    """The material study of ``body`` in ``scenario`` (a Scenario or a scenario file) with its
    files and console lines (module doc): :func:`material_study`, then materials.csv,
    materials.json, the figure and the summary line. ``t_end_s``, ``dt_s`` and ``other`` as in
    studies.grid.study_scenario; ``kind`` the reduced model (module doc). Returns the
    materials.json content.

    Raises as :func:`material_study`, and SolverError, after everything is written, if no run
    at all could be compared.
    """
    opts = with_settings(options, _COMMAND, settings, "run_materials_study")
    echo = print if opts.echo is None else opts.echo
    out = Path(out_dir).resolve()
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    kind = study_kind(kind)
    if redistributing_contacts(sc, body):
        echo(SEED_SCHEME_NOTE)
    sc = study_scenario(sc, body, t_end_s=opts.t_end_s, dt_s=opts.dt_s, other=opts.other)
    study = material_study(sc, out, body, materials, selections, modes, kind, opts)
    rows, result = study.rows, study.summary
    materials, per, failures = list(result["materials"]), result["materials"], result["failures"]
    n_per = len(result["selections"]) * len(result["modes"])
    write_table_csv(out / "materials.csv", study.columns, rows)
    write_json_atomic(out / "materials.json", result)
    from flexmvm.plots.study_figures import plot_materials

    invalid = {b["case"] for b in result["guard_outside_validity"]}
    plot_materials(
        out / "fig9_materials.png",
        [r | {"valid": material_case_key(r) not in invalid} for r in rows],
        title=f"{sc.name}: body {body} of each material, {kind.value} models",
    )
    _echo_summary(echo, result, kind, n_per, out / "materials.json")
    if not any(per[m]["n_cases"] for m in materials):
        raise SolverError(
            f"material study: no run could be compared ({len(failures)} "
            f"failures, first: {failures[0]['case']}: {failures[0]['reason']}); "
            f"see {out / 'materials.json'}"
        )
    return result
