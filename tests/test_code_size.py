"""Size limits of the package (issue 39): no module of src/flexmvm over MAX_MODULE_LINES lines
and no function (or method) over MAX_FUNCTION_LINES, except the numba kernels listed below with
the reason they must be long. Lines are counted as a reader scrolls them: a module's lines, a
function's from its ``def`` to its last line (end_lineno - lineno + 1, decorators excluded,
docstring included). The limits are exact integers: the test has no tolerance. It parses the
sources only, once (no import): 0.6 s of CPU."""

from __future__ import annotations

import ast
import functools
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "flexmvm"

MAX_MODULE_LINES = 500
MAX_FUNCTION_LINES = 80

#: Numba kernels allowed to be long, "module path::function" -> the reason (the one-line comment
#: above the kernel says the same).
LONG_KERNELS = {
    "bodies/momentum.py::momentum_terms_nodal": "one loop over the coordinates with its three "
    "component branches written out: scalar accumulators, not small arrays indexed by the "
    "component, which made a call about twice as slow",
}

#: Modules over the limit for now: being split by the lead (remove the entry once it is).
LONG_MODULES: dict[str, str] = {}


@functools.cache
def _sources() -> dict[str, tuple[int, list[tuple[ast.FunctionDef, int]]]]:
    """Module path -> (its lines, [(function node, its lines)]), parsed once for all tests."""
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        funcs = [
            (node, node.end_lineno - node.lineno + 1)
            for node in ast.walk(ast.parse(text))
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
        ]
        out[path.relative_to(PACKAGE).as_posix()] = (len(text.splitlines()), funcs)
    return out


def _is_numba_kernel(node: ast.FunctionDef) -> bool:
    return any("numba" in ast.unparse(d) or "njit" in ast.unparse(d) for d in node.decorator_list)


def test_no_module_over_the_limit():
    over = [
        f"{rel}: {n} lines"
        for rel, (n, _) in _sources().items()
        if n > MAX_MODULE_LINES and rel not in LONG_MODULES
    ]
    assert not over, f"modules over {MAX_MODULE_LINES} lines (split them by job): {over}"


def test_no_function_over_the_limit():
    over = []
    for rel, (_, funcs) in _sources().items():
        for node, n in funcs:
            if n > MAX_FUNCTION_LINES and f"{rel}::{node.name}" not in LONG_KERNELS:
                over.append(f"{rel}::{node.name} ({n} lines, line {node.lineno})")
    assert not over, (
        f"functions over {MAX_FUNCTION_LINES} lines (split them into helpers named for their "
        f"job; a numba kernel that must be long goes in LONG_KERNELS with its reason): {over}"
    )


def test_listed_exceptions_are_still_needed():
    """Every exception names a module or numba kernel that exists and is still over its limit:
    an entry outlives no split."""
    sources = _sources()
    stale = [
        rel for rel in LONG_MODULES if rel not in sources or sources[rel][0] <= MAX_MODULE_LINES
    ]
    for key in LONG_KERNELS:
        rel, name = key.split("::")
        found = [(node, n) for node, n in sources.get(rel, (0, []))[1] if node.name == name]
        if not any(n > MAX_FUNCTION_LINES and _is_numba_kernel(node) for node, n in found):
            stale.append(key)
    assert not stale, f"exceptions no longer needed (remove them from this test): {stale}"
