"""The default MVM (kind ``mvm``): Craig-Bampton (1968), the retained nodes' DOFs, their
static constraint modes and the fixed-interface modes; the constraint modes of massless
retained nodes split into static columns of their own (reduction/basis.py's module doc,
MasslessStatics). Its fixed-interface modes also serve kind mvm-seed-fixed."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from flexmvm.fe.assembly import FEModel
from flexmvm.fe.modes import shift_invert_modes, solver_pool, spd_solver, to_hz
from flexmvm.reduction.kinds.registry import ModelKind
from flexmvm.reduction.kinds.spec import (
    Basis,
    BasisRequest,
    MasslessStatics,
    NodesAndModes,
)
from flexmvm.reduction.reference_condition import ReferenceCondition


@dataclass(frozen=True)
class CraigBampton(NodesAndModes):
    """Columns: the retained nodes' x, y, z, the massless nodes' static columns, the modes;
    a basis of fewer modes is the leading columns of one of more (cuts_modes)."""

    name: str = ModelKind.MVM.value
    cuts_modes: bool = True

    def build_basis(self, request: BasisRequest) -> Basis:
        return craig_bampton(
            request.fe,
            request.reference,
            request.nodes,
            request.n_modes,
            MasslessStatics(request.massless_statics),
        )

    def n_static(self, basis: Basis) -> int:
        return basis.nq - 3 * basis.retained_nodes.size - basis.n_modes


SPEC = CraigBampton()


def node_dofs(nodes: np.ndarray) -> np.ndarray:
    """DOF ids 3k + d, node-major in the given node order, (3 len(nodes),)."""
    return (3 * nodes[:, None] + np.arange(3)).ravel()


def craig_bampton(
    fe: FEModel,
    reference: ReferenceCondition,
    nodes: np.ndarray,
    n_modes: int,
    statics_kind: MasslessStatics = MasslessStatics.PATCH,
) -> Basis:
    """Craig-Bampton (1968): constraint modes -K_ii^-1 K_ib and fixed-interface modes; the
    constraint modes of massless retained nodes split (module doc, ``statics_kind``).

    b = the retained nodes' DOFs, i = the other DOFs not in the reference condition.
    K_ii is factored once (fe.modes.spd_solver) and that factor serves the constraint modes
    (all columns in one solve) and, as OPinv of the shift-invert eigen solve about
    sigma = 0, the fixed-interface modes.
    """
    b = node_dofs(nodes)
    interior = np.setdiff1d(reference.free_dofs(fe.n_dof), b)
    k_rows = fe.K[interior]
    k_ii, k_ib = k_rows[:, interior], k_rows[:, b]
    with solver_pool() as pool:
        solve = spd_solver(k_ii, pool)
        statics = -solve(k_ib.toarray())
        modes, freqs = fixed_interface_modes(fe, interior, k_ii, solve, n_modes)
    massless = np.flatnonzero(massless_mask(fe, nodes))
    split = node_dofs(massless)  # columns of massless nodes
    fields = statics[:, split]
    if statics_kind is MasslessStatics.PATCH and massless.size:
        fields = fields @ massless_patterns(fe.mesh.nodes[nodes[massless]])
    extra = static_columns(fe, interior, fields)
    statics[:, split] = 0.0
    psi = np.zeros((fe.n_dof, b.size + extra.shape[1] + n_modes))
    psi[b, np.arange(b.size)] = 1.0
    psi[interior, : b.size] = statics
    psi[interior, b.size : b.size + extra.shape[1]] = extra
    psi[interior, b.size + extra.shape[1] :] = modes
    return Basis(ModelKind.MVM, psi, nodes, n_modes, reference, freqs)


def massless_mask(fe: FEModel, nodes: np.ndarray) -> np.ndarray:
    """(len(nodes),) bool: the nodes whose rows of the scalar mass matrix are zero."""
    m = sp.csr_matrix(fe.M_scalar)
    return np.asarray(abs(m).sum(axis=1)).ravel()[nodes] == 0.0


#: massless_patterns: axisymmetric normal displacements rho^0, rho^2, rho^4, rho^6 (a Hertz
#: patch and its growth), radial rho and rho^3 (Poisson's expansion of the face).
PATCH_NORMAL_POWERS = (0, 2, 4, 6)
PATCH_RADIAL_POWERS = (1, 3)


def massless_patterns(X: np.ndarray) -> np.ndarray:
    """(3 n, 11) smooth displacement patterns of the n nodes X (n, 3) (DOFs node-major, as
    node_dofs): about their centroid, with n the principal axis of least spread (the normal
    of a face or cap) and t1, t2 the others, rho the in-plane distance over its largest value
    and phi its angle: along n, rho^k for k in PATCH_NORMAL_POWERS and the tilts rho cos phi,
    rho sin phi; in the plane, rho^k e_rho for k in PATCH_RADIAL_POWERS, the slides t1, t2 and
    the twist rho e_phi. A contact patch on the nodes, axial (the seed case) or oblique,
    deforms them along these; their interior static fields span the massless nodes' static
    columns in MasslessStatics.PATCH. Patterns that vanish on the nodes (one node: all but the
    normal and the slides) give columns of no mass, dropped by static_columns."""
    X = np.asarray(X, dtype=float)
    d = X - X.mean(axis=0)
    _, vecs = np.linalg.eigh(d.T @ d)
    n, t1, t2 = vecs[:, 0], vecs[:, 1], vecs[:, 2]
    s1, s2 = d @ t1, d @ t2
    rho = np.hypot(s1, s2)
    top = rho.max()
    rho, c, s = (
        (rho / top, s1 / top, s2 / top)
        if top > 0
        else (rho, np.zeros_like(rho), np.zeros_like(rho))
    )
    e_rho = np.outer(c, t1) + np.outer(s, t2)  # rho e_rho
    e_phi = np.outer(-s, t1) + np.outer(c, t2)  # rho e_phi
    fields = [np.outer(rho**k, n) for k in PATCH_NORMAL_POWERS]
    fields += [np.outer(c, n), np.outer(s, n)]
    fields += [e_rho * rho[:, None] ** (k - 1) for k in PATCH_RADIAL_POWERS]
    fields += [np.tile(t1, (len(X), 1)), np.tile(t2, (len(X), 1)), e_phi]
    return np.column_stack([f.ravel() for f in fields])


def static_columns(fe: FEModel, interior: np.ndarray, fields: np.ndarray) -> np.ndarray:
    """An M-orthonormal basis (interior rows) of the span of ``fields``, the interior static
    fields of the massless retained nodes; directions of relative mass below 1e-12 of the
    largest are dropped (a node whose neighbours are all retained has a zero field)."""
    if not fields.shape[1]:
        return fields
    gram = fields.T @ (fe.M[interior][:, interior] @ fields)
    w, v = np.linalg.eigh(0.5 * (gram + gram.T))
    keep = w > 1e-12 * max(w.max(), 0.0)
    return fields @ (v[:, keep] / np.sqrt(w[keep]))


def fixed_interface_modes(
    fe: FEModel, interior: np.ndarray, k_ii, solve, n_modes: int
) -> tuple[np.ndarray, np.ndarray]:
    """First n_modes modes of the interior DOFs with all others held: (phi (len(interior),
    n_modes) M-normalised, frequencies (n_modes,) [Hz]); shift-invert about 0 with `solve`,
    the factor of k_ii. n_modes = 0 gives empty arrays."""
    if not n_modes:
        return np.zeros((interior.size, 0)), np.zeros(0)
    m_ii = fe.M[interior][:, interior]
    lam, phi = shift_invert_modes(m_ii, k_ii, n_modes, 0.0, solve=solve)
    return phi, to_hz(lam)
