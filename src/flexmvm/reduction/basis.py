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
step ends (integrate/massless.py). Without the split a constraint mode drags interior mass
along and the redistribution leaves the retained contact coordinates massive.

Every Psi has zero rows at the reference DOFs (ReferenceCondition), so q carries no
rigid-body motion. The reduced matrices are m_hat = Psi^T M Psi, k_hat = Psi^T K Psi
(seed eq. 5; Wang, Hong, Liu 2014).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np
import scipy.sparse as sp
from threadpoolctl import threadpool_limits

from flexmvm.errors import InputError
from flexmvm.fe.assembly import FEModel
from flexmvm.fe.modes import (
    constrained_modes,
    shift_invert_modes,
    solver_pool,
    spd_solver,
    to_hz,
)
from flexmvm.reduction.interface import InterfaceSources, InterfaceSpec, interface_columns
from flexmvm.reduction.reference import ReferenceCondition


class BasisKind(Enum):
    """Which reduction basis; values are the names used in scenarios and studies."""

    FULL = "full"  # reference FE model: every free nodal DOF
    CRAIG_BAMPTON = "mvm"  # default MVM: retained nodes + fixed-interface modes
    SEED_BLOCK = "mvm-seed"  # seed eq. (4): whole-body modes on region I, nodes on II
    SEED_FIXED = "mvm-seed-fixed"  # seed eq. (4): region-I modes with region II held, nodes on II
    MODAL = "modal"  # first N modes of the reference-supported body
    INTERFACE = "interface"  # contact-patch Ritz vectors + modes by participation


class MasslessStatics(Enum):
    """The static columns of the massless retained nodes of a Craig-Bampton basis."""

    ALL = "all"  # every massless DOF's interior static field: span contains Craig-Bampton's
    PATCH = "patch"  # the static fields of massless_patterns: a few columns per body


@dataclass(frozen=True)
class Basis:
    """A reduction basis of one body.

    psi: (3n, nq) ndarray (csr for FULL); u = psi @ q [m]; reference DOF rows are zero.
    retained_nodes: (nb,) region-II node ids, in column order (FULL: every node not in the
    reference condition; MODAL: empty). n_modes: number of modal columns.
    mode_freqs_hz: (n_modes,) frequencies [Hz] of the modes in the modal columns.
    """

    kind: BasisKind
    psi: np.ndarray | sp.csr_matrix
    retained_nodes: np.ndarray
    n_modes: int
    reference: ReferenceCondition
    mode_freqs_hz: np.ndarray

    @property
    def nq(self) -> int:
        """Number of generalised elastic coordinates."""
        return int(self.psi.shape[1])

    @property
    def n_static(self) -> int:
        """Static columns of the massless retained nodes (CRAIG_BAMPTON: between the retained
        nodes' columns and the modal ones; 0 for the other kinds)."""
        if self.kind is not BasisKind.CRAIG_BAMPTON:
            return 0
        return self.nq - 3 * self.retained_nodes.size - self.n_modes

    def retained_columns(self) -> np.ndarray:
        """Columns of psi holding the x, y, z displacement of each retained node, (nb, 3).

        For FULL, a reference node's clamped components have no column and do not appear
        (such nodes are not retained). CRAIG_BAMPTON: 0..3nb-1; SEED_BLOCK and
        SEED_FIXED: after the modes.
        """
        nb = len(self.retained_nodes)
        if self.kind is BasisKind.FULL:
            free = self.reference.free_dofs(self.psi.shape[0])
            dofs = 3 * self.retained_nodes[:, None] + np.arange(3)
            return np.searchsorted(free, dofs)
        first = self.n_modes if self.kind in (BasisKind.SEED_BLOCK, BasisKind.SEED_FIXED) else 0
        return first + np.arange(3 * nb).reshape(nb, 3)


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


def _node_dofs(nodes: np.ndarray) -> np.ndarray:
    """DOF ids 3k + d, node-major in the given node order, (3 len(nodes),)."""
    return (3 * nodes[:, None] + np.arange(3)).ravel()


def _full(fe: FEModel, reference: ReferenceCondition) -> Basis:
    free = reference.free_dofs(fe.n_dof)
    psi = sp.csr_matrix(
        (np.ones(free.size), (free, np.arange(free.size))), shape=(fe.n_dof, free.size)
    )
    nodes = np.setdiff1d(np.arange(fe.mesh.n_nodes), reference.nodes)
    return Basis(BasisKind.FULL, psi, nodes, 0, reference, np.zeros(0))


