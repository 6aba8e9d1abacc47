"""The package asks for what it uses through declared interfaces (issue 50 item 2, for the
whole of src/flexmvm as tests/test_integrate_interfaces.py does for integrate/): every
getattr/hasattr call left is one of the listed dynamic uses below, each with its reason; a
new probe of an optional capability (getattr(x, "attr", default), hasattr(x, "attr")) fails
it. 60 calls before this test (25 capability probes: a load's external, energy, reset and
bodies, a contact's slave, master, name and search radius, a joint's p1, a material's
plasticity, a spring's body2, a run's curves, a basis kind's value, a sparse psi's todense,
the notes hook's marker). Reads the sources only, in well under a second."""

from __future__ import annotations

import ast
from collections import Counter
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "flexmvm"

#: The module's __getattr__ importing a public name on first use (lazy import)
LAZY = "a package __getattr__: the public name imported on first use"
#: A frozen config or spec reads its own fields by name from a table of field names
FIELD = "a field read by its name from a table of field names (validation, serialising)"

#: (module, enclosing function, the call) -> (how many, why it stays)
ALLOWED = {
    ("__init__.py", "__getattr__", "getattr(importlib.import_module(module), name)"): (1, LAZY),
    ("cli/main.py", "__getattr__", "getattr(app, name)"): (1, LAZY),
    ("assembly/mesh_lookup.py", "check_contact_surfaces", "getattr(c, role)"): (1, FIELD),
    ("bodies/damping.py", "RayleighDamping.__post_init__", "getattr(self, name)"): (1, FIELD),
    ("contact/geometry.py", "Projection.take", "getattr(self, k)"): (1, FIELD),
    ("mesh/rod.py", "RodSpec.__post_init__", "getattr(self, name)"): (3, FIELD),
    ("metrics/ncc.py", "Target.__post_init__", "getattr(self, key)"): (1, FIELD),
    ("runs/compare.py", "RunComparison.as_dict", "getattr(self, k)"): (2, FIELD),
    ("scenarios/body_schema.py", "RegionSpec._check", "getattr(self, k)"): (1, FIELD),
    ("scenarios/body_schema.py", "Placement._one_motion", "getattr(self, k)"): (1, FIELD),
    ("scenarios/drive_schema.py", "_exactly_one", "getattr(model, k)"): (1, FIELD),
    ("scenarios/drive_schema.py", "PathConfig._check", "getattr(self, key)"): (1, FIELD),
    ("scenarios/joint_schema.py", "JointConfig._check", "getattr(self, key)"): (1, FIELD),
    ("scenarios/load_schema.py", "_need_allow", "getattr(obj, key)"): (1, FIELD),
    ("scenarios/load_schema.py", "LoadConfig._check", "getattr(self, other)"): (1, FIELD),
    ("scenarios/load_schema.py", "LoadConfig._check", "getattr(self, key)"): (1, FIELD),
    ("scenarios/load_schema.py", "LoadConfig.history", "getattr(self, key)"): (1, FIELD),
    ("scenarios/schema.py", "Scenario._cross_references", "getattr(c, role)"): (1, FIELD),
    ("scenarios/support_schema.py", "SupportConfig._keys", "getattr(self, key)"): (1, FIELD),
    ("scenarios/support_schema.py", "SupportConfig._check_targets", "getattr(self, key)"): (
        1,
        FIELD,
    ),
    ("scenarios/support_schema.py", "SupportConfig.axes", "getattr(self, key)"): (1, FIELD),
    ("studies/report.py", "target_dict", "getattr(t, k)"): (1, FIELD),
    ("studies/report.py", "target_text", "getattr(t, key)"): (2, FIELD),
    ("theory/beam_impact.py", "SphereOnBeam.__post_init__", "getattr(self, name)"): (1, FIELD),
    ("theory/moving_load.py", "MovingForce.__post_init__", "getattr(self, name)"): (1, FIELD),
    ("theory/scenario.py", "_rod_histories", "getattr(sol, f'v{rod}_{where}')"): (1, FIELD),
    ("theory/slider_crank.py", "SliderCrank.__post_init__", "getattr(self, name)"): (1, FIELD),
    ("theory/timoshenko.py", "TimoshenkoBeam.__post_init__", "getattr(self, name)"): (1, FIELD),
    ("theory/wave.py", "Rod1D.__post_init__", "getattr(self, key)"): (1, FIELD),
    # the standard library's private attribute (ProcessPoolExecutor._processes): no public
    # interface lists a pool's worker processes, and it may be absent or None after shutdown
    ("runs/main_job.py", "_stop_workers", "getattr(pool, '_processes', None)"): (1, "stdlib"),
    # __main__ has no __file__ in an interactive session or under python -c
    (
        "studies/main_guard.py",
        "unguarded_main_script",
        "getattr(sys.modules.get('__main__'), '__file__', None)",
    ): (1, "interpreter"),
}


def _calls(path: Path) -> list[tuple[str, str, str]]:
    """(module, enclosing function or class.method, the call's source) of every getattr and
    hasattr call in the module at path."""
    module = path.relative_to(PACKAGE).as_posix()
    found = []

    def walk(node: ast.AST, scope: tuple[str, ...]) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                walk(child, (*scope, child.name))
                continue
            if (
                isinstance(child, ast.Call)
                and isinstance(child.func, ast.Name)
                and child.func.id in ("getattr", "hasattr")
            ):
                found.append((module, ".".join(scope), ast.unparse(child)))
            walk(child, scope)

    walk(ast.parse(path.read_text(encoding="utf-8")), ())
    return found


def test_every_getattr_left_is_a_listed_dynamic_use():
    calls = Counter(c for path in sorted(PACKAGE.rglob("*.py")) for c in _calls(path))
    assert dict(calls) == {key: n for key, (n, _) in ALLOWED.items()}
