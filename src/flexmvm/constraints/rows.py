"""Rows of the constraint Jacobian Phi_v (seed eq. 9-11), stored per body.

A block of m rows holds, for each body it touches, a frame part (m, 6) acting on
[r_dot, omega] and an elastic part (m, nq) acting on q_dot. Dense arrays: m is small.
Rows built from nodal directions (contact) may also carry, per body, the sparse nodal
selector N (m, 3 n_nodes) with elastic part = N psi: the integrator then applies W_qq^-1 to
psi^T N^T through cached nodal columns instead of one back-substitution per row.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp


@dataclass
class Rows:
    """m rows of Phi_v: blocks[body_index] = (frame (m, 6), elastic (m, nq))."""

    m: int
    blocks: dict[int, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    nodal: dict[int, sp.csr_matrix] = field(default_factory=dict)

    @classmethod
    def empty(cls) -> Rows:
        return cls(0, {})

    def add(self, row: int, body: int, frame: np.ndarray, elastic: np.ndarray, nq: int) -> None:
        """Add frame (6,) and elastic (nq,) contributions of one body to row `row`."""
        if body not in self.blocks:
            self.blocks[body] = (np.zeros((self.m, 6)), np.zeros((self.m, nq)))
        bf, bq = self.blocks[body]
        bf[row] += frame
        if nq:
            bq[row] += elastic

    def times(self, velocities: list[np.ndarray]) -> np.ndarray:
        """Phi_v v (m,) for the list of per-body velocity vectors."""
        out = np.zeros(self.m)
        for b, (bf, bq) in self.blocks.items():
            v = velocities[b]
            out += bf @ v[:6]
            if bq.shape[1]:
                out += bq @ v[6:]
        return out

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
    # nodal selectors survive only if every part touching the body has one
    for b in out.blocks:
        sels = [p.nodal.get(b) for p in parts if b in p.blocks]
        if all(s is not None for s in sels):
            n = sels[0].shape[1]
            blocks = [p.nodal[b] if b in p.blocks else sp.csr_matrix((p.m, n)) for p in parts]
            out.nodal[b] = sp.vstack(blocks, format="csr")
    return out
