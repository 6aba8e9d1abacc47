"""Reduction stage: reference condition (3-2-1 support) and bases Psi with m_hat, k_hat."""

from flexmvm.reduction.basis import Basis, BasisKind, build_basis, reduced_matrices
from flexmvm.reduction.reference_condition import (
    ReferenceCondition,
    rigid_body_modes,
    three_two_one,
)

__all__ = [
    "Basis",
    "BasisKind",
    "ReferenceCondition",
    "build_basis",
    "reduced_matrices",
    "rigid_body_modes",
    "three_two_one",
]
