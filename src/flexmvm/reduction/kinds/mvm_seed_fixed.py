"""The seed's MVM, the other reading (kind ``mvm-seed-fixed``): seed eq. (4) with the
region-I modes of region II held (Craig-Bampton's fixed-interface modes without its
constraint modes)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.fe.assembly import FEModel
from flexmvm.fe.modes import solver_pool, spd_solver
from flexmvm.reduction.kinds.mvm import fixed_interface_modes, node_dofs
from flexmvm.reduction.kinds.registry import ModelKind
from flexmvm.reduction.kinds.spec import Basis, BasisRequest, ModesFirst
from flexmvm.reduction.reference_condition import ReferenceCondition


@dataclass(frozen=True)
class SeedFixed(ModesFirst):
    name: str = ModelKind.MVM_SEED_FIXED.value

    def build_basis(self, request: BasisRequest) -> Basis:
        return seed_fixed(request.fe, request.reference, request.nodes, request.n_modes)


SPEC = SeedFixed()


def seed_fixed(
    fe: FEModel, reference: ReferenceCondition, nodes: np.ndarray, n_modes: int
) -> Basis:
    """Seed eq. (4), T = diag(Psi_I, I_II), the other reading: Psi_I = the first n_modes
    modes of region I with the region-II DOFs (and the reference DOFs) held, i.e. the
    fixed-interface modes of Craig-Bampton without its static constraint modes. A region-II
    node moving alone leaves its region-I neighbours in place (the modes vanish at it).
    Columns: the modes, then the retained nodes' x, y, z (as SEED_BLOCK).
    """
    b = node_dofs(nodes)
    interior = np.setdiff1d(reference.free_dofs(fe.n_dof), b)
    psi = np.zeros((fe.n_dof, n_modes + b.size))
    freqs = np.zeros(0)
    if n_modes:
        k_ii = fe.K[interior][:, interior]
        with solver_pool() as pool:
            psi[interior, :n_modes], freqs = fixed_interface_modes(
                fe, interior, k_ii, spd_solver(k_ii, pool), n_modes
            )
    psi[b, n_modes + np.arange(b.size)] = 1.0
    return Basis(ModelKind.MVM_SEED_FIXED, psi, nodes, n_modes, reference, freqs)
