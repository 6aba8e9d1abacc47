"""Stages point one way (docs/architecture.md): a module imports only from its own stage or the
stages below it, and never another module's private (underscored) names. Checked on the
import statements of every module (top level and inside functions), so a lazy import cannot
hide a cycle either."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "flexmvm"

# lowest first; a stage may import itself and anything earlier in this list
STAGES = [
    "errors",
    "enum_registry",
    "threads",
    "processes",
    "materials",
    "time_functions",
    "mesh",
    "fe",
    "plasticity",
    "reduction",
    "bodies",
    "constraints",
    "contact",
    "loads",
    "integrate",
    "metrics",
    "theory",
    "results",
    "setup_cache",
    "plots",
    # a scenario file in three stages, one job each (docs/architecture.md): the schema and its
    # loading (a Scenario: values only), the assembly of a System from it (through the setup
    # cache), and the runs made of a System (summaries, guards, comparisons, stored runs)
    "scenarios",
    "assembly",
    "runs",
    "studies",
    "cli",
]


def _stage(module: str) -> str | None:
    parts = module.split(".")
    if parts[0] != "flexmvm" or len(parts) < 2:
        return None
    return parts[1]


def _imports(path: Path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            yield node.module, node.lineno
        elif isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, node.lineno


def test_stages_point_one_way():
    wrong = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE)
        own = rel.parts[0].removesuffix(".py")
        if own not in STAGES or path.name == "__main__.py":
            continue  # the package's __init__ and `python -m` entry points: above every stage
        for module, line in _imports(path):
            other = _stage(module)
            if other is None or other not in STAGES:
                continue
            if STAGES.index(other) > STAGES.index(own):
                wrong.append(f"{rel}:{line} ({own}) imports {module} ({other})")
    assert not wrong, "\n".join(wrong)


#: Top-level names of the repository's own code outside the package (tools/validation, the
#: benchmarks' scripts, the tests): they may import flexmvm, flexmvm never imports them.
REPOSITORY_ONLY = ("tools", "benchmarks", "tests")


def test_package_imports_no_repository_tool():
    """The package works from a wheel: no module of flexmvm imports the repository's tools
    (tools.validation calls git and writes the checkout's docs/), benchmarks or tests."""
    wrong = [
        f"{path.relative_to(PACKAGE)}:{line} imports {module}"
        for path in sorted(PACKAGE.rglob("*.py"))
        for module, line in _imports(path)
        if module.split(".")[0] in REPOSITORY_ONLY
    ]
    assert not wrong, "\n".join(wrong)
    assert not (PACKAGE / "validation").exists(), "the validation is tools/validation, not a stage"


def test_every_stage_is_listed():
    names = {
        p.name.removesuffix(".py")
        for p in PACKAGE.iterdir()
        if (p.is_dir() and (p / "__init__.py").exists())
        or (p.suffix == ".py" and p.name != "__init__.py")
    }
    assert names <= set(STAGES), names - set(STAGES)


def test_no_private_names_across_modules():
    """`from flexmvm.x import _name` reaches into another module's internals: what a module
    shares it names without an underscore (dunders such as __version__ excepted)."""
    wrong = []
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.ImportFrom)
                and node.module
                and node.level == 0
                and node.module.split(".")[0] == "flexmvm"
            ):
                for alias in node.names:
                    if alias.name.startswith("_") and not alias.name.startswith("__"):
                        wrong.append(
                            f"{path.relative_to(PACKAGE)}:{node.lineno} imports "
                            f"{node.module}.{alias.name}"
                        )
    assert not wrong, "\n".join(wrong)


#: What a build makes (bodies, states, FE models, plastic parts, the system): the schema stage
#: (scenarios/) holds values and checks them, so none of its modules imports these; the
#: assembly stage makes them from its tables
BUILT = {
    "flexmvm.bodies.body": {"FlexibleBody"},
    "flexmvm.bodies.stiffening": {"geometric_stiffening"},
    "flexmvm.integrate.state": {"BodyState"},
    "flexmvm.integrate.system": {"System"},
    "flexmvm.integrate.plastic_bodies": {"PlasticPart"},
    "flexmvm.plasticity.body": {"PlasticBody"},
    "flexmvm.fe.assembly": {"FEModel", "assemble"},
}


