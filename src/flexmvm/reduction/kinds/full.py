"""The full FE model (kind ``full``): every nodal DOF but the reference condition's six; psi
the sparse identity on the free DOFs."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from flexmvm.errors import InputError
from flexmvm.reduction.kinds.registry import ModelKind
from flexmvm.reduction.kinds.spec import Basis, BasisRequest, KindSpec


@dataclass(frozen=True)
class Full(KindSpec):
    """Nodal: every node not in the reference condition is retained; its parts are sparse."""

    name: str = ModelKind.FULL.value
    nodal: bool = True

    def build_basis(self, request: BasisRequest) -> Basis:
        if request.n_modes:
            raise InputError(f"a full basis takes no modes, got n_modes={request.n_modes}")
        fe, reference = request.fe, request.reference
        free = reference.free_dofs(fe.n_dof)
        psi = sp.csr_matrix(
            (np.ones(free.size), (free, np.arange(free.size))), shape=(fe.n_dof, free.size)
        )
        nodes = np.setdiff1d(np.arange(fe.mesh.n_nodes), reference.nodes)
        return Basis(ModelKind.FULL, psi, nodes, 0, reference, np.zeros(0))

    def retained_columns(self, basis: Basis) -> np.ndarray:
        """The free DOFs' columns of each retained node (a reference node's clamped
        components have none)."""
        free = basis.reference.free_dofs(basis.psi.shape[0])
        dofs = 3 * basis.retained_nodes[:, None] + np.arange(3)
        return np.searchsorted(free, dofs)

    def study_fields(self, args: tuple[str, ...]) -> Mapping[str, Any] | None:
        return None if args else {"kind": self.name}


SPEC = Full()
