"""A body with the geometric stiffening of its ``[bodies.model] geometric_stiffening`` table
(scenarios/stiffening_schema.py): the prestress of a unit spin about the table's axis, solved
with the body supported as it is (its clamp when a support clamps it, else the six DOFs of its
3-2-1 reference condition) and scaled by the square of the frame's spin at every step
(bodies/stiffening.py)."""

from __future__ import annotations

import dataclasses

from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.stiffening import geometric_stiffening
from flexmvm.errors import InputError
from flexmvm.scenarios.stiffening_schema import StiffeningConfig


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


__all__ = ["stiffened"]
