"""Contact rows through W^-1 without forming W^-1 Phi^T: the compliance D and one velocity.

A contact row of a body is Phi = [Phi_f, N psi] (frame part (m, 6), elastic part = the sparse
nodal selector N (m, 3 n_nodes) times the basis psi (3 n_nodes, nq)). The contact needs only

    D  = Phi W^-1 Phi^T                 (m, m)       the LCP matrix
    dv = W^-1 Phi^T lambda              (6 + nq,)    the velocity correction

With the bordered form of W (body_solver) and y = W_qq^-1 psi^T N^T = C_d N_d^T, where C_d are
the cached nodal columns c_j = W_qq^-1 psi^T e_j of the DOFs d the rows touch and N_d the
selector restricted to them (m, n_d):

    M_fq~ y = [A (S1 C_d) ; M_w C_d] N_d^T                        (6, m)
    x_f     = S^-1 (Phi_f^T - M_fq~ y)                            (6, m), S the frame Schur
                                                                  complement (body_solver)
    D       = Phi_f x_f + N_d P_dd N_d^T - N_d (psi_d Z_r A^T x_f,r + psi_d Z_w x_f,w)
    dv      = [x_f lambda ; C_d N_d^T lambda - Z_r A^T (x_f lambda)_r - Z_w (x_f lambda)_w]

with P_dd = psi_d W_qq^-1 psi_d^T (n_d, n_d). Per cached column are kept S1 c_j, M_w c_j and
the rows psi_j Z_r, psi_j Z_w of Z at its DOF. By symmetry of W_qq the latter equal the former
to round-off, but both are kept so that every product is rounded as in the explicit columns:
S is nearly singular for a full FE body (~1e-5 of the mass, see iteration_matrix.py), and M_fq~ y must
be consistent with the S1 Z_r, M_w Z_w in S. The translational step (3 x 3 Schur complement,
frame rotation frozen) drops the M_w and Z_w terms. A step then costs small gathers and one
weighted sum of n_d cached columns instead of dense (nq, m) blocks.
"""

from __future__ import annotations

import numba
import numpy as np
import scipy.sparse as sp

from flexmvm.constraints.rows import NodalSelector
from flexmvm.integrate.moreau_jean.dense_solve import cho_solve, lu_solve


@numba.njit(cache=True)
def add_weighted_rows(cols, slots, w, out):  # pragma: no cover - compiled
    """out += sum_i w[i] cols[slots[i]] (cols (capacity, nq) C-ordered, out (nq,)); rows with
    w[i] = 0 are not read. One sequential stream per row (measured 2x faster than chunking
    out over the rows: the hardware prefetcher follows one stream, not fifty)."""
    for i in range(slots.shape[0]):
        wi = w[i]
        if wi != 0.0:
            row = cols[slots[i]]
            for j in range(out.shape[0]):
                out[j] += wi * row[j]


@numba.njit(cache=True)
def selector_columns(data, indices, indptr, slot_of):  # pragma: no cover - compiled
    """The DOFs a nodal selector in CSR arrays (m rows) touches, as NodalColumns.touch's
    scipy path finds them: dofs (n_d,) sorted and unique (explicit zeros included), their
    slots slot_of[dofs] (-1: not cached), N_d (m, n_d) with repeated columns of a row added in
    their order (scipy's sum_duplicates), and the number of uncached DOFs. ok = False when a
    row's columns are not ascending (the scipy path then sorts them first)."""
    m = indptr.shape[0] - 1
    nnz = indptr[m]
    ok = True
    for a in range(m):
        for e in range(indptr[a] + 1, indptr[a + 1]):
            ok = ok and indices[e - 1] <= indices[e]
    cols = np.sort(indices[:nnz])
    dofs = np.empty(nnz, dtype=np.int64)
    n = 0
    for i in range(nnz):
        if i == 0 or cols[i] != cols[i - 1]:
            dofs[n] = cols[i]
            n += 1
    dofs = dofs[:n]
    slots = np.empty(n, dtype=np.int64)
    missing = 0
    for i in range(n):
        slots[i] = slot_of[dofs[i]]
        if slots[i] < 0:
            missing += 1
    Nd = np.zeros((m, n))
    if ok:
        for a in range(m):
            for e in range(indptr[a], indptr[a + 1]):
                k = np.searchsorted(dofs, indices[e])
                if e > indptr[a] and indices[e] == indices[e - 1]:
                    Nd[a, k] += data[e]
                else:
                    Nd[a, k] = data[e]
    return ok, dofs, slots, Nd, missing


