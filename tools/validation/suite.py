"""Run the validation cases and write their numbers (validation.json) and, for the whole set,
the report page (report.py).
"""

from __future__ import annotations

import os
import platform
from collections.abc import Callable, Sequence
from pathlib import Path

from flexmvm.errors import InputError
from flexmvm.results.atomic import write_json_atomic
from flexmvm.runs.provenance import run_code_version
from flexmvm.scenarios import load_scenario
from tools.validation import acceptance
from tools.validation.cases import CASES, stored_cases
from tools.validation.paths import git_commit, scenario_path, tool_version
from tools.validation.report import write_report_md
from tools.validation.runs import now


def machine() -> str:
    """The CPU the runs were made on: its model name (Linux /proc/cpuinfo, else the platform's
    processor string), architecture and core count, e.g. "AMD EPYC, x86_64, 2 cores"."""
    model = ""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            model = next(
                (line.split(":", 1)[1].strip() for line in f if line.startswith("model name")), ""
            )
    except OSError:
        pass
    model = model or platform.processor()
    return ", ".join(p for p in (model, platform.machine(), f"{os.cpu_count()} cores") if p)


def run_validation(
    out: Path,
    md: Path | None,
    recompute: bool = False,
    keys: Sequence[str] | None = None,
    echo: Callable[[str], None] = print,
) -> dict:
    """Run the cases ``keys`` (default: every case of CASES, in order) with their stored runs
    under ``out``; write out/validation.json and, when every case ran and ``md`` is given, the
    report page ``md``. Returns the report dict. Raises InputError for an unknown case."""
    known = [c.key for c in CASES]
    keys = known if keys is None else list(keys)
    unknown = [k for k in keys if k not in known]
    if unknown:
        raise InputError(
            f"unknown validation case {unknown[0]!r}; expected one of {', '.join(known)}"
        )
    commit = git_commit()
    out.mkdir(parents=True, exist_ok=True)
    report: dict = {c.key: c.run(out, recompute) for c in CASES if c.key in keys}
    report["theta"] = load_scenario(scenario_path("rod_impact.toml")).time.theta
    report["cases"] = stored_cases(report)
    report["meta"] = {
        "commit": commit,
        "code_version": run_code_version(),
        "tool_version": tool_version(),
        "date": now(),
        "machine": machine(),
    }
    write_json_atomic(out / "validation.json", report)
    for key in keys:
        rows = acceptance.criteria(key)
        bad = acceptance.failures(report[key], key)
        echo(
            f"{key}: {len(rows) - len(bad)} of {len(rows)} acceptance rows met"
            + "".join(f"\n  NOT met: {b}" for b in bad)
        )
    if keys == known and md is not None:
        write_report_md(md, report)
        echo(f"wrote {md} and {out}/validation.json (commit {commit})")
    else:
        echo(f"wrote {out}/validation.json (commit {commit}); the report page needs every case")
    return report


__all__ = ["machine", "run_validation"]
