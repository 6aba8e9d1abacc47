"""What a selection study reports: the rows of ncc.csv, the failed cases, the winner and the
target as text (studies/selection.py module doc: the files)."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

from flexmvm.metrics.ncc import Target
from flexmvm.results.atomic import write_table_csv
from flexmvm.runs.guard import VALIDITY_KEYS
from flexmvm.studies.runner import Case
from flexmvm.studies.search import Candidate


def failed_case_row(case: Case, line: str, nodes: int) -> dict:
    """The ncc.csv row of a case that raised: its grid fields and ``failed``, no metrics."""
    p = case.params
    i, j, m = int(p["layers"]), int(p["laps"]), int(p["modes"])
    return {
        "layers": i,
        "laps": j,
        "nodes": nodes,
        "modes": m,
        "dof": 3 * nodes + m,
        "dof_total": 3 * nodes + m + 6,
        "failed": line,
    }


def failure_list(keyed_rows: Iterable[tuple[str, dict]]) -> list[dict]:
    """[{"case", "reason"}] of the rows that carry ``failed``, sorted by case key."""
    return sorted(
        ({"case": k, "reason": r["failed"]} for k, r in keyed_rows if "failed" in r),
        key=lambda f: f["case"],
    )


def echo_failures(
    echo: Callable[[str], Any],
    failures: Sequence[dict],
    n_runs: int,
    where: str | os.PathLike,
    shown: int = 5,
) -> None:
    """One console line per failed case (the first ``shown``), then where the rest are."""
    if not failures:
        return
    echo(f"{len(failures)} of {n_runs} runs failed (listed in {where}):")
    for f in failures[:shown]:
        echo(f"  {f['case']}: {f['reason']}")
    if len(failures) > shown:
        echo(f"  ... and {len(failures) - shown} more")


def ncc_columns(probes: Sequence[str]) -> list[str]:
    return (
        ["layers", "laps", "nodes", "modes", "dof", "ncc_force"]
        + [f"ncc_{p}" for p in probes]
        + ["peak_err", "impulse_err", "duration_err", *VALIDITY_KEYS, "wall_time_s"]
    )


def write_ncc_csv(path: Path, rows: Iterable[dict], probes: Sequence[str]) -> list[dict]:
    cols = ncc_columns(probes)
    rows = sorted(rows, key=lambda r: (r["layers"], r["laps"], r["modes"]))
    write_table_csv(path, cols, rows)
    return rows


def winner_dict(best: Candidate | None, rows: dict[tuple, dict]) -> dict:
    if best is None or best.selection is None:
        return {"passed": False}
    r = rows[(*best.selection, best.modes)]
    return {
        "passed": True,
        "layers": r["layers"],
        "laps": r["laps"],
        "nodes": r["nodes"],
        "modes": r["modes"],
        "dof": r["dof"],
        "dof_total": r["dof_total"],
        "ncc_force": r.get("ncc_force"),
    }


def target_dict(t: Target) -> dict:
    return {
        k: getattr(t, k) for k in ("ncc_min", "peak_err_max", "impulse_err_max", "duration_err_max")
    }


def target_text(t: Target) -> str:
    parts = [f"ncc>={t.ncc_min:.12g}"]  # 12 digits: 0.9999996 is not printed as 1
    for key, name in (
        ("peak_err_max", "peak"),
        ("impulse_err_max", "impulse"),
        ("duration_err_max", "duration"),
    ):
        if getattr(t, key) is not None:
            parts.append(f"{name}<={getattr(t, key):.12g}")
    return ",".join(parts)


def echo_summary(echo: Callable[[str], Any], result: dict, target: Target, where: Path) -> None:
    """The console lines of a selection study's selection.json content ``result``: failures,
    the node kind's answer and, with the interface kind, its answer and the best overall. A
    kind that ``--search`` did not follow past the other kind's smaller winner (``exact``
    false) is reported as such, not as that kind's smallest model."""
    t = target_text(target)
    ie = result.get("interface")
    top = result["best_overall"]["dof"] if ie and result["best_overall"] else None
    beyond = f"none up to {top} DOF, the search looked no further"
    echo_failures(echo, result["failures"], result["runs"], where)
    runs = f"{result['runs']} runs ({result['runs_made']} made, {result['runs_loaded']} loaded)"
    exact = result.get("exact", True)
    if result["passed"]:
        kept = result["region"] if "region" in result else f"{result['layers']}-{result['laps']}"
        model = (
            f"{kept} with {result['modes']} modes, "
            f"{result['dof']} DOF ({result['nodes']} nodes), NCC {result['ncc_force']:.6f}"
        )
        echo(
            f"smallest model reaching {t}: {model}; {runs}"
            if exact
            else f"node selections, best run reaching {t}: {model} ({beyond}); {runs}"
        )
    else:
        echo(
            f"no model of the grid reaches {t}; {runs}"
            if exact
            else f"no node selection reaches {t} up to {top} DOF (the search looked no further); "
            f"{runs}"
        )
    if ie is None:
        return
    echo_failures(echo, ie["failures"], ie["runs"], where)
    runs = f"{ie['runs']} of {ie['grid_size']} runs"
    if ie["passed"]:
        model = f"{ie['model']}, {ie['dof']} DOF, NCC {ie['ncc_force']:.6f}"
        echo(
            f"smallest interface model reaching {t}: {model}; {runs}"
            if ie["exact"]
            else f"interface, best run reaching {t}: {model} ({beyond}); {runs}"
        )
    else:
        echo(
            f"no interface model of the grid reaches {t}; {runs}"
            if ie["exact"]
            else f"no interface model reaches {t} up to {top} DOF (the search looked no further); "
            f"{runs}"
        )
    b = result["best_overall"]
    if b is not None:
        echo(
            f"smallest model over both kinds: {b['model']}, {b['dof']} DOF, "
            f"NCC {b['ncc_force']:.6f}; {result['runs'] + ie['runs']} of "
            f"{result['grid_size'] + ie['grid_size']} runs"
        )
