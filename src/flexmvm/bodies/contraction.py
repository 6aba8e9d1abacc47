"""The G2 contractions of a dense (reduced) basis in one pass over half of the G2 blocks.

L(x)[a, b] = G2[b][a] x (bodies.body.FlexibleBody.contractions) takes the nine (nq, nq)
blocks G2[a][b] = P_a^T M_s P_b (Shabana, "Dynamics of Multibody Systems", ch. 5: the inertia
shape integrals S_ab). Only six are distinct: G2[b][a] = G2[a][b]^T (bodies.invariants makes
them so), and G2[a][a] is symmetric. So a pass reads the three upper triangles of G2[a][a] and
the three blocks G2[a][b], a < b, once, and gets from each off-diagonal block both G2[a][b] x
(by rows) and G2[b][a] x = G2[a][b]^T x (by columns): 4.5 nq^2 numbers read instead of the
9 nq^2 of the stacked product (b1 of the seed case, nq = 553: 11 MB instead of 22 MB per
contraction, one per body and step). The diagonal blocks are symmetrised, (G + G^T) / 2, when
packed: they are symmetric up to round-off of the product that made them.
"""

from __future__ import annotations

import numba
import numpy as np

_PAIRS = ((0, 1), (0, 2), (1, 2))


@numba.njit(nogil=True, cache=True, fastmath={"reassoc", "contract"})
def _rows_and_cols(G, i0, nr, j0, x, by_rows, by_cols):  # pragma: no cover - compiled
    """For the nr (<= 4) rows i0.. of G and its columns j0..: by_rows[i] += G[i, j0:] x[j0:]
    and by_cols[j0:] += G[i0:i0 + nr, j0:]^T x[i0:i0 + nr], reading each entry once (four
    rows at a time: the column update is one store per column for four rows)."""
    nq = x.shape[0]
    if nr == 4:
        x0, x1, x2, x3 = x[i0], x[i0 + 1], x[i0 + 2], x[i0 + 3]
        a0 = a1 = a2 = a3 = 0.0
        g0, g1, g2, g3 = G[i0], G[i0 + 1], G[i0 + 2], G[i0 + 3]
        for j in range(j0, nq):
            xj = x[j]
            a0 += g0[j] * xj
            a1 += g1[j] * xj
            a2 += g2[j] * xj
            a3 += g3[j] * xj
            by_cols[j] += g0[j] * x0 + g1[j] * x1 + g2[j] * x2 + g3[j] * x3
        by_rows[i0] += a0
        by_rows[i0 + 1] += a1
        by_rows[i0 + 2] += a2
        by_rows[i0 + 3] += a3
    else:
        for i in range(i0, i0 + nr):
            xi = x[i]
            g = G[i]
            acc = 0.0
            for j in range(j0, nq):
                acc += g[j] * x[j]
                by_cols[j] += g[j] * xi
            by_rows[i] += acc


@numba.njit(nogil=True, cache=True)
def _contract_diagonal(diag, off, x, out):  # pragma: no cover - compiled
    """The part of _contract that writes out[a, a] (the three symmetric blocks, upper
    triangles read) and out[1, 0], out[0, 1] (the block G2[0][1]): 2.5 nq^2 numbers read."""
    nq = x.shape[0]
    for a in range(3):
        D = diag[a]
        o = out[a, a]
        o[:] = 0.0
        for i0 in range(0, nq, 4):
            nr = min(4, nq - i0)
            # the nr x nr corner on and above the diagonal, then the columns right of it
            for i in range(i0, i0 + nr):
                o[i] += D[i, i] * x[i]
                for j in range(i + 1, i0 + nr):
                    o[i] += D[i, j] * x[j]
                    o[j] += D[i, j] * x[i]
            _rows_and_cols(D, i0, nr, i0 + nr, x, o, o)
    _off_diagonal(off, x, out, 0, 1)


@numba.njit(nogil=True, cache=True)
def _contract_rest(diag, off, x, out):  # pragma: no cover - compiled
    """The other part: out[2, 0], out[0, 2], out[2, 1], out[1, 2] (blocks G2[0][2], G2[1][2]):
    2 nq^2 numbers read. Disjoint from _contract_diagonal's outputs, so the two may run on
    two threads with the results of one, bit for bit."""
    _off_diagonal(off, x, out, 1, 3)


@numba.njit(nogil=True, cache=True)
def _off_diagonal(off, x, out, p0, p1):  # pragma: no cover - compiled
    nq = x.shape[0]
    for p in range(p0, p1):
        a = 0 if p < 2 else 1
        b = 1 if p == 0 else 2
        out[b, a][:] = 0.0
        out[a, b][:] = 0.0
        # L[b, a] = G2[a][b] x (by rows), L[a, b] = G2[b][a] x = G2[a][b]^T x (by columns)
        for i0 in range(0, nq, 4):
            _rows_and_cols(off[p], i0, min(4, nq - i0), 0, x, out[b, a], out[a, b])


def _contract(diag, off, x, out) -> None:
    """out (3, 3, nq) = L(x): diag (3, nq, nq) symmetric blocks (upper triangles read), off
    (3, nq, nq) the blocks G2[a][b] for (a, b) in _PAIRS."""
    _contract_diagonal(diag, off, x, out)
    _contract_rest(diag, off, x, out)


class G2Contraction:
    """Packed G2 blocks of a dense basis; `__call__(x)` -> L(x) (3, 3, nq)."""

    def __init__(self, G2):
        nq = np.asarray(G2[0][0]).shape[0]
        self.nq = nq
        self._diag = np.empty((3, nq, nq))
        for a in range(3):
            g = np.asarray(G2[a][a], float)
            self._diag[a] = 0.5 * (g + g.T)
        self._off = np.ascontiguousarray(np.stack([np.asarray(G2[a][b], float) for a, b in _PAIRS]))

    def __call__(self, x: np.ndarray, pool=None) -> np.ndarray:
        """L(x); with a thread pool (a concurrent.futures executor with a free worker) its
        two parts run on two threads (bit for bit the same; the pass is memory-bound, so two
        threads read the blocks faster than one: docs/notes/2026-11-27-comment-measurements.md)."""
        out = np.empty((3, 3, self.nq))
        x = np.ascontiguousarray(x, dtype=float)
        if pool is None:
            _contract(self._diag, self._off, x, out)
        else:
            job = pool.submit(_contract_rest, self._diag, self._off, x, out)
            _contract_diagonal(self._diag, self._off, x, out)
            job.result()
        return out