@numba.njit(cache=True)
def row_entries(Nd):  # pragma: no cover - compiled
    """The nonzeros of each row of Nd (m, n_d): counts (m,), their columns cols (m, k) and
    values vals (m, k), k the most in a row (a contact row touches one slave node and a master
    facet's nodes: 3 to 15 of the n_d DOFs)."""
    m, n = Nd.shape
    counts = np.zeros(m, dtype=np.int64)
    for a in range(m):
        for j in range(n):
            if Nd[a, j] != 0.0:
                counts[a] += 1
    k = counts.max() if m else 0
    cols, vals = np.zeros((m, k), dtype=np.int64), np.zeros((m, k))
    for a in range(m):
        c = 0
        for j in range(n):
            if Nd[a, j] != 0.0:
                cols[a, c], vals[a, c] = j, Nd[a, j]
                c += 1
    return counts, cols, vals


@numba.njit(cache=True)
def sandwich(counts, cols, vals, slots, P):  # pragma: no cover - compiled
    """K = N_d P[slots, slots] N_d^T (m, m) from N_d's row entries (row_entries), reading P
    (symmetric) in place: m^2 k^2 products instead of the dense n_d^2 m + n_d m^2 (n_d ~ 3 m:
    ~1 GFlop at 460 rows). Upper triangle computed, mirrored (K symmetric to the last bit)."""
    m = counts.shape[0]
    K = np.empty((m, m))
    for i in range(m):
        for j in range(i, m):
            s = 0.0
            for a in range(counts[i]):
                pa = slots[cols[i, a]]
                t = 0.0
                for b in range(counts[j]):
                    t += P[pa, slots[cols[j, b]]] * vals[j, b]
                s += vals[i, a] * t
            K[i, j] = s
            K[j, i] = s
    return K


@numba.njit(cache=True)
def rows_times(counts, cols, vals, X):  # pragma: no cover - compiled
    """N_d X (m, p) from N_d's row entries (row_entries) and X (n_d, p)."""
    m, p = counts.shape[0], X.shape[1]
    out = np.zeros((m, p))
    for i in range(m):
        for a in range(counts[i]):
            v, r = vals[i, a], cols[i, a]
            for c in range(p):
                out[i, c] += v * X[r, c]
    return out


def _psi_times(psi_rows, X: np.ndarray) -> np.ndarray:
    """psi_rows @ X as a dense array (psi_rows (k, nq) sparse or dense, X (nq, p))."""
    return np.asarray(psi_rows @ X)


def _psi_times_rows(psi_rows, cols: np.ndarray) -> np.ndarray:
    """psi_rows @ cols.T (k, n) for cols (n, nq), reading only the columns of cols where the
    sparse psi_rows has entries (a gather, no (nq, n) copy)."""
    if not sp.issparse(psi_rows):
        return np.asarray(psi_rows) @ cols.T
    csr = sp.csr_matrix(psi_rows)
    idx = np.unique(csr.indices)
    if idx.size == 0:
        return np.zeros((csr.shape[0], cols.shape[0]))
    return csr[:, idx].toarray() @ np.take(cols, idx, axis=1).T


