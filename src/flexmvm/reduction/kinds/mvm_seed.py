"""The seed's MVM (kind ``mvm-seed``): seed eq. (4), T = diag(Psi_I, I_II), Psi_I the
reference-supported body's modes restricted to region I."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.fe.assembly import FEModel
from flexmvm.fe.modes import constrained_modes
from flexmvm.reduction.kinds.mvm import node_dofs
from flexmvm.reduction.kinds.registry import ModelKind
from flexmvm.reduction.kinds.spec import Basis, BasisRequest, ModesFirst
from flexmvm.reduction.reference_condition import ReferenceCondition


@dataclass(frozen=True)
class SeedBlock(ModesFirst):
    name: str = ModelKind.MVM_SEED.value

    def build_basis(self, request: BasisRequest) -> Basis:
        return seed_block(request.fe, request.reference, request.nodes, request.n_modes)


SPEC = SeedBlock()


def seed_block(
    fe: FEModel, reference: ReferenceCondition, nodes: np.ndarray, n_modes: int
) -> Basis:
    """Seed eq. (4): T = diag(Psi_I, I_II).

    Choice made here: Psi_I = the first n_modes modes of the whole body supported by the
    reference condition, with their region-II rows set to zero (restricted to region I);
    region-II DOFs keep their nodal coordinates. Columns: the modes, then the retained
    nodes' x, y, z.
    """
    b = node_dofs(nodes)
    psi = np.zeros((fe.n_dof, n_modes + b.size))
    freqs = np.zeros(0)
    if n_modes:
        freqs, phi = constrained_modes(fe.M, fe.K, reference.fixed_dofs, n_modes)
        phi[b] = 0.0
        psi[:, :n_modes] = phi
    psi[b, n_modes + np.arange(b.size)] = 1.0
    return Basis(ModelKind.MVM_SEED, psi, nodes, n_modes, reference, freqs)
