"""Scenarios: the schema and its loading (the first of three stages, docs/architecture.md). The
schema (schema.py, a body's tables body_schema.py, one module per table kind *_schema.py; value
types fields.py, error lines problems.py), reading files and dicts (load.py), the model
constructors (model_constructors.py) and a mechanism's tables made from Python (mechanism.py).
A Scenario holds values only: a System is built from it by flexmvm.assembly (build.py) and run
by flexmvm.runs (run.py).

``load_scenario(path)`` reads and validates a file (docs/scenario_format.md) and returns a frozen
:class:`Scenario`; every problem is one :class:`ScenarioError` line (file, key path, problem).
"""

from flexmvm.bodies.build import ModelKind
from flexmvm.constraints.contact import ContactKind
from flexmvm.constraints.joints import JointType
from flexmvm.mesh.rod import EndShape
from flexmvm.scenarios.body_schema import (
    Ball,
    BodyConfig,
    Box,
    MaterialSpec,
    ModelConfig,
    Placement,
    RegionSpec,
    RodConfig,
    Rotation,
)
from flexmvm.scenarios.damping_schema import DampingConfig
from flexmvm.scenarios.drive_schema import DriveConfig, HistoryConfig, PathConfig, SpinUpConfig
from flexmvm.scenarios.fields import ROD_FACET_SETS, ROD_NODE_SETS
from flexmvm.scenarios.initial_motion import RigidMotionConfig
from flexmvm.scenarios.load import load_scenario, scenario_from_dict
from flexmvm.scenarios.load_schema import LoadConfig, LoadFrame, LoadType, SpringConfig, SpringType
from flexmvm.scenarios.model_constructors import full, interface, modal, mvm, rigid
from flexmvm.scenarios.problems import ScenarioError
from flexmvm.scenarios.schema import ContactConfig, JointConfig, ProbeConfig, Scenario, TimeConfig
from flexmvm.scenarios.support_schema import SupportConfig, SupportType

__all__ = [
    "ROD_FACET_SETS",
    "ROD_NODE_SETS",
    "Ball",
    "BodyConfig",
    "Box",
    "ContactConfig",
    "ContactKind",
    "DampingConfig",
    "DriveConfig",
    "EndShape",
    "HistoryConfig",
    "JointConfig",
    "JointType",
    "LoadConfig",
    "LoadFrame",
    "LoadType",
    "MaterialSpec",
    "ModelConfig",
    "ModelKind",
    "PathConfig",
    "Placement",
    "ProbeConfig",
    "RegionSpec",
    "RigidMotionConfig",
    "RodConfig",
    "Rotation",
    "Scenario",
    "ScenarioError",
    "SpinUpConfig",
    "SpringConfig",
    "SpringType",
    "SupportConfig",
    "SupportType",
    "TimeConfig",
    "full",
    "interface",
    "load_scenario",
    "modal",
    "mvm",
    "rigid",
    "scenario_from_dict",
]
