"""Reduction bases Psi (3n x nq): nodal displacement in the body frame u = Psi q.

| kind          | Psi                                             | q                          |
|---------------|-------------------------------------------------|----------------------------|
| FULL          | identity on every DOF but the reference ones    | nodal displacements        |
| CRAIG_BAMPTON | [[I, 0], [-K_ii^-1 K_ib, Phi_in]] (default MVM) | u_b of retained nodes, eta |
|               | with massless retained nodes c (n: the others): | u_b, static amplitudes,    |
|               | [[I, 0, 0], [(0, -K_ii^-1 K_in), S_c, Phi_in]]  | eta                        |
| SEED_BLOCK    | diag(Psi_I, I_II), seed eq. (4); Psi_I: whole-  | a_I, region-II u_II        |
|               | body modes, region-II rows zeroed               |                            |
| SEED_FIXED    | diag(Psi_I, I_II), seed eq. (4); Psi_I: modes   | a_I, region-II u_II        |
|               | of region I with region II held (Craig-Bampton  |                            |
|               | without its static constraint modes)            |                            |
| MODAL         | first N modes of the reference-supported body   | modal coordinates          |
| INTERFACE     | Hertz contact-patch Ritz vectors + free-free    | patch amplitudes, modal    |
|               | modes by participation (reduction/interface.py) | coordinates                |

A retained node without mass (its mass redistributed to its neighbours,
fe.mass_redistribution) keeps a massless coordinate only if its column moves nothing else: its
constraint mode is split into the nodal unit vector and its interior static field, whose span
gets columns of its own, M-orthonormalised (directions of no rank dropped), between the
retained nodes' columns and the modes (MasslessStatics):
- ALL: the static fields -K_ii^-1 K_ic of every massless DOF c; the span is the Craig-Bampton
  one plus the unit vectors of c, so every frequency lies between the full model's and the
  Craig-Bampton one (Rayleigh-Ritz); 3 columns per massless node (75 on the seed's b2 1-3);
- PATCH (default): the static fields of the smooth boundary patterns a contact patch loads
  (massless_patterns: 11 fields over the massless nodes, about their centroid and
  principal axes), so a body gains at most 11 columns instead of 3 per node; on the seed
  case (b2 1-3 + 37: 129 DOF with the frame, ALL's 193) its force matches ALL's and its full
  FE's at theta = 1/2 (docs/contact_law.md).
The coordinates u_c have zero rows in m_hat: the integrator holds them in equilibrium at the
step ends (integrate/moreau_jean/massless.py). Without the split a constraint mode drags interior
mass along and the redistribution leaves the retained contact coordinates massive.

Every Psi has zero rows at the reference DOFs (ReferenceCondition), so q carries no
rigid-body motion. The reduced matrices are m_hat = Psi^T M Psi, k_hat = Psi^T K Psi
(seed eq. 5; Wang, Hong, Liu 2014).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp
from threadpoolctl import threadpool_limits

from flexmvm.errors import InputError
from flexmvm.fe.assembly import FEModel
from flexmvm.reduction.interface import InterfaceSources, InterfaceSpec
from flexmvm.reduction.kinds import Basis, BasisRequest, ModelKind, kind_spec
from flexmvm.reduction.kinds.mvm import massless_patterns
from flexmvm.reduction.kinds.registry import BasisKind
from flexmvm.reduction.kinds.spec import MasslessStatics
from flexmvm.reduction.reference_condition import ReferenceCondition


def _retained(fe: FEModel, reference: ReferenceCondition, nodes) -> np.ndarray:
    """Validated retained node ids in the given order; InputError on a bad id."""
    ids = np.asarray(nodes).ravel()
    if ids.size == 0:
        return np.zeros(0, dtype=np.int64)
    if not np.issubdtype(ids.dtype, np.integer):
        raise InputError(f"retained nodes must be integer node ids, got dtype {ids.dtype}")
    ids = ids.astype(np.int64)
    n = fe.mesh.n_nodes
    if ids.min() < 0 or ids.max() >= n:
        raise InputError(f"retained node ids must be in 0..{n - 1}, got {ids.min()}..{ids.max()}")
    uniq, counts = np.unique(ids, return_counts=True)
    if np.any(counts > 1):
        raise InputError(f"retained nodes repeat: {uniq[counts > 1].tolist()[:10]}")
    clash = np.intersect1d(ids, reference.nodes)
    if clash.size:
        raise InputError(
            f"retained nodes {clash.tolist()} belong to the reference condition {reference.nodes}"
            "; choose the reference support away from region II"
        )
    return ids


def build_basis(
    fe: FEModel,
    kind: ModelKind,
    reference: ReferenceCondition,
    retained_nodes=(),
    n_modes: int = 0,
    interface: InterfaceSpec | None = None,
    sources: InterfaceSources | None = None,
    massless_statics: MasslessStatics = MasslessStatics.PATCH,
) -> Basis:
    """Build the basis ``kind`` of body ``fe`` (see the module table): the kind's own builder
    (reduction/kinds/, kind_spec(kind).build_basis).

    retained_nodes: region-II node ids (CRAIG_BAMPTON, SEED_BLOCK, SEED_FIXED: at least one;
    FULL, MODAL and INTERFACE: none); n_modes: modal columns (MODAL: >= 1; FULL: 0);
    interface: the patch and mode choice of an INTERFACE basis (reduction/interface.py);
    sources: where it takes its mode pool and patch statics from (default: computed);
    massless_statics: the static columns of massless retained nodes (CRAIG_BAMPTON).
    Raises InputError for a wrong kind, retained nodes that are reference nodes, repeated or
    outside the mesh, or n_modes negative or more than the free DOFs allow; SolverError if
    a factorisation or eigen solve fails.
    """
    if not isinstance(kind, BasisKind):
        raise InputError(f"basis kind must be a BasisKind, got {kind!r}")
    if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or n_modes < 0:
        raise InputError(f"n_modes must be an integer >= 0, got {n_modes!r}")
    if reference.fixed_dofs.size and reference.fixed_dofs.max() >= fe.n_dof:
        raise InputError(f"reference DOFs {reference.fixed_dofs.tolist()} exceed {fe.n_dof} DOFs")
    nodes = _retained(fe, reference, retained_nodes)
    spec = kind_spec(kind)
    if not spec.retains_nodes and nodes.size:
        raise InputError(f"a {kind.value} basis takes no retained nodes, got {nodes.size}")
    if spec.retains_nodes and not nodes.size:
        raise InputError(f"a {kind.value} basis needs at least one retained node, got none")
    request = BasisRequest(
        fe, reference, nodes, int(n_modes), interface, sources, MasslessStatics(massless_statics)
    )
    if spec.nodal:  # a sparse selection of DOFs: no BLAS
        basis = spec.build_basis(request)
    else:
        # One BLAS thread: SuperLU's many-right-hand-side solve calls BLAS once per
        # supernode; threaded OpenBLAS there is no faster on idle cores and ~10x slower when
        # other jobs share them (docs/notes/2026-11-27-comment-measurements.md).
        with threadpool_limits(limits=1, user_api="blas"):
            basis = spec.build_basis(request)
    # a kind that reuses another's builder (a registered variant) names its own bases
    return basis if basis.kind is kind else dataclasses.replace(basis, kind=kind)


def reduced_matrices(
    fe: FEModel, basis: Basis
) -> tuple[np.ndarray | sp.csr_matrix, np.ndarray | sp.csr_matrix]:
    """Reduced mass and stiffness m_hat = Psi^T M Psi, k_hat = Psi^T K Psi (seed eq. 5).

    Returns (m_hat, k_hat), (nq, nq) [kg], [N/m] in q units; csr for FULL, dense otherwise;
    both symmetrised ((A + A^T) / 2) to remove round-off asymmetry.
    Raises InputError if the basis does not match the model's DOF count.
    """
    psi = basis.psi
    if psi.shape[0] != fe.n_dof:
        raise InputError(f"basis has {psi.shape[0]} rows, model has {fe.n_dof} DOFs")
    if sp.issparse(psi):
        m = sp.csr_matrix(psi.T @ fe.M @ psi)
        k = sp.csr_matrix(psi.T @ fe.K @ psi)
        return sp.csr_matrix(0.5 * (m + m.T)), sp.csr_matrix(0.5 * (k + k.T))
    m = psi.T @ (fe.M @ psi)
    k = psi.T @ (fe.K @ psi)
    return 0.5 * (m + m.T), 0.5 * (k + k.T)


__all__ = [
    "Basis",
    "BasisKind",
    "MasslessStatics",
    "build_basis",
    "massless_patterns",
    "reduced_matrices",
]