def _craig_bampton(
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
    b = _node_dofs(nodes)
    interior = np.setdiff1d(reference.free_dofs(fe.n_dof), b)
    k_rows = fe.K[interior]
    k_ii, k_ib = k_rows[:, interior], k_rows[:, b]
    with solver_pool() as pool:
        solve = spd_solver(k_ii, pool)
        statics = -solve(k_ib.toarray())
        modes, freqs = _fixed_interface_modes(fe, interior, k_ii, solve, n_modes)
    massless = np.flatnonzero(_massless(fe, nodes))
    split = _node_dofs(massless)  # columns of massless nodes
    fields = statics[:, split]
    if statics_kind is MasslessStatics.PATCH and massless.size:
        fields = fields @ massless_patterns(fe.mesh.nodes[nodes[massless]])
    extra = _static_columns(fe, interior, fields)
    statics[:, split] = 0.0
    psi = np.zeros((fe.n_dof, b.size + extra.shape[1] + n_modes))
    psi[b, np.arange(b.size)] = 1.0
    psi[interior, : b.size] = statics
    psi[interior, b.size : b.size + extra.shape[1]] = extra
    psi[interior, b.size + extra.shape[1] :] = modes
    return Basis(BasisKind.CRAIG_BAMPTON, psi, nodes, n_modes, reference, freqs)


def _massless(fe: FEModel, nodes: np.ndarray) -> np.ndarray:
    """(len(nodes),) bool: the nodes whose rows of the scalar mass matrix are zero."""
    m = sp.csr_matrix(fe.M_scalar)
    return np.asarray(abs(m).sum(axis=1)).ravel()[nodes] == 0.0


#: massless_patterns: axisymmetric normal displacements rho^0, rho^2, rho^4, rho^6 (a Hertz
#: patch and its growth), radial rho and rho^3 (Poisson's expansion of the face).
PATCH_NORMAL_POWERS = (0, 2, 4, 6)
PATCH_RADIAL_POWERS = (1, 3)


def massless_patterns(X: np.ndarray) -> np.ndarray:
    """(3 n, 11) smooth displacement patterns of the n nodes X (n, 3) (DOFs node-major, as
    _node_dofs): about their centroid, with n the principal axis of least spread (the normal
    of a face or cap) and t1, t2 the others, rho the in-plane distance over its largest value
    and phi its angle: along n, rho^k for k in PATCH_NORMAL_POWERS and the tilts rho cos phi,
    rho sin phi; in the plane, rho^k e_rho for k in PATCH_RADIAL_POWERS, the slides t1, t2 and
    the twist rho e_phi. A contact patch on the nodes, axial (the seed case) or oblique,
    deforms them along these; their interior static fields span the massless nodes' static
    columns in MasslessStatics.PATCH. Patterns that vanish on the nodes (one node: all but the
    normal and the slides) give columns of no mass, dropped by _static_columns."""
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


def _static_columns(fe: FEModel, interior: np.ndarray, fields: np.ndarray) -> np.ndarray:
    """An M-orthonormal basis (interior rows) of the span of ``fields``, the interior static
    fields of the massless retained nodes; directions of relative mass below 1e-12 of the
    largest are dropped (a node whose neighbours are all retained has a zero field)."""
    if not fields.shape[1]:
        return fields
    gram = fields.T @ (fe.M[interior][:, interior] @ fields)
    w, v = np.linalg.eigh(0.5 * (gram + gram.T))
    keep = w > 1e-12 * max(w.max(), 0.0)
    return fields @ (v[:, keep] / np.sqrt(w[keep]))


def _fixed_interface_modes(
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


def _seed_block(
    fe: FEModel, reference: ReferenceCondition, nodes: np.ndarray, n_modes: int
) -> Basis:
    """Seed eq. (4): T = diag(Psi_I, I_II).

    Choice made here: Psi_I = the first n_modes modes of the whole body supported by the
    reference condition, with their region-II rows set to zero (restricted to region I);
    region-II DOFs keep their nodal coordinates. Columns: the modes, then the retained
    nodes' x, y, z.
    """
    b = _node_dofs(nodes)
    psi = np.zeros((fe.n_dof, n_modes + b.size))
    freqs = np.zeros(0)
    if n_modes:
        freqs, phi = constrained_modes(fe.M, fe.K, reference.fixed_dofs, n_modes)
        phi[b] = 0.0
        psi[:, :n_modes] = phi
    psi[b, n_modes + np.arange(b.size)] = 1.0
    return Basis(BasisKind.SEED_BLOCK, psi, nodes, n_modes, reference, freqs)


def _seed_fixed(
    fe: FEModel, reference: ReferenceCondition, nodes: np.ndarray, n_modes: int
) -> Basis:
    """Seed eq. (4), T = diag(Psi_I, I_II), the other reading: Psi_I = the first n_modes
    modes of region I with the region-II DOFs (and the reference DOFs) held, i.e. the
    fixed-interface modes of Craig-Bampton without its static constraint modes. A region-II
    node moving alone leaves its region-I neighbours in place (the modes vanish at it).
    Columns: the modes, then the retained nodes' x, y, z (as SEED_BLOCK).
    """
    b = _node_dofs(nodes)
    interior = np.setdiff1d(reference.free_dofs(fe.n_dof), b)
    psi = np.zeros((fe.n_dof, n_modes + b.size))
    freqs = np.zeros(0)
    if n_modes:
        k_ii = fe.K[interior][:, interior]
        with solver_pool() as pool:
            psi[interior, :n_modes], freqs = _fixed_interface_modes(
                fe, interior, k_ii, spd_solver(k_ii, pool), n_modes
            )
    psi[b, n_modes + np.arange(b.size)] = 1.0
    return Basis(BasisKind.SEED_FIXED, psi, nodes, n_modes, reference, freqs)


def _modal(fe: FEModel, reference: ReferenceCondition, n_modes: int) -> Basis:
    freqs, phi = constrained_modes(fe.M, fe.K, reference.fixed_dofs, n_modes)
    return Basis(BasisKind.MODAL, phi, np.zeros(0, dtype=np.int64), n_modes, reference, freqs)


def _interface(
    fe: FEModel,
    reference: ReferenceCondition,
    spec: InterfaceSpec | None,
    n_modes: int,
    sources: InterfaceSources | None,
) -> Basis:
    if not isinstance(spec, InterfaceSpec):
        raise InputError(f"an interface basis needs an InterfaceSpec, got {spec!r}")
    cols = interface_columns(fe, reference, spec, n_modes, sources)
    return Basis(
        BasisKind.INTERFACE,
        cols.psi,
        np.zeros(0, dtype=np.int64),
        n_modes,
        reference,
        cols.mode_freqs_hz,
    )


def build_basis(
    fe: FEModel,
    kind: BasisKind,
    reference: ReferenceCondition,
    retained_nodes=(),
    n_modes: int = 0,
    interface: InterfaceSpec | None = None,
    sources: InterfaceSources | None = None,
    massless_statics: MasslessStatics = MasslessStatics.PATCH,
) -> Basis:
    """Build the basis ``kind`` of body ``fe`` (see the module table).

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
    if reference.fixed_dofs.max() >= fe.n_dof:
        raise InputError(f"reference DOFs {reference.fixed_dofs.tolist()} exceed {fe.n_dof} DOFs")
    nodes = _retained(fe, reference, retained_nodes)
    if kind in (BasisKind.FULL, BasisKind.MODAL, BasisKind.INTERFACE) and nodes.size:
        raise InputError(f"a {kind.value} basis takes no retained nodes, got {nodes.size}")
    if (
        kind in (BasisKind.CRAIG_BAMPTON, BasisKind.SEED_BLOCK, BasisKind.SEED_FIXED)
        and not nodes.size
    ):
        raise InputError(f"a {kind.value} basis needs at least one retained node, got none")
    if kind is BasisKind.FULL:
        if n_modes:
            raise InputError(f"a full basis takes no modes, got n_modes={n_modes}")
        return _full(fe, reference)
    if kind is BasisKind.MODAL and n_modes < 1:
        raise InputError("a modal basis needs n_modes >= 1, got 0")
    # One BLAS thread: SuperLU's many-right-hand-side solve calls BLAS once per supernode;
    # threaded OpenBLAS there is no faster on idle cores and ~10x slower when other jobs share
    # them (docs/notes/2026-11-27-comment-measurements.md).
    with threadpool_limits(limits=1, user_api="blas"):
        if kind is BasisKind.MODAL:
            return _modal(fe, reference, int(n_modes))
        if kind is BasisKind.INTERFACE:
            return _interface(fe, reference, interface, int(n_modes), sources)
        if kind is BasisKind.CRAIG_BAMPTON:
            return _craig_bampton(
                fe, reference, nodes, int(n_modes), MasslessStatics(massless_statics)
            )
        if kind is BasisKind.SEED_FIXED:
            return _seed_fixed(fe, reference, nodes, int(n_modes))
        return _seed_block(fe, reference, nodes, int(n_modes))


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


__all__ = ["Basis", "BasisKind", "build_basis", "reduced_matrices"]
