"""The value types of scenario files: numbers with their ranges, 3-vectors, names, the frozen
base model, and the rod sets every rod body has (docs/architecture.md, mesh)."""

from __future__ import annotations

import math
from typing import Annotated, Any

from annotated_types import Ge, Gt
from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Strict,
    StringConstraints,
)

from flexmvm.scenarios.problems import problem

ROD_NODE_SETS = ("end_a", "end_b", "end_a_centre", "end_b_centre", "side", "surface")
ROD_FACET_SETS = ("end_a", "end_b", "side", "surface")
ZERO3 = (0.0, 0.0, 0.0)


def vec3(value: Any) -> tuple[float, float, float]:
    """Three finite numbers [x, y, z] as a tuple of floats (a validator)."""
    ok = isinstance(value, (list, tuple)) and len(value) == 3
    ok = ok and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in value)
    if not ok or not all(math.isfinite(c) for c in value):
        raise problem(f"must be 3 finite numbers [x, y, z], got {value!r}")
    return (float(value[0]), float(value[1]), float(value[2]))


# Largest magnitudes of the motion a scenario may give [SI]. A speed of 1e6 m/s is two orders
# above the wave speed of any solid (~1e4 m/s), where a linear-elastic impact means nothing,
# and far below where the run's sums of squares overflow (1e200 m/s ended in "math domain
# error"); angular speeds the same in rad/s; gravity 1e9 m/s^2 is 1e8 g, beyond any shock test.
MAX_SPEED = 1e6
MAX_ACCELERATION = 1e9


def bounded(limit: float, unit: str):
    """A validator: a Vec3 whose magnitude is at most ``limit`` (in ``unit``)."""

    def check(value: tuple[float, float, float]) -> tuple[float, float, float]:
        size = math.hypot(*value)
        if not size <= limit:
            raise problem(
                f"magnitude must be <= {limit:g} {unit}, got {size:g} {unit} ({list(value)})"
            )
        return value

    return check


Num = Annotated[float, Strict()]
Positive = Annotated[float, Strict(), Gt(0)]
Count = Annotated[int, Strict(), Ge(1)]
Vec3 = Annotated[tuple[float, float, float], BeforeValidator(vec3)]
Velocity = Annotated[Vec3, AfterValidator(bounded(MAX_SPEED, "m/s"))]
AngularVelocity = Annotated[Vec3, AfterValidator(bounded(MAX_SPEED, "rad/s"))]
Acceleration = Annotated[Vec3, AfterValidator(bounded(MAX_ACCELERATION, "m/s^2"))]
Name = Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9_]+$")]
SetName = Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9_]+$")]


class Frozen(BaseModel):
    """Base of every scenario table: unknown keys, NaN and inf are errors; instances frozen."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


def check_rod_set(name: str, known: tuple[str, ...], key: str) -> None:
    """ScenarioError (via pydantic) unless ``name`` is one of a rod's sets ``known``."""
    if name not in known:
        raise problem(f"rods have no set {name!r} (rod sets: {', '.join(known)})", key)
