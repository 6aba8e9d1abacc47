"""Scenarios: the TOML schema (schema.py) shared by tests, examples and benchmarks.

``load_scenario(path)`` reads and validates a file (docs/scenario_format.md) and returns a frozen
:class:`Scenario`; every problem is one :class:`ScenarioError` line (file, key path, problem).
"""

from flexmvm.scenarios.schema import (
    ROD_FACET_SETS,
    ROD_NODE_SETS,
    Ball,
    BodyConfig,
    Box,
    ContactConfig,
    ContactKind,
    JointConfig,
    JointType,
    MaterialSpec,
    ModelConfig,
    ModelKind,
    Placement,
    ProbeConfig,
    RegionSpec,
    RodConfig,
    RodEnd,
    Rotation,
    Scenario,
    ScenarioError,
    TimeConfig,
    load_scenario,
    scenario_from_dict,
)

__all__ = [
    "ROD_FACET_SETS",
    "ROD_NODE_SETS",
    "Ball",
    "BodyConfig",
    "Box",
    "ContactConfig",
    "ContactKind",
    "JointConfig",
    "JointType",
    "MaterialSpec",
    "ModelConfig",
    "ModelKind",
    "Placement",
    "ProbeConfig",
    "RegionSpec",
    "RodConfig",
    "RodEnd",
    "Rotation",
    "Scenario",
    "ScenarioError",
    "TimeConfig",
    "load_scenario",
    "scenario_from_dict",
]