def test_schema_stage_builds_nothing():
    """A schema module reads and checks a table; what the table makes is built by the assembly
    stage (e.g. a body's geometric stiffening: assembly/stiffened_body.py)."""
    wrong = []
    for path in sorted((PACKAGE / "scenarios").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module in BUILT:
                names = {a.name for a in node.names} & BUILT[node.module]
                if names:
                    wrong.append(f"{path.relative_to(PACKAGE)}:{node.lineno} {sorted(names)}")
    assert not wrong, "\n".join(wrong)


def test_showcase_code_is_in_showcases():
    """Code for one shipped scenario file (the pendulum release's measures, the sphere on
    block's Hertz check) sits in runs/showcases/, not in a stage's own modules."""
    showcases = {"pendulum.py", "hertz_block.py"}
    found = {
        p.relative_to(PACKAGE).as_posix()
        for p in PACKAGE.rglob("*.py")
        if p.name in showcases and "plots" not in p.parts
    }
    assert found == {f"runs/showcases/{name}" for name in showcases}, found


# integrate/ in three rooms, lowest first: the step contract (what an integrator fulfils and
# the driver reads), the Moreau-Jean scheme's own package, the driver's side (the time loop,
# its outputs and energy ledger). A room imports only itself and the rooms before it; outside
# integrate/moreau_jean/ the scheme is taken from the package (its __init__), never from its
# modules. A new module of integrate/ joins a room here.
INTEGRATE_ROOMS = [
    {"integrate", "state", "system", "step", "theta", "row_products", "plastic_bodies"},
    {"moreau_jean"},
    {"energy_ledger", "run_result", "recorder", "progress", "moving_region", "driver"},
]
SCHEME = PACKAGE / "integrate" / "moreau_jean"


def _integrate_room(module: str) -> int | None:
    parts = module.split(".")
    if parts[:2] != ["flexmvm", "integrate"]:
        return None
    name = parts[2] if len(parts) > 2 and parts[2] != "__init__" else "integrate"
    return next(k for k, room in enumerate(INTEGRATE_ROOMS) if name in room)


def test_integrate_rooms_point_one_way():
    """The contract does not import the scheme or the driver, the scheme does not import the
    driver's side, and nothing outside the scheme's package reaches into its modules."""
    scheme_modules = {p.stem for p in SCHEME.glob("*.py")} - {"__init__"}
    wrong = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE)
        inside = SCHEME in path.parents
        own = (
            _integrate_room("flexmvm." + ".".join(rel.with_suffix("").parts))
            if rel.parts[0] == "integrate"
            else None
        )
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if not (isinstance(node, ast.ImportFrom) and node.module and node.level == 0):
                continue
            module = node.module
            other = _integrate_room(module)
            if other is None:
                continue
            reaches = module.startswith("flexmvm.integrate.moreau_jean.") or (
                module == "flexmvm.integrate.moreau_jean"
                and any(a.name in scheme_modules for a in node.names)
            )
            if reaches and not inside:
                wrong.append(f"{rel}:{node.lineno} imports {module} (a module of the scheme)")
            if own is not None and other > own:
                wrong.append(f"{rel}:{node.lineno} imports {module} (a later room of integrate/)")
    assert not wrong, "\n".join(wrong)


def test_every_integrate_module_has_a_room():
    """integrate/ holds the contract, the scheme's package and the driver's side: a module
    directly in it is in one of INTEGRATE_ROOMS (a piece of the scheme goes in moreau_jean/)."""
    here = {
        p.stem if p.suffix == ".py" else p.name
        for p in (PACKAGE / "integrate").iterdir()
        if p.name != "__init__.py" and (p.suffix == ".py" or (p / "__init__.py").exists())
    }
    assert SCHEME.is_dir()
    assert here <= set().union(*INTEGRATE_ROOMS), sorted(here - set().union(*INTEGRATE_ROOMS))
