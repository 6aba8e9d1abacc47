"""Constraint rows and a body's coordinates: the generalized impulse Phi_b^T lambda of a
body, the step's contact rows merged over the contact providers (and their impulses handed
back to them), and matrix @ vector as a flat array for dense and sparse matrices alike."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from flexmvm.constraints.contact import ContactRows, FrictionRows
from flexmvm.constraints.rows import Rows, stack
from flexmvm.errors import SolverError

if TYPE_CHECKING:
    from flexmvm.integrate.state import BodyState
    from flexmvm.integrate.system import System


def body_impulse(rows: Rows, b: int, body, lam: np.ndarray) -> np.ndarray:
    """Phi_b^T lam (6 + nq,) for body b's part Phi_b = [bf, bq] of rows: with a nodal
    selector N and a sparse basis (full FE) bq^T lam = psi^T (N^T lam), a few nodes' worth,
    instead of a product with the dense (m, nq) block."""
    bf, bq = rows.blocks[b]
    sel = rows.nodal_selector(b) if body.is_sparse else None
    if sel is None:
        elastic = bq.T @ lam
    elif body.nodal is not None:
        # psi selects DOFs: psi^T y = y at each coordinate's DOF; N^T lam summed entry by
        # entry in row order (as the transposed product does) from N's CSR arrays (a
        # NodalSelector's or a csr matrix's), no transposed matrices made
        nt_lam = np.bincount(
            sel.indices,
            weights=sel.data * np.repeat(lam, np.diff(sel.indptr)),
            minlength=sel.shape[1],
        )
        elastic = nt_lam[body.nodal.dof]
    else:
        # (N psi)^T lam: the rows of psi at the selected DOFs only (a ring basis's psi holds
        # dense exterior rows that N never touches)
        elastic = np.asarray((sel.tocsr() @ body.psi).T @ lam).ravel()
    return np.concatenate([bf.T @ lam, elastic])


def flat_product(matrix, x: np.ndarray) -> np.ndarray:
    """matrix @ x as a flat (n,) array, for dense or sparse matrices."""
    return np.asarray(matrix @ x).ravel()


def merge_contacts(a: ContactRows, b: ContactRows) -> ContactRows:
    """The rows of a followed by those of b (one set of contact rows for the step's LCP)."""
    if a.rows.m == 0:
        return b
    if b.rows.m == 0:
        return a
    if a.n_eq or b.n_eq:
        raise SolverError("several bonded contact definitions are not supported in one system")
    wa = a.normal_weight if a.normal_weight is not None else np.ones(a.rows.m)
    wb = b.normal_weight if b.normal_weight is not None else np.ones(b.rows.m)
    friction = None
    if a.friction is not None or b.friction is not None:
        parts = [
            f
            for f in (a.friction, b.friction.shifted(a.rows.m) if b.friction else None)
            if f is not None
        ]
        friction = FrictionRows(
            np.concatenate([f.normal for f in parts]),
            np.concatenate([f.tangent for f in parts]),
            np.concatenate([f.mu for f in parts]),
            np.concatenate([f.directions for f in parts]),
        )
    return ContactRows(
        stack([a.rows, b.rows]),
        np.concatenate([a.lower, b.lower]),
        a.keys + b.keys,
        np.concatenate([a.gaps, b.gaps]),
        0,
        np.concatenate([wa, wb]),
        friction,
    )


def candidate_rows(system: System, states: list[BodyState], h: float):
    """The step's contact rows (all providers merged) and per provider (provider, its
    rows, their offset)."""
    crows = ContactRows.empty()
    parts = []
    for provider in system.contacts:
        part = provider.candidate_rows(system.bodies, states, h)
        parts.append((provider, part, crows.rows.m))
        crows = merge_contacts(crows, part)
    return crows, parts


def after_step(parts, lam_c: np.ndarray, h: float) -> None:
    """Each provider's share of the accepted contact impulses lam_c (candidate_rows' parts)."""
    for provider, part, offset in parts:
        provider.after_step(part, lam_c[offset : offset + part.rows.m], h)
