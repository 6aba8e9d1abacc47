"""The modal model (kind ``modal``): the first N modes of the body supported by its reference
condition."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError
from flexmvm.fe.modes import constrained_modes
from flexmvm.reduction.kinds.registry import ModelKind
from flexmvm.reduction.kinds.spec import Basis, BasisRequest, KindSpec


@dataclass(frozen=True)
class Modal(KindSpec):
    name: str = ModelKind.MODAL.value
    uses_modes: bool = True
    reads_modes: bool = True

    def build_basis(self, request: BasisRequest) -> Basis:
        if request.n_modes < 1:
            raise InputError("a modal basis needs n_modes >= 1, got 0")
        fe, reference, n_modes = request.fe, request.reference, request.n_modes
        freqs, phi = constrained_modes(fe.M, fe.K, reference.fixed_dofs, n_modes)
        return Basis(ModelKind.MODAL, phi, np.zeros(0, dtype=np.int64), n_modes, reference, freqs)


SPEC = Modal()
