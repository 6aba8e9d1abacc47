"""The interface model (kind ``interface``, reduction/interface.py): no retained node; one
inertia-relieved static response to a Hertz pressure per patch radius, M-orthonormal to
free-free modes chosen by their participation (docs/interface_basis.md)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError
from flexmvm.reduction.interface import InterfaceSpec, interface_columns
from flexmvm.reduction.kinds.registry import ModelKind
from flexmvm.reduction.kinds.spec import Basis, BasisRequest, KindSpec


@dataclass(frozen=True)
class Interface(KindSpec):
    """Reads model.modes (>= 0: patch vectors alone are a basis) and the model.patch_* keys."""

    name: str = ModelKind.INTERFACE.value
    reads_modes: bool = True
    uses_patches: bool = True
    clampable: bool = False

    def build_basis(self, request: BasisRequest) -> Basis:
        spec = request.interface
        if not isinstance(spec, InterfaceSpec):
            raise InputError(f"an interface basis needs an InterfaceSpec, got {spec!r}")
        fe, reference, n_modes = request.fe, request.reference, request.n_modes
        cols = interface_columns(fe, reference, spec, n_modes, request.sources)
        return Basis(
            ModelKind.INTERFACE,
            cols.psi,
            np.zeros(0, dtype=np.int64),
            n_modes,
            reference,
            cols.mode_freqs_hz,
        )


SPEC = Interface()
