"""A body's ``[bodies.model] geometric_stiffening`` table (bodies.stiffening): the spin axis
whose centrifugal prestress stiffens the body (the builder makes the stiffened body of it:
assembly/stiffened_body.py).

    geometric_stiffening = { axis = [0, 0, 1], point_m = [0, 0, 0] }

axis: the spin axis in the body's own (mesh) coordinates; point_m: a point of it [m], default
the mesh origin. The prestress of a unit spin is solved with the body supported as it is: its
clamp when a support clamps it, else its reference condition (the six DOFs of its 3-2-1
support); it is scaled by the square of the frame's spin about the axis at every step.
"""

from __future__ import annotations

import math
from typing import Annotated

from pydantic import Field, field_validator

from flexmvm.scenarios.fields import ZERO3, Frozen, Vec3
from flexmvm.scenarios.problems import problem


class StiffeningConfig(Frozen):
    """The spin axis (body frame, non-zero) and a point of it [m] (module doc)."""

    axis: Vec3
    point_m: Vec3 = ZERO3

    @field_validator("axis")
    @classmethod
    def _nonzero(cls, axis: tuple[float, float, float]) -> tuple[float, float, float]:
        if math.hypot(*axis) == 0.0:
            raise problem(f"must be non-zero, got {list(axis)}")
        return axis


#: The model's key: None (off) is left out of a dump, so a model without it dumps as before
#: the key existed (study keys and cache identities hash the dumps)
StiffeningKey = Annotated[StiffeningConfig | None, Field(exclude_if=lambda value: value is None)]


__all__ = ["StiffeningConfig", "StiffeningKey"]
