"""What a selection study reports: the rows of ncc.csv, the failed cases, the winner and the
target as text (studies/selection.py module doc: the files)."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

from flexmvm.metrics.ncc import Target
from flexmvm.results.atomic import write_table_csv
from flexmvm.studies.runner import Case
from flexmvm.studies.search import Candidate


def failed_case_row(case: Case, line: str, nodes: int) -> dict:
    """The ncc.csv row of a case that raised: its grid fields and ``failed``, no metrics."""
    p = case.params
    i, j, m = int(p["layers"]), int(p["laps"]), int(p["modes"])
    return {"layers": i, "laps": j, "nodes": nodes, "modes": m, "dof": 3 * nodes + m,
            "dof_total": 3 * nodes + m + 6, "failed": line}


def failure_list(keyed_rows: Iterable[tuple[str, dict]]) -> list[dict]:
    """[{"case", "reason"}] of the rows that carry ``failed``, sorted by case key."""
    return sorted(({"case": k, "reason": r["failed"]} for k, r in keyed_rows if "failed" in r),
                  key=lambda f: f["case"])


def echo_failures(echo: Callable[[str], Any], failures: Sequence[dict], n_runs: int,
                  where: str, shown: int = 5) -> None:
    """One console line per failed case (the first ``shown``), then where the rest are."""
    if not failures:
        return
    echo(f"{len(failures)} of {n_runs} runs failed (listed in {where}):")
    for f in failures[:shown]:
        echo(f"  {f['case']}: {f['reason']}")
    if len(failures) > shown:
        echo(f"  ... and {len(failures) - shown} more")


def ncc_columns(probes: Sequence[str]) -> list[str]:
    return (["layers", "laps", "nodes", "modes", "dof", "ncc_force"]
            + [f"ncc_{p}" for p in probes] + ["peak_err", "impulse_err", "duration_err",
                                                "guard_outside_fraction", "wall_time_s"])


def write_ncc_csv(path: Path, rows: Iterable[dict], probes: Sequence[str]) -> list[dict]:
    cols = ncc_columns(probes)
    rows = sorted(rows, key=lambda r: (r["layers"], r["laps"], r["modes"]))
    write_table_csv(path, cols, rows)
    return rows


def winner_dict(best: Candidate | None, rows: dict[tuple, dict]) -> dict:
    if best is None:
        return {"passed": False}
    r = rows[(*best.selection, best.modes)]
    return {"passed": True, "layers": r["layers"], "laps": r["laps"], "nodes": r["nodes"],
            "modes": r["modes"], "dof": r["dof"], "dof_total": r["dof_total"],
            "ncc_force": r.get("ncc_force")}


def target_dict(t: Target) -> dict:
    return {k: getattr(t, k) for k in ("ncc_min", "peak_err_max", "impulse_err_max",
                                       "duration_err_max")}


def target_text(t: Target) -> str:
    parts = [f"ncc>={t.ncc_min:g}"]
    for key, name in (("peak_err_max", "peak"), ("impulse_err_max", "impulse"),
                      ("duration_err_max", "duration")):
        if getattr(t, key) is not None:
            parts.append(f"{name}<={getattr(t, key):g}")
    return ",".join(parts)
