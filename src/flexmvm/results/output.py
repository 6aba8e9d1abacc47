"""Everything a run writes: history CSV, summary JSON, HDF5, ParaView series, figure."""

from __future__ import annotations

from pathlib import Path

from flexmvm.results.writers import (
    write_history_csv,
    write_paraview_series,
    write_results_h5,
    write_summary_json,
)


def write_run(out_dir: Path, srun, fields: bool = True) -> dict[str, Path]:
    """Write one ScenarioRun into out_dir (created); returns the paths written."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    res = srun.result
    bodies = list(srun.built.system.bodies)
    materials = [info.material for info in srun.built.info]
    paths = {"history": out_dir / "history.csv", "summary": out_dir / "summary.json",
             "results": out_dir / "results.h5"}
    write_history_csv(paths["history"], res, probe_axis=0)
    write_summary_json(paths["summary"], srun.summary)
    if fields:
        write_results_h5(paths["results"], res, bodies)
        paths["paraview"] = write_paraview_series(out_dir / "paraview", res, bodies, materials)
    return paths
