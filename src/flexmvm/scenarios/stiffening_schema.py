"""A body's ``[bodies.model] geometric_stiffening`` table (bodies.stiffening): the spin axis
whose centrifugal prestress stiffens the body, and what the builder makes of it.

    geometric_stiffening = { axis = [0, 0, 1], point_m = [0, 0, 0] }

axis: the spin axis in the body's own (mesh) coordinates; point_m: a point of it [m], default
the mesh origin. The prestress of a unit spin is solved with the body supported as it is: its
clamp when a support clamps it, else its reference condition (the six DOFs of its 3-2-1
support); it is scaled by the square of the frame's spin about the axis at every step.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Annotated

from pydantic import Field, field_validator

from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.stiffening import geometric_stiffening
from flexmvm.errors import InputError
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


def stiffened(body: FlexibleBody, spec: StiffeningConfig, fe, basis, where: str) -> FlexibleBody:
    """``body`` (built on ``basis`` from the FE model ``fe``) with the geometric stiffening of
    ``spec``, the unit-spin prestress held at the basis' reference DOFs (its clamp's, or its
    3-2-1 support's). InputError naming ``where`` for supports that leave the body free."""
    try:
        st = geometric_stiffening(
            fe, basis.psi, body.k_hat, spec.axis, basis.reference.fixed_dofs, spec.point_m
        )
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    return dataclasses.replace(body, stiffening=st)


__all__ = ["StiffeningConfig", "StiffeningKey", "stiffened"]
