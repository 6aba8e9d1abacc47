"""flexmvm: contact and impact of flexible bodies with the multi-variable method.

Stages follow the data flow (docs/architecture.md):
mesh -> fe -> reduction -> bodies -> constraints/contact -> integrate -> results
-> metrics -> studies -> plots / cli.

The names below are the library's surface (docs/api.md); they are imported on first use, so
``import flexmvm`` stays cheap::

    import flexmvm as fm
    sc = fm.load_scenario("scenarios/rod_impact.toml").with_model("b2", fm.mvm("1-3", 25))
    res = fm.run(sc, t_end_s=8e-4)
    ref = fm.run(sc.with_model("b2", fm.full()), t_end_s=8e-4)
    fm.compare(res, ref).ncc_force
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

#: public name -> module that defines it
_API = {
    # scenarios: read, build, change
    "load_scenario": "flexmvm.scenarios.load",
    "scenario_from_dict": "flexmvm.scenarios.load",
    "Scenario": "flexmvm.scenarios.schema",
    "ModelConfig": "flexmvm.scenarios.body_schema",
    "ScenarioError": "flexmvm.scenarios.problems",
    "full": "flexmvm.scenarios.model_constructors",
    "mvm": "flexmvm.scenarios.model_constructors",
    "modal": "flexmvm.scenarios.model_constructors",
    "interface": "flexmvm.scenarios.model_constructors",
    "rigid": "flexmvm.scenarios.model_constructors",
    "ModelKind": "flexmvm.bodies.build",
    "KindSpec": "flexmvm.reduction.kinds",
    "register_kind": "flexmvm.reduction.kinds",
    "Material": "flexmvm.materials",
    "rayleigh_from_ratios": "flexmvm.bodies.damping",
    # mechanisms: the tables of joints, drives, supports, loads, springs, damping, motion
    "joint": "flexmvm.scenarios.mechanism",
    "drive": "flexmvm.scenarios.mechanism",
    "spin_up": "flexmvm.scenarios.mechanism",
    "prescribed_path": "flexmvm.scenarios.mechanism",
    "clamp": "flexmvm.scenarios.mechanism",
    "applied_load": "flexmvm.scenarios.mechanism",
    "spring": "flexmvm.scenarios.mechanism",
    "damping": "flexmvm.scenarios.mechanism",
    "rigid_motion": "flexmvm.scenarios.mechanism",
    # runs and comparisons
    "run": "flexmvm.runs.run",
    "ScenarioRun": "flexmvm.runs.run",
    "RunResult": "flexmvm.integrate.run_result",
    "compare": "flexmvm.runs.compare",
    "RunComparison": "flexmvm.runs.compare",
    "theory_histories": "flexmvm.theory.scenario",
    "write_run": "flexmvm.results.output",
    "read_run": "flexmvm.runs.written_run",
    "Target": "flexmvm.metrics.ncc",
    # studies
    "select": "flexmvm.studies.api",
    "material_study": "flexmvm.studies.api",
    "estimate_selection": "flexmvm.studies.estimate",
    "estimate_interface": "flexmvm.studies.estimate",
    "estimate_region": "flexmvm.studies.region_estimate",
    # per-process caches
    "clear_caches": "flexmvm.assembly.build_cache",
    "set_cache_sizes": "flexmvm.assembly.build_cache",
    "cache_sizes": "flexmvm.assembly.build_cache",
    # errors
    "FlexmvmError": "flexmvm.errors",
    "InputError": "flexmvm.errors",
    "SolverError": "flexmvm.errors",
}

__all__ = [
    "FlexmvmError",
    "InputError",
    "KindSpec",
    "Material",
    "ModelConfig",
    "ModelKind",
    "RunComparison",
    "RunResult",
    "Scenario",
    "ScenarioError",
    "ScenarioRun",
    "SolverError",
    "Target",
    "applied_load",
    "cache_sizes",
    "clamp",
    "clear_caches",
    "compare",
    "damping",
    "drive",
    "estimate_interface",
    "estimate_region",
    "estimate_selection",
    "full",
    "interface",
    "joint",
    "load_scenario",
    "material_study",
    "modal",
    "mvm",
    "prescribed_path",
    "rayleigh_from_ratios",
    "read_run",
    "register_kind",
    "rigid",
    "rigid_motion",
    "run",
    "scenario_from_dict",
    "select",
    "set_cache_sizes",
    "spin_up",
    "spring",
    "theory_histories",
    "write_run",
]


def __getattr__(name: str):
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'flexmvm' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_API))
