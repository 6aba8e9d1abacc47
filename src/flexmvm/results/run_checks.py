"""Checks shared by the writers of a RunResult (results.writers, results.h5): names usable
in files, array shapes, the bodies in the run's order, strides, the fields' precision."""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np

from flexmvm.bodies.body import FlexibleBody
from flexmvm.errors import InputError
from flexmvm.integrate.run_result import FieldPrecision, RunResult

SAFE_NAME = re.compile(r"^[A-Za-z0-9_.\-]+$")


def safe_name(kind: str, name: str) -> str:
    if not SAFE_NAME.match(name):
        raise InputError(
            f"{kind} name {name!r} cannot be used in a file name or column header; "
            "expected letters, digits, '_', '.', '-'"
        )
    return name


def check_run(run: RunResult) -> int:
    """Number of outputs; InputError unless run's arrays agree with its time axis."""
    n = len(run.t)
    checks = {
        "contact_force": (run.contact_force, (n,)),
        "probe_v": (run.probe_v, (n, len(run.probe_names), 3)),
        "probe_x": (run.probe_x, (n, len(run.probe_names), 3)),
        "frame_r": (run.frame_r, (n, len(run.body_names), 3)),
        "frame_v": (run.frame_v, (n, len(run.body_names), 6)),
        "frame_A": (run.frame_A, (n, len(run.body_names), 3, 3)),
    }
    for key, (arr, shape) in checks.items():
        if np.shape(arr) != shape:
            raise InputError(f"RunResult.{key}: expected shape {shape}, got {np.shape(arr)}")
    return n


def bodies_by_name(run: RunResult, bodies: Sequence[FlexibleBody]) -> list[FlexibleBody]:
    names = [b.name for b in bodies]
    if names != list(run.body_names):
        raise InputError(
            f"bodies: expected the run's bodies {list(run.body_names)} in order, got {names}"
        )
    return list(bodies)


def check_every(name: str, every: int) -> int:
    if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 1:
        raise InputError(f"{name}: expected an integer >= 1, got {every!r}")
    return int(every)


def field_dtype(run: RunResult) -> type:
    """The numpy type of the run's written fields (RunResult.field_precision)."""
    return np.float32 if run.field_precision is FieldPrecision.FLOAT32 else np.float64
