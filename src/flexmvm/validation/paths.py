"""Where the validation reads its scenarios and writes its report.

The scenarios are the repository's ``scenarios/*.toml``, read through ``scenarios`` beside this
module: in a checkout a link to the repository's folder (one copy, the one users, tests and
the README use), in a wheel the files the validation needs (pyproject.toml, package data).
So the command runs from a wheel too. The report's defaults, docs/validation.md and
docs/validation/, belong to the repository: outside a checkout the command asks for --out.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

from flexmvm.errors import InputError

#: The scenario files of the validation cases (package data of the wheel: pyproject.toml).
SCENARIOS = Path(__file__).resolve().parent / "scenarios"
#: The repository root when the package runs from a checkout (src layout), else None.
_ROOT = Path(__file__).resolve().parents[3]
#: What the runs depend on: a change here (uncommitted) marks the commit stamp "-dirty".
RUN_INPUTS = ("src", "scenarios", "pyproject.toml")


def scenario_path(name: str) -> Path:
    """The validation's scenario file ``name`` (e.g. "rod_impact.toml")."""
    return SCENARIOS / name


def repository() -> Path | None:
    """The repository root of a checkout (it holds pyproject.toml, scenarios/ and docs/), or
    None when the package is installed from a wheel."""
    if all((_ROOT / p).exists() for p in ("pyproject.toml", "scenarios", "docs")):
        return _ROOT
    return None


def default_outputs() -> tuple[Path, Path]:
    """(case folder, report page) of a checkout: docs/validation and docs/validation.md.
    Raises InputError outside a checkout (installed from a wheel): give --out."""
    root = repository()
    if root is None:
        raise InputError(
            "the validation report's default place is a repository checkout's "
            "docs/; installed from a wheel, give --out DIR (and --md FILE)"
        )
    return root / "docs" / "validation", root / "docs" / "validation.md"


def git_commit(root: Path | None = None) -> str:
    """Short commit of the checkout plus "-dirty" if tracked or untracked files under
    RUN_INPUTS (the package source, the scenarios) differ from it; "unknown" outside a git
    checkout (a wheel)."""
    root = repository() if root is None else root
    if root is None:
        return "unknown"
    try:
        head = subprocess.run(
            ["git", "-C", str(root), "rev-parse", "--short=12", "HEAD"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        status = subprocess.run(
            ["git", "-C", str(root), "status", "--porcelain", "--", *RUN_INPUTS],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + ("-dirty" if status.strip() else "")


__all__ = [
    "RUN_INPUTS",
    "SCENARIOS",
    "default_outputs",
    "git_commit",
    "repository",
    "scenario_path",
]
