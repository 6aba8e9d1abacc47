"""integrate/ asks for what it uses through declared interfaces and is type-checked (issue 50
item 2): no getattr/hasattr anywhere in integrate/ (8 calls before: a load's
state_independent, the system's plastic parts, a body factor's Mw_used and nodal cache, the
plastic bodies' parts, the friction rows' fields), and none of its modules in mypy's
ignore_errors list of pyproject.toml (7 before). Both read the sources only (no import, no
mypy run: mypy itself runs in .ci/run), in well under a second."""

from __future__ import annotations

import ast
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
INTEGRATE = ROOT / "src" / "flexmvm" / "integrate"


def test_integrate_probes_for_no_capability():
    probes = []
    for path in sorted(INTEGRATE.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        probes += [
            f"{path.relative_to(INTEGRATE)}:{node.lineno}"
            for node in ast.walk(tree)
            if isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in ("getattr", "hasattr")
        ]
    assert probes == []


def test_no_integrate_module_escapes_the_type_checker():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    ignored = [
        module
        for override in config["tool"]["mypy"].get("overrides", [])
        if override.get("ignore_errors")
        for module in override["module"]
        if module.startswith("flexmvm.integrate")
    ]
    assert ignored == []
