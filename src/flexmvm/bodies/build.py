"""Build a FlexibleBody from an FE model and a basis (seed eq. 5: m = psi^T M psi, k = psi^T K psi).

The expensive, configuration-independent part of a body is its BodyParts (inertia invariants
and k_hat): body_parts computes them, body_from_parts wraps them into a body without
recomputing, so a cache (flexmvm.setup_cache.cached_body) can hold them. ModelKind (the model
kinds, reduction/kinds/) is imported here for its former importers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.damping import Damping, reduced_damping
from flexmvm.bodies.invariants import InertiaInvariants, inertia_invariants, leading_columns
from flexmvm.reduction.kinds import ModelKind


@dataclass(frozen=True)
class BodyParts:
    """What a body costs to build: inertia invariants and k_hat (nq, nq) [N/m] (csr if the basis
    is sparse, else dense)."""

    inv: InertiaInvariants
    k_hat: np.ndarray | sp.csr_matrix

    def leading(self, m: int) -> BodyParts:
        """The parts of the dense basis psi[:, :m] (a Craig-Bampton basis cut to fewer modes)."""
        return BodyParts(leading_columns(self.inv, m), np.ascontiguousarray(self.k_hat[:m, :m]))


def reduced_stiffness(K: sp.spmatrix, psi) -> np.ndarray | sp.csr_matrix:
    """k_hat = psi^T K psi, symmetrized: (nq, nq) [N/m] for K (3n, 3n) [N/m], psi (3n, nq).

    Dense psi gives a dense k_hat. A sparse psi that only selects DOFs (one entry 1.0 per
    column: a full-FE basis) gives K's rows and columns at those DOFs (the same numbers as the
    product, ~10x faster); another sparse psi the sparse product. Both csr.
    """
    if not sp.issparse(psi):
        k_hat = psi.T @ (K @ psi)
        return 0.5 * (k_hat + k_hat.T)
    pc = sp.csc_matrix(psi)
    if np.all(np.diff(pc.indptr) == 1) and np.all(pc.data == 1.0):
        K = sp.csr_matrix(K)
        k_hat = K[pc.indices][:, pc.indices]
    else:
        pr = sp.csr_matrix(psi)
        k_hat = sp.csr_matrix(pr.T @ K @ pr)
    return sp.csr_matrix(0.5 * (k_hat + k_hat.T))


def body_parts(fe, basis) -> BodyParts:
    """Invariants of (fe.mesh.nodes, fe.M_scalar, basis.psi) and k_hat = psi^T fe.K psi."""
    psi = sp.csr_matrix(basis.psi) if sp.issparse(basis.psi) else basis.psi
    return BodyParts(
        inertia_invariants(fe.mesh.nodes, fe.M_scalar, psi), reduced_stiffness(fe.K, psi)
    )


def body_from_parts(
    name: str,
    mesh,
    basis,
    parts: BodyParts,
    *,
    damping: Damping | None = None,
    body_type: type[FlexibleBody] = FlexibleBody,
    **fields,
) -> FlexibleBody:
    """The body of mesh (nodes X (n, 3) [m]) and basis psi (3n, nq) with precomputed parts.

    damping: Rayleigh (C = alpha M_qq + beta k_hat) or modal ratios (bodies.damping; off by
    default). body_type: a FlexibleBody subclass to make (e.g. bodies.ring_body.RingBody),
    given its further ``fields``.
    """
    psi = sp.csr_matrix(basis.psi) if sp.issparse(basis.psi) else basis.psi
    if psi.shape != (3 * mesh.n_nodes, parts.inv.nq):
        raise ValueError(
            f"body {name}: basis {psi.shape} does not match its parts "
            f"({3 * mesh.n_nodes}, {parts.inv.nq})"
        )
    c_hat = reduced_damping(damping, parts.inv.M_qq, parts.k_hat, basis, name)
    return body_type(
        name,
        np.asarray(mesh.nodes, float),
        psi,
        parts.inv,
        parts.k_hat,
        mesh,
        c_hat,
        str(basis.kind),
        **fields,
    )


def body_from_fe(name: str, fe, basis, *, damping: Damping | None = None) -> FlexibleBody:
    """The floating-frame body of FE model `fe` (M_scalar, K) with basis psi.

    damping: see body_from_parts (off by default).
    A basis with no columns gives a rigid body with the FE model's mass distribution.
    """
    return body_from_parts(name, fe.mesh, basis, body_parts(fe, basis), damping=damping)


def rigid_body_from_fe(name: str, fe) -> FlexibleBody:
    """A rigid body (nq = 0) with the mass distribution of fe."""
    n = fe.mesh.n_nodes
    return FlexibleBody.build(
        name,
        fe.mesh.nodes,
        fe.M_scalar,
        np.zeros((3 * n, 0)),
        np.zeros((0, 0)),
        mesh=fe.mesh,
        label="rigid",
    )


__all__ = [
    "BodyParts",
    "ModelKind",
    "body_from_fe",
    "body_from_parts",
    "body_parts",
    "reduced_stiffness",
    "rigid_body_from_fe",
]
