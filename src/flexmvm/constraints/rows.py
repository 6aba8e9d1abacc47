"""Rows of the constraint Jacobian Phi_v (seed eq. 9-11), stored per body.

A block of m rows holds, for each body it touches, a frame part (m, 6) acting on
[r_dot, omega] and an elastic part (m, nq) acting on q_dot. Dense arrays: m is small.
Rows built from nodal directions (contact) may also carry, per body, the sparse nodal
selector N (m, 3 n_nodes) with elastic part = N psi: the integrator then applies W_qq^-1 to
psi^T N^T through cached nodal columns instead of one back-substitution per row. The
selector is a scipy CSR matrix, or (contact rows, made every step) a NodalSelector: the same
CSR arrays without the scipy object, which the nodal columns read directly
(integrate.moreau_jean.compliance.NodalColumns.touch).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp


class NodalSelector:
    """A nodal selector N (shape (m, n_dofs)) as CSR arrays: row a holds the columns
    indices[indptr[a]:indptr[a + 1]] (ascending, repeats allowed: they add) with the values
    data[...]. Not copied: the arrays are the caller's and are not written afterwards.
    Anything else than the nodal columns reads it as the scipy matrix of these arrays
    (tocsr, made once on first use; `N @ x` goes through it)."""

    __slots__ = ("_csr", "data", "indices", "indptr", "shape")

    def __init__(
        self, data: np.ndarray, indices: np.ndarray, indptr: np.ndarray, shape: tuple[int, int]
    ):
        self.data, self.indices, self.indptr = data, indices, indptr
        self.shape = (int(shape[0]), int(shape[1]))
        self._csr = None

    def tocsr(self) -> sp.csr_matrix:
        """The scipy CSR matrix of these arrays (as it was built before there was this class)."""
        if self._csr is None:
            self._csr = sp.csr_matrix((self.data, self.indices, self.indptr), shape=self.shape)
        return self._csr

    def toarray(self) -> np.ndarray:
        return self.tocsr().toarray()

    def __matmul__(self, other):
        return self.tocsr() @ other


@dataclass
class Rows:
    """m rows of Phi_v: blocks[body_index] = (frame (m, 6), elastic (m, nq))."""

    m: int
    blocks: dict[int, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    nodal: dict[int, sp.csr_matrix | NodalSelector] = field(default_factory=dict)
    # rows built by add(..., nodal=...): per body the selector's entries (row, dofs, values)
    # and its column count, or None once an elastic part came without them
    _entries: dict[int, tuple[list, int] | None] = field(default_factory=dict, repr=False)

    @classmethod
    def empty(cls) -> Rows:
        return cls(0, {})

    def add(
        self,
        row: int,
        body: int,
        frame: np.ndarray,
        elastic: np.ndarray,
        nq: int,
        nodal: tuple[np.ndarray, np.ndarray, int] | None = None,
    ) -> None:
        """Add frame (6,) and elastic (nq,) contributions of one body to row `row`. nodal =
        (dofs, values, n_dofs): the elastic part is values^T psi[dofs] (empty dofs: none);
        rows whose every contribution to a body says so get its nodal selector (nodal_selector)."""
        if body not in self.blocks:
            self.blocks[body] = (np.zeros((self.m, 6)), np.zeros((self.m, nq)))
        bf, bq = self.blocks[body]
        bf[row] += frame
        if nq:
            bq[row] += elastic
        known = self._entries.get(body, ([], 0))
        # a rigid body (nodal n_dofs = 0) gets no selector: nothing reads an (m, 0) one, and
        # building it at every joint evaluation cost most of a rigid mechanism's step
        if nodal is None or known is None or not nodal[2]:
            self._entries[body] = None
        else:
            dofs, values, n_dofs = nodal
            known[0].append((row, np.asarray(dofs, np.int64), np.asarray(values, float)))
            self._entries[body] = (known[0], n_dofs)

    def add_block(
        self,
        row0: int,
        body: int,
        frame: np.ndarray,
        elastic: np.ndarray | None,
        nq: int,
        nodal: list[tuple[np.ndarray, np.ndarray, int]] | None = None,
    ) -> None:
        """add() of the k rows row0 .. row0 + k - 1 at once: frame (k, 6), elastic (k, nq)
        (None: zero), nodal one (dofs, values, n_dofs) per row or None, as add's. The same
        sums as k calls of add (each entry gets its terms in the order of the calls), without
        their per-row Python (a mechanism's joints add ~30 rows per Newton iterate)."""
        k = frame.shape[0]
        if k == 0:  # no rows: nothing added, as no call of add
            return
        if body not in self.blocks:
            self.blocks[body] = (np.zeros((self.m, 6)), np.zeros((self.m, nq)))
        bf, bq = self.blocks[body]
        bf[row0 : row0 + k] += frame
        if nq and elastic is not None:
            bq[row0 : row0 + k] += elastic
        known = self._entries.get(body, ([], 0))
        if nodal is None or known is None or not nodal[0][2]:
            self._entries[body] = None
            return
        for i, (dofs, values, _) in enumerate(nodal):
            known[0].append((row0 + i, np.asarray(dofs, np.int64), np.asarray(values, float)))
        self._entries[body] = (known[0], nodal[0][2])

    def nodal_selector(self, b: int) -> sp.csr_matrix | NodalSelector | None:
        """The nodal selector N (m, n_dofs) of body b (elastic part = N psi), or None."""
        sel = self.nodal.get(b)
        if sel is None and self._entries.get(b) is not None and b in self.blocks:
            entries, n_dofs = self._entries[b]  # type: ignore[misc]  # checked above
            empty = np.zeros(0)
            rows = np.concatenate([np.full(len(d), r) for r, d, _ in entries] or [empty])
            cols = np.concatenate([d for _, d, _ in entries] or [empty]).astype(np.int64)
            vals = np.concatenate([v for _, _, v in entries] or [empty])
            sel = sp.csr_matrix((vals, (rows.astype(np.int64), cols)), shape=(self.m, n_dofs))
            sel.sum_duplicates()
            self.nodal[b] = sel
        return sel

    def times(self, velocities: list[np.ndarray]) -> np.ndarray:
        """Phi_v v (m,) for the list of per-body velocity vectors."""
        out = np.zeros(self.m)
        for b, (bf, bq) in self.blocks.items():
            v = velocities[b]
            out += bf @ v[:6]
            if bq.shape[1]:
                out += bq @ v[6:]
        return out

    def body_times(self, b: int, Y: np.ndarray, psi) -> np.ndarray:
        """Phi_b Y (m, p) for Y (6 + nq, p): Phi_b = [Phi_f, N psi] through body b's nodal
        selector N when it has one and psi (3 n_nodes, nq) is sparse (a full FE body: its
        dense (m, nq) block would be stacked and multiplied, ~0.1 GB and 0.2 GFlop for 460
        contact rows on a 37,000-DOF part), else the block times Y. Only the rows of psi that
        N reads are multiplied (psi @ Y whole read every exterior row of an mvm-sparse body:
        0.69 s a call on the 274k-DOF plate with a 2,892-column corner); the same sums, in the
        same order, as N @ (psi @ Y)."""
        bf, bq = self.blocks[b]
        sel = self.nodal_selector(b) if sp.issparse(psi) and bq.shape[1] else None
        if sel is None:
            return bf @ Y[:6] + bq @ Y[6:]
        n = sel.tocsr() if isinstance(sel, NodalSelector) else sp.csr_matrix(sel)
        read = np.unique(n.indices)  # the DOFs the rows touch, ascending
        compact = sp.csr_matrix(
            (n.data, np.searchsorted(read, n.indices), n.indptr), shape=(n.shape[0], read.size)
        )
        return bf @ Y[:6] + compact @ np.asarray(sp.csr_matrix(psi)[read] @ Y[6:])

    def body_matrix(self, b: int) -> np.ndarray | None:
        """The rows of body b as one (m, 6 + nq) matrix, or None."""
        blk = self.blocks.get(b)
        if blk is None:
            return None
        return np.hstack(blk)


def stack(parts: list[Rows]) -> Rows:
    """Concatenate row blocks (in order)."""
    m = sum(p.m for p in parts)
    out = Rows(m, {})
    start = 0
    for p in parts:
        for b, (bf, bq) in p.blocks.items():
            if b not in out.blocks:
                out.blocks[b] = (np.zeros((m, 6)), np.zeros((m, bq.shape[1])))
            out.blocks[b][0][start : start + p.m] = bf
            out.blocks[b][1][start : start + p.m] = bq
        start += p.m
    # nodal selectors survive only if every part touching the body has one (checked before
    # any is built: a mechanism's joint rows built, per iterate, the selectors of rows that
    # other parts then left without one)
    for b in out.blocks:
        touching = [p for p in parts if b in p.blocks]
        if not all(b in p.nodal or p._entries.get(b) is not None for p in touching):
            continue
        sels = [p.nodal_selector(b) for p in touching]
        if all(s is not None for s in sels):
            n = sels[0].shape[1]  # type: ignore[union-attr]  # none is None
            blocks = [
                p.nodal[b].tocsr() if b in p.blocks else sp.csr_matrix((p.m, n)) for p in parts
            ]
            out.nodal[b] = sp.vstack(blocks, format="csr")
    return out
