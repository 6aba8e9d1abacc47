"""Reading scenarios: from a TOML file (docs/scenario_format.md) or from the dict it parses to.
Every problem is one :class:`~flexmvm.scenarios.problems.ScenarioError` line (source, key
path, problem)."""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from flexmvm.scenarios.problems import ScenarioError
from flexmvm.scenarios.schema import Scenario, validate_scenario


def scenario_from_dict(
    data: Mapping[str, Any], source: str = "scenario", base_dir: str | Path | None = None
) -> Scenario:
    """Validate a scenario given as the dict a TOML file parses to (docs/scenario_format.md).

    ``source`` names it in errors; ``mesh_file`` paths are resolved against ``base_dir``
    (default: the working directory). Raises ScenarioError (one line: source, key path, problem).
    """
    return validate_scenario(data, source, Path(base_dir) if base_dir is not None else None)


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario TOML file (docs/scenario_format.md).

    ``mesh_file`` paths are resolved relative to the file. Raises ScenarioError (one line:
    file, key path, problem) for a missing file, a TOML syntax error or any invalid value.
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise ScenarioError(f"{path}: cannot read scenario file ({exc.strerror})") from None
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"{path}: not UTF-8 text (byte {exc.start})") from None
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{path}: invalid TOML: {exc}") from None
    return validate_scenario(data, str(path), path.parent)
