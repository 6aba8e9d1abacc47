"""Physics validation, a repository tool: the cases (cases.py) against closed forms, the 1D
wave-Hertz solution and each other, their stored runs (runs.py), the one acceptance table
(acceptance.py) that the report (report.py, templates/) and the tests read, and the command that
runs them all (suite.py; ``python -m tools.validation`` from the repository root, command.py).

It reads the repository's scenarios/ and writes docs/validation.md and docs/validation/
(paths.py); it imports flexmvm, flexmvm never imports it.
"""

from tools.validation.arm_stop import arm_stop_case
from tools.validation.cases import (
    CASES,
    DT,
    SHORT_FINE_MESH,
    T_FLAT,
    T_SEED,
    T_STEP,
    flat_vs_st_venant,
    pendulum_case,
    seed_scenario,
    seed_vs_theory,
    short_case,
    short_scenario,
    step_convergence,
)
from tools.validation.paths import git_commit
from tools.validation.runs import Case, case_inputs, case_key, run_case

__all__ = [
    "CASES",
    "DT",
    "SHORT_FINE_MESH",
    "T_FLAT",
    "T_SEED",
    "T_STEP",
    "Case",
    "arm_stop_case",
    "case_inputs",
    "case_key",
    "flat_vs_st_venant",
    "git_commit",
    "pendulum_case",
    "run_case",
    "seed_scenario",
    "seed_vs_theory",
    "short_case",
    "short_scenario",
    "step_convergence",
]