class NodalColumns:
    """Cached nodal columns of one factor of W_qq (one step size), grown on demand.

    cols (capacity, nq): row s = c_j = W_qq^-1 psi^T e_j for the nodal DOF j = dof[s]
    (C-ordered: a column is contiguous); P (capacity, capacity) = psi_j W_qq^-1 psi_k^T.
    F (capacity, 12), per column: [S1 c_j, M_w c_j, psi_j Z_r, psi_j Z_w] (3 each; the frame
    coupling of the column and the rows of Z at its DOF), the M_w and Z_w parts for the M_w and
    Z_w they were made with (remade when refresh_coupling replaced them). slot_of
    (3 n_nodes,): slot of each DOF, -1 when not cached.
    """

    def __init__(self, psi, S1: np.ndarray, zr: np.ndarray, zw: np.ndarray, mw: np.ndarray):
        self.psi, self.S1 = psi, S1
        self.nq = psi.shape[1]
        self.slot_of = np.full(psi.shape[0], -1, dtype=np.int64)
        self.n = 0
        self.dof = np.zeros(0, dtype=np.int64)
        self.cols = np.zeros((0, self.nq))
        self.P = np.zeros((0, 0))
        self.F = np.zeros((0, 12))
        self._zr, self._zw, self._mw = zr, zw, mw

    def touch(self, selector, solve) -> tuple[np.ndarray, np.ndarray]:
        """Slots (n_d,) of the DOFs the selector (m, 3 n_nodes) touches, sorted by DOF, and the
        selector restricted to them, N_d (m, n_d). DOFs not cached yet are solved for (one
        multi-RHS back-substitution with `solve`). selector: a scipy sparse matrix, or a
        NodalSelector (constraints.rows), read in its CSR arrays by a compiled kernel
        (selector_columns: the same DOFs and N_d, bit for bit)."""
        if isinstance(selector, NodalSelector):
            ok, dofs, slots, Nd, missing = selector_columns(
                selector.data, selector.indices, selector.indptr, self.slot_of
            )
            if ok:
                if missing:
                    self._add(dofs[slots < 0], solve)
                    slots = self.slot_of[dofs]
                return slots, Nd
            selector = selector.tocsr()
        sel = sp.csr_matrix(selector, copy=True)
        sel.sum_duplicates()
        dofs = np.unique(sel.indices)
        slots = self.slot_of[dofs]
        if np.any(slots < 0):
            self._add(dofs[slots < 0], solve)
            slots = self.slot_of[dofs]
        rows = np.repeat(np.arange(sel.shape[0]), np.diff(sel.indptr))
        Nd = np.zeros((sel.shape[0], dofs.size))
        Nd[rows, np.searchsorted(dofs, sel.indices)] = sel.data
        return slots, Nd

    def coupling(self, mw: np.ndarray, zw: np.ndarray) -> None:
        """Make the M_w c_j and psi_j Z_w parts of F those of mw (3, nq) and zw (nq, 3) if they
        are other arrays than the ones in use: a product with every cached column (M_w c_j)
        and a gather (psi_j Z_w)."""
        n = self.n
        if mw is not self._mw:
            self.F[:n, 3:6] = self.cols[:n] @ mw.T
            self._mw = mw
        if zw is not self._zw:
            self.F[:n, 9:12] = _psi_times(self.psi[self.dof[:n]], zw)
            self._zw = zw

    def _add(self, new: np.ndarray, solve) -> None:
        """Solve for the columns of the DOFs `new` (k,) and extend P and F."""
        k, n0 = new.size, self.n
        n1 = n0 + k
        self._grow(n1)
        psi_new = self.psi[new]
        rhs = psi_new.toarray().T if sp.issparse(psi_new) else np.asarray(psi_new).T
        cols = np.asarray(solve(np.ascontiguousarray(rhs))).reshape(self.nq, k).T
        self.cols[n0:n1] = cols
        self.dof[n0:n1] = new
        self.slot_of[new] = np.arange(n0, n1)
        block = _psi_times_rows(psi_new, self.cols[:n1])  # (k, n1)
        self.P[n0:n1, :n0] = block[:, :n0]
        self.P[:n0, n0:n1] = block[:, :n0].T
        self.P[n0:n1, n0:n1] = 0.5 * (block[:, n0:] + block[:, n0:].T)
        self.F[n0:n1, 0:3] = cols @ self.S1.T
        self.F[n0:n1, 3:6] = cols @ self._mw.T
        self.F[n0:n1, 6:9] = _psi_times(psi_new, self._zr)
        self.F[n0:n1, 9:12] = _psi_times(psi_new, self._zw)
        self.n = n1

    def _grow(self, need: int) -> None:
        cap = self.cols.shape[0]
        if need <= cap:
            return
        new_cap = max(need, 2 * cap, 16)
        n = self.n
        cols = np.empty((new_cap, self.nq))
        cols[:n] = self.cols[:n]
        P = np.zeros((new_cap, new_cap))
        P[:n, :n] = self.P[:n, :n]
        F = np.zeros((new_cap, 12))
        F[:n] = self.F[:n]
        dof = np.zeros(new_cap, dtype=np.int64)
        dof[:n] = self.dof[:n]
        self.cols, self.P, self.F, self.dof = cols, P, F, dof


