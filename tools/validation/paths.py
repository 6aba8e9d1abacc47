"""Where the validation reads its scenarios and writes its report, and the stamps of what made
a report.

The validation is a repository tool (``python -m tools.validation`` from the repository root):
it reads the repository's ``scenarios/*.toml``, writes docs/validation.md and docs/validation/
by default, and stamps a report with the checkout's commit (git) and the hashes of the package
source (flexmvm.runs.provenance.run_code_version) and of this tool's source
(:func:`tool_version`).
"""

from __future__ import annotations

import hashlib
import subprocess
from pathlib import Path

#: The repository root (this file is tools/validation/paths.py).
ROOT = Path(__file__).resolve().parents[2]
#: The scenario files of the validation cases: the repository's scenarios/.
SCENARIOS = ROOT / "scenarios"
#: This tool's folder: its modules and report templates (tool_version).
TOOL = Path(__file__).resolve().parent
#: What a report depends on: a change here (uncommitted) marks the commit stamp "-dirty".
RUN_INPUTS = ("src", "scenarios", "pyproject.toml", "tools/validation")


def scenario_path(name: str) -> Path:
    """The validation's scenario file ``name`` (e.g. "rod_impact.toml")."""
    return SCENARIOS / name


def default_outputs() -> tuple[Path, Path]:
    """(case folder, report page) of the repository: docs/validation and docs/validation.md."""
    return ROOT / "docs" / "validation", ROOT / "docs" / "validation.md"


def tool_version() -> str:
    """SHA-256 (16 hex) of this tool's source, its modules and its report templates (relative
    path and bytes of each, in order): what renders the report page from the runs, stamped
    beside the package's code version (whose edits the runs' keys cover)."""
    digest = hashlib.sha256()
    for f in sorted([*TOOL.glob("*.py"), *TOOL.glob("templates/*.md")]):
        digest.update(f.relative_to(TOOL).as_posix().encode() + b"\0")
        digest.update(f.read_bytes())
    return digest.hexdigest()[:16]


def git_commit(root: Path = ROOT) -> str:
    """Short commit of the checkout plus "-dirty" if tracked or untracked files under
    RUN_INPUTS (the package source, the scenarios, this tool) differ from it; "unknown" if
    git or the commit cannot be read (a copy without .git)."""
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
    "ROOT",
    "RUN_INPUTS",
    "SCENARIOS",
    "TOOL",
    "default_outputs",
    "git_commit",
    "scenario_path",
    "tool_version",
]
