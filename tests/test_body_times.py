"""Rows.body_times multiplies only the rows of a sparse psi its nodal selector reads
(constraints/rows.py). A contact's rows on an mvm-sparse body read the basis at a few nodes; the
whole psi @ Y read every exterior row of the basis (0.69 s a call, 2.2 s a step on the
274k-DOF plate with a 2,892-column corner) though the rows then kept only a handful."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from flexmvm.constraints.rows import Rows


class _NoWholeProduct(sp.csr_matrix):
    """A psi whose whole product is refused: only its rows may be taken."""

    def __matmul__(self, other):
        raise AssertionError("psi multiplied whole")

    def dot(self, other):
        raise AssertionError("psi multiplied whole")


def _rows_and_psi(seed: int = 7):
    """4 contact rows on body 1 (psi: 300 DOFs x 40 coordinates, its last 200 rows dense as an
    mvm-sparse body's exterior), each row 3 to 9 nodal entries."""
    rng = np.random.default_rng(seed)
    n_dofs, nq = 300, 40
    dense = sp.csr_matrix(rng.standard_normal((200, nq)))
    ident = sp.eye(100, nq, format="csr")
    psi = sp.vstack([ident, dense], format="csr")
    rows = Rows(4)
    for r in range(4):
        dofs = np.sort(rng.choice(n_dofs, size=3 * (r % 3 + 1), replace=False))
        values = rng.standard_normal(dofs.size)
        elastic = values @ psi[dofs].toarray()
        rows.add(r, 1, rng.standard_normal(6), elastic, nq, nodal=(dofs, values, n_dofs))
    return rows, psi, rng.standard_normal((6 + nq, 5))


def test_body_times_reads_only_the_selected_rows():
    """Equal to the rows' dense block times Y (the elastic block is values^T psi[dofs]: the
    same numbers by another order of sums, so to round-off of their size), without psi @ Y
    whole (which failed here before)."""
    rows, psi, Y = _rows_and_psi()
    bf, bq = rows.blocks[1]
    expected = bf @ Y[:6] + bq @ Y[6:]
    guarded = _NoWholeProduct(psi)
    got = rows.body_times(1, Y, guarded)
    assert got.shape == (4, 5)
    assert np.allclose(got, expected, rtol=0, atol=1e-12 * np.abs(expected).max())


def test_body_times_is_the_selector_times_psi_y_bit_for_bit():
    """The same sums in the same order as N @ (psi @ Y): a run's histories do not move."""
    rows, psi, Y = _rows_and_psi(11)
    bf, _ = rows.blocks[1]
    n = rows.nodal_selector(1)
    whole = bf @ Y[:6] + n @ np.asarray(psi @ Y[6:])
    assert np.array_equal(rows.body_times(1, Y, psi), whole)
