"""The files of a selection study (studies.selection module doc): ncc.csv (or, for region
families, their table), selection.json, ncc_interface.csv and the figures."""

from __future__ import annotations

from pathlib import Path

from flexmvm.metrics.ncc import Target
from flexmvm.results.atomic import write_json_atomic
from flexmvm.results.output import writing
from flexmvm.studies.interface import write_interface_csv
from flexmvm.studies.region_families import front_points, write_region_csv
from flexmvm.studies.report import write_ncc_csv

__all__ = ["kind_name", "write_selection_files"]


def kind_name(summary: dict) -> str:
    """The node kind of a study's summary (selection.json's ``kind``; mvm when absent)."""
    return str(summary.get("kind", "mvm"))


def write_selection_files(
    out: Path, study, name: str, body: str, target: Target, by_region: bool
) -> None:
    """ncc.csv (the region table with ``by_region``), selection.json, the figures of fig. 7
    and 8 (node selections), ncc_interface.csv (interface rows) and the NCC-DOF front (regions
    or interface rows) of ``study`` (a studies.selection.SelectionStudy) in ``out``; ``name``
    (the scenario's) and ``body`` title the figures, ``target`` marks the front's."""
    from flexmvm.plots.study_figures import plot_ncc_dof_fronts, plot_ncc_map, plot_ncc_modes

    if by_region:
        with writing(out / "ncc.csv"):  # a full disk: OutputError naming the file
            write_region_csv(out / "ncc.csv", study.rows, study.probes)
        pts = front_points(study.rows)
    else:
        with writing(out / "ncc.csv"):
            write_ncc_csv(out / "ncc.csv", study.rows, study.probes)
        pts = {
            f"node selections ({kind_name(study.summary)})": [
                (r["dof"], r["ncc_force"]) for r in study.rows if "ncc_force" in r
            ]
        }
    with writing(out / "selection.json"):
        write_json_atomic(out / "selection.json", study.summary)
    if study.rows and not by_region:  # none when --search closed every node selection
        with writing(out / "fig7_ncc_map.png"):
            plot_ncc_map(
                out / "fig7_ncc_map.png", study.rows, title=f"{name}: NCC of the contact force"
            )
        with writing(out / "fig8_ncc_modes.png"):
            plot_ncc_modes(
                out / "fig8_ncc_modes.png", study.rows, title=f"{name}: NCC against modes"
            )
    if study.interface_rows:
        with writing(out / "ncc_interface.csv"):
            write_interface_csv(out / "ncc_interface.csv", study.interface_rows, study.probes)
        pts["interface"] = [
            (r["dof"], r["ncc_force"]) for r in study.interface_rows if "ncc_force" in r
        ]
    if (study.interface_rows or by_region) and any(pts.values()):
        with writing(out / "fig_front_ncc_dof.png"):
            plot_ncc_dof_fronts(
                out / "fig_front_ncc_dof.png",
                pts,
                target=target.ncc_min,
                title=f"{name}: force NCC against DOF of {body}",
            )