class NodalCompliance:
    """D (m, m) and the velocity correction of one body's contact rows (module docstring).

    xf: frame part of W^-1 Phi^T, (6, m) (or (3, m) for the translational form); the elastic
    part is kept implicit: the cached columns `cols` at `slots`, N_d (m, n_d), Z_r, Z_w (nq, 3)
    and A (3, 3) as they were when D was made.
    """

    def __init__(self, D, xf, cols, slots, Nd, zr, zw, A):
        self.D, self.xf = D, xf
        self._cols, self._slots, self._Nd = cols, slots, Nd
        self._zr, self._zw, self._A = zr, zw, A

    def velocity(self, lam: np.ndarray) -> np.ndarray:
        """W^-1 Phi^T lam, (6 + nq,) (or (3 + nq,) translational) for impulses lam (m,) [N s]
        (unit of the result: that of W^-1 times N s, i.e. m/s and 1/s for the frame)."""
        dvf = self.xf @ lam
        dq = self._zr @ (-(self._A.T @ dvf[:3]))
        if self._zw is not None:
            dq -= self._zw @ dvf[3:]
        add_weighted_rows(self._cols, self._slots, self._Nd.T @ lam, dq)
        return np.concatenate([dvf, dq])


def nodal_compliance(
    cache: NodalColumns, solve, bf: np.ndarray, selector, frame: tuple
) -> NodalCompliance:
    """Compliance of the rows [bf (m, 6), selector (m, 3 n_nodes) psi] (module docstring).

    frame = (A (3, 3), schur, Z_r (nq, 3), Z_w (nq, 3), M_w (3, nq)) for the 6 x 6 frame Schur
    complement (schur: lu_factor of S), or (A, schur, Z_r, None, None) for the 3 x 3
    translational one (schur: cho_factor of S_t; only bf[:, :3] is used)."""
    A, schur, zr, zw, mw = frame
    slots, Nd = cache.touch(selector, solve)
    if zw is not None:
        cache.coupling(mw, zw)
    # N_d is sparse (a row: its slave node and master facet nodes): every product with it
    # reads its row entries; N_d F (m, 12) = [S1 y, M_w y, N psi Z_r, N psi Z_w]^T per row
    counts, cols, vals = row_entries(Nd)
    K = sandwich(counts, cols, vals, slots, cache.P)  # N psi W_qq^-1 psi^T N^T
    NF = rows_times(counts, cols, vals, cache.F[slots])
    ar = A @ NF[:, 0:3].T  # A S1 y, (3, m)
    if zw is None:
        phi_f = bf[:, :3]
        xf = cho_solve(schur, phi_f.T - ar)
        nzq = NF[:, 6:9] @ (A.T @ xf)  # N psi_d Z x_f, (m, m)
    else:
        phi_f = bf
        xf = lu_solve(schur, bf.T - np.vstack([ar, NF[:, 3:6].T]))
        nzq = NF[:, 6:9] @ (A.T @ xf[:3]) + NF[:, 9:12] @ xf[3:]
    D = phi_f @ xf + K - nzq
    return NodalCompliance(D, xf, cache.cols, slots, Nd, zr, zw, A)


class DenseCompliance:
    """The same interface from explicit columns Y = W^-1 Phi^T (nv, m) and rows Phi (m, nv)
    (small or rigid bodies, joints): D = Phi Y, velocity = Y lam."""

    def __init__(self, Phi: np.ndarray, Y: np.ndarray):
        self.D = np.asarray(Phi @ Y)
        self.Y = Y

    def velocity(self, lam: np.ndarray) -> np.ndarray:
        """Y lam (nv,)."""
        return self.Y @ lam
