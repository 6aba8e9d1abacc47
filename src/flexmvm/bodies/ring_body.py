"""The floating-frame body of kind mvm-sparse's ring basis (reduction/kinds/mvm_sparse.py):
sparse where the FE model is.

With q = [u_R, s, eta] and psi = [I on the region's DOFs; B on the exterior rows of the corner
columns c] (RingColumns), every inertia invariant of bodies/invariants.py splits
into the region's nodal part, as sparse as M_s, and a dense block on c:

    G2[a][b] = Sel_a^T M_RR Sel_b + E_c D_ab E_c^T,
    D_ab     = Q_a^T M_EE Q_b + R_a (M_Gamma,E Q_b) + (R_b (M_Gamma,E Q_a))^T

(Q_a (n_E, n_c): the a-components of B at the exterior nodes; R_a puts ring node g's row at
corner position 3 g + a; M_s's blocks R-E couple only ring nodes to E). Likewise
k_hat = K_RR + E_c (B^T K_EE B + R(K_Gamma,E B) + R(..)^T) E_c^T. Built with dense products on
n_c columns only: setup costs ~9 n_E n_c^2 flops, against the dense Craig-Bampton body's
~9 n nq^2, and nothing of size nq^2 is dense. A step's contraction L(x) (3, 3, nq) is one
product with the stacked sparse part and one packed pass over the six distinct dense corner
blocks (bodies.contraction).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from flexmvm.bodies.body import PACKED_MIN_NQ, FlexibleBody
from flexmvm.bodies.build import BodyParts, body_from_parts
from flexmvm.bodies.contraction import G2Contraction
from flexmvm.bodies.damping import Damping
from flexmvm.bodies.invariants import InertiaInvariants
from flexmvm.fe.assembly import FEModel
from flexmvm.reduction.kinds import KINDS, ModelKind
from flexmvm.reduction.kinds.mvm_sparse import RingColumns, split_ring_psi

#: Bytes of the exterior rows of psi one block of the parts' products gathers (with its
#: neighbours' rows, a little more: _row_blocks): the parts are summed over blocks of rows, so
#: the set-up never holds the corner's exterior rows whole beside psi.
PARTS_BLOCK_BYTES = 64e6


def _rows_per_block(n_c: int) -> int:
    """Rows of n_c columns in PARTS_BLOCK_BYTES (at least 16)."""
    return max(16, int(PARTS_BLOCK_BYTES // (8 * max(n_c, 1))))


def _row_blocks(pattern: sp.csr_matrix, n_c: int) -> list[np.ndarray]:
    """Blocks of the rows of the symmetric ``pattern`` (n, n) (sorted row ids, PARTS_BLOCK_BYTES
    of n_c columns each), consecutive in its reverse Cuthill-McKee order: a block's rows and
    their neighbours then lie in a band. In the mesh's own numbering a block of 922 exterior
    nodes of a 274k-DOF plate had up to 50,297 neighbours (3.5 GB of their rows of a
    2,892-column corner gathered at once), in this order at most 3,215."""
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    n = pattern.shape[0]
    order = reverse_cuthill_mckee(sp.csr_matrix(pattern), symmetric_mode=True)
    step = _rows_per_block(n_c)
    return [np.sort(order[k : k + step]).astype(np.int64) for k in range(0, n, step)]


def _components(cols: RingColumns, ext_nodes: np.ndarray) -> list[np.ndarray]:
    """[Q_0, Q_1, Q_2] (len(ext_nodes), n_c): the rows of B of each exterior node's x, y, z
    DOF, zero where that DOF is a reference DOF (no row)."""
    Q = []
    for a in range(3):
        dof = 3 * ext_nodes + a
        at = np.minimum(np.searchsorted(cols.interior, dof), cols.interior.size - 1)
        has = cols.interior[at] == dof
        Qa = np.zeros((ext_nodes.size, cols.corner.size))
        Qa[has] = cols.rows(at[has])
        Q.append(Qa)
    return Q


def _support(rows: sp.csr_matrix, block: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(the columns of ``rows`` (the rows ``block``, sorted ids, of a square matrix) and the
    block's own, sorted; the block's positions in them)."""
    S = np.union1d(rows.indices, block)
    return S, np.searchsorted(S, block)


def _nodal_block(M_RR: sp.coo_matrix, a: int, b: int, nq: int) -> sp.coo_matrix:
    """Sel_a^T M_RR Sel_b (nq, nq): entry (3 i + a, 3 j + b) = M_RR[i, j]."""
    return sp.coo_matrix((M_RR.data, (3 * M_RR.row + a, 3 * M_RR.col + b)), shape=(nq, nq))


def _corner_block(D: np.ndarray, corner: np.ndarray, nq: int) -> sp.coo_matrix:
    """E_c D E_c^T (nq, nq) as coo."""
    n_c = corner.size
    rows = np.repeat(corner, n_c)
    cols = np.tile(corner, n_c)
    return sp.coo_matrix((D.ravel(), (rows, cols)), shape=(nq, nq))


def _ring_rows(X: np.ndarray, a: int, n_c: int) -> np.ndarray:
    """R_a X: ring node g's row of X (n_Gamma, n_c) at corner position 3 g + a."""
    out = np.zeros((n_c, X.shape[1]))
    out[a : 3 * X.shape[0] : 3] = X
    return out


def ring_parts(fe: FEModel, nodes: np.ndarray, cols: RingColumns, nq: int) -> BodyParts:
    """Inertia invariants and k_hat of the ring basis of ``fe`` with retained ``nodes``
    (module doc): G2 blocks, M_qq and k_hat csr (nq, nq), the rest dense as
    bodies.invariants.inertia_invariants gives them (to round-off). The exterior's products
    are summed over blocks of exterior nodes (_exterior_sums)."""
    X = np.asarray(fe.mesh.nodes, dtype=float)
    Ms = sp.csr_matrix(fe.M_scalar)
    msum = np.asarray(Ms.sum(axis=1)).ravel()
    MsX = Ms @ X
    G0 = X.T @ MsX
    G0 = 0.5 * (G0 + G0.T)
    S0 = msum @ X
    M_RR = sp.coo_matrix(Ms[nodes][:, nodes])
    n_c, corner = cols.corner.size, cols.corner
    D, GQ, S1c, G1c = _exterior_sums(fe, nodes, cols, msum, MsX)
    G2: list[list] = [[None] * 3 for _ in range(3)]
    for b in range(3):
        for a in range(b + 1):
            D_ab = D[a][b] + _ring_rows(GQ[b], a, n_c) + _ring_rows(GQ[a], b, n_c).T
            block = sp.csr_matrix(_nodal_block(M_RR, a, b, nq) + _corner_block(D_ab, corner, nq))
            D[a][b] = None  # freed as it is used
            G2[a][b] = block
            if b > a:
                G2[b][a] = sp.csr_matrix(block.T)
    S1 = np.zeros((3, nq))
    G1x = np.zeros((3, 3, nq))
    j = np.arange(nodes.size)
    for a in range(3):
        S1[a, 3 * j + a] = msum[nodes]
        S1[a, corner] += S1c[a]
        for b in range(3):
            G1x[a, b, 3 * j + b] = MsX[nodes, a]
            G1x[a, b, corner] += G1c[a, b]
    G1 = tuple(tuple(G1x[a, b].copy() for b in range(3)) for a in range(3))
    M_qq = G2[0][0] + G2[1][1] + G2[2][2]
    M_qq = sp.csr_matrix(0.5 * (M_qq + M_qq.T))
    inv = InertiaInvariants(float(msum.sum()), S0, S1, G0, G1, tuple(tuple(r) for r in G2), M_qq)
    return BodyParts(inv, ring_stiffness(fe, nodes, cols, nq))


def _exterior_sums(fe: FEModel, nodes: np.ndarray, cols: RingColumns, msum, MsX):
    """The exterior's products of the ring parts, summed over blocks of exterior nodes E:
    D[a][b] = Q_a^T M_EE Q_b (a <= b; n_c, n_c), GQ[b] = M_Gamma,E Q_b (n_Gamma, n_c),
    msum_E Q_a (3, n_c) and (MsX)_E,a Q_b (3, 3, n_c); a block gathers the rows of its nodes
    and of their neighbours in M_EE (RingColumns.rows)."""
    Ms = sp.csr_matrix(fe.M_scalar)
    ext = np.setdiff1d(np.arange(fe.mesh.n_nodes), nodes)
    M_GE = sp.csc_matrix(Ms[nodes[cols.ring]][:, ext])
    M_EE = sp.csr_matrix(Ms[ext][:, ext])
    n_c = cols.corner.size
    D = [[np.zeros((n_c, n_c)) if a <= b else None for b in range(3)] for a in range(3)]
    GQ = [np.zeros((cols.ring.size, n_c)) for _ in range(3)]
    S1c, G1c = np.zeros((3, n_c)), np.zeros((3, 3, n_c))
    for blk in _row_blocks(M_EE, 3 * n_c):
        rows = M_EE[blk]
        S, pos = _support(rows, blk)
        Q = _components(cols, ext[S])
        QR = [q[pos] for q in Q]
        near = sp.csr_matrix(rows[:, S])
        for b in range(3):
            MQ = np.asarray(near @ Q[b])
            for a in range(b + 1):
                D[a][b] += QR[a].T @ MQ
            GQ[b] += np.asarray(M_GE[:, blk] @ QR[b])
        for a in range(3):
            S1c[a] += msum[ext[blk]] @ QR[a]
            for b in range(3):
                G1c[a, b] += MsX[ext[blk], a] @ QR[b]
    return D, GQ, S1c, G1c


#: The ring's static columns are taken to solve K_EE B_s = -K_E,Gamma (ring_stiffness) when a
#: random combination of them does to this backward error: ring_solve's direct factor does to
#: 3.6e-16 (the shipped block's 0.9 mm region); a basis not made on this K (or not by
#: ring_solve) does not, and takes the products.
RELATION_RTOL = 1e-8


def ring_stiffness(fe: FEModel, nodes: np.ndarray, cols: RingColumns, nq: int) -> sp.csr_matrix:
    """k_hat = psi^T K psi (nq, nq) csr of the ring basis (module doc), symmetrized. The ring's
    static columns B_s solve K_EE B_s = -K_E,Gamma (the ring's unit displacements, the rest of
    the ring held: ring_solve), so B^T K_EE B_s = -(K_Gamma,E B)^T: the static condensation
    of the ring (Craig and Bampton 1968), sparse work; only the other corner columns B_x (the
    massless nodes' static fields and the modes: tens) take B^T (K_EE B_x), and a ring column
    zero on E (a massless ring node's unit vector) has K_EE B_j = 0. The relation is checked
    (RELATION_RTOL) and, where it does not hold, B^T K_EE B is summed over blocks of rows
    (_direct_products). The 2,967-node region of a 274k-DOF plate: its body's stage (parts
    and k_hat) 165 -> 126 s with it, the products alone having taken 57 s."""
    b = (3 * nodes[:, None] + np.arange(3)).ravel()
    K = sp.csr_matrix(fe.K)
    K_bb = sp.coo_matrix(K[b][:, b])
    n_g = cols.n_ring_dofs
    K_ii = sp.csr_matrix(K[cols.interior][:, cols.interior])
    K_gi = sp.csr_matrix(K[b[cols.corner[:n_g]]][:, cols.interior])  # K_Gamma,E
    near = np.unique(K_gi.indices)  # the exterior rows next to the ring
    T = np.asarray(sp.csr_matrix(K_gi[:, near]) @ cols.rows(near))  # K_Gamma,E B
    C = _condensed(K_ii, K_gi, T, cols)
    if C is None:
        C = _direct_products(K_ii, cols)
    C[:n_g] += T
    C[:, :n_g] += T.T
    k_hat = sp.coo_matrix((K_bb.data, (K_bb.row, K_bb.col)), shape=(nq, nq))
    k_hat = sp.csr_matrix(k_hat + _corner_block(C, cols.corner, nq))
    return sp.csr_matrix(0.5 * (k_hat + k_hat.T))


def _condensed(K_ii, K_gi, T, cols: RingColumns) -> np.ndarray | None:
    """B^T K_EE B (n_c, n_c) from the statics' relation (ring_stiffness), or None where a
    random combination of the ring's columns does not satisfy it."""
    n_g, n_c, n_i = cols.n_ring_dofs, cols.corner.size, cols.interior.size
    z = np.random.default_rng(49).standard_normal(n_g)
    step = _rows_per_block(n_c)
    blocks = [(k, min(k + step, n_i)) for k in range(0, n_i, step)]
    colmax, y, B_x = np.zeros(n_g), np.zeros(n_i), np.zeros((n_i, n_c - n_g))
    for r0, r1 in blocks:  # one pass over B: its ring columns' extent, B_s z, B_x
        B_r = cols.rows(np.arange(r0, r1))
        np.maximum(colmax, np.abs(B_r[:, :n_g]).max(axis=0), out=colmax)
        y[r0:r1] = B_r[:, :n_g] @ z
        B_x[r0:r1] = B_r[:, n_g:]
    solved = colmax > 0.0  # zero on E: a massless ring node's unit vector (K_EE B_j = 0)
    load = np.asarray(K_gi.T @ (z * solved)).ravel()  # K_E,Gamma z over the solved columns
    # the solve's backward error: |K_EE y + K_E,Gamma z| against |K_EE| |y| + |K_E,Gamma z|
    residual = np.abs(K_ii @ y + load)
    scale = abs(K_ii) @ np.abs(y) + np.abs(load)
    if not residual.max() <= RELATION_RTOL * max(scale.max(), np.finfo(float).tiny):
        return None
    C = np.zeros((n_c, n_c))
    C[:, :n_g] = -(T * solved[:, None]).T
    KB_x = np.asarray(K_ii @ B_x)
    for r0, r1 in blocks:  # B^T (K_EE B_x), a second pass
        C[:, n_g:] += cols.rows(np.arange(r0, r1)).T @ KB_x[r0:r1]
    return C


def _direct_products(K_ii, cols: RingColumns) -> np.ndarray:
    """B^T K_EE B (n_c, n_c) summed over blocks of exterior rows (_row_blocks)."""
    n_c = cols.corner.size
    C = np.zeros((n_c, n_c))
    for blk in _row_blocks(K_ii, n_c):
        rows = K_ii[blk]
        S, pos = _support(rows, blk)
        B_S = cols.rows(S)
        C += B_S[pos].T @ np.asarray(sp.csr_matrix(rows[:, S]) @ B_S)
    return C


@dataclass(frozen=True)
class RingBody(FlexibleBody):
    """A FlexibleBody of a ring basis: psi, G2, M_qq and k_hat sparse with a dense corner on
    the coordinates ``corner`` (n_c,); contractions split accordingly (module doc)."""

    corner: np.ndarray | None = None

    @functools.cached_property
    def _split_g2(self) -> tuple[sp.csr_matrix, G2Contraction]:
        """(the nine blocks L[a, b] = G2[b][a] without their corner entries, stacked (9 nq,
        nq) csr; the packed dense corner blocks)."""
        nq, c = self.nq, self.corner
        in_corner = np.zeros(nq, dtype=bool)
        in_corner[c] = True
        G2 = self.inv.G2
        rest = []
        for a in range(3):
            for b in range(3):
                g = sp.coo_matrix(G2[b][a])
                keep = ~(in_corner[g.row] & in_corner[g.col])
                rest.append(
                    sp.coo_matrix((g.data[keep], (g.row[keep], g.col[keep])), shape=(nq, nq))
                )
        stack = sp.csr_matrix(sp.vstack(rest))
        # the ring body's G2 blocks are sparse (csr)
        D = [
            [np.asarray(sp.csr_matrix(G2[a][b])[c][:, c].toarray()) for b in range(3)]
            for a in range(3)
        ]
        return stack, G2Contraction(D)

    @functools.cached_property
    def _g2_packed(self):
        return None

    @functools.cached_property
    def _rotational_coupling(self) -> tuple[np.ndarray, None]:
        """M_wq(0) (3, nq) and no dense stack: M_wq(q) comes from contractions(q)."""
        G1 = self.inv.G1
        Mw0 = np.array([G1[a][b] - G1[b][a] for a, b in ((1, 2), (2, 0), (0, 1))])
        return Mw0.reshape(3, self.nq), None

    @property
    def contracts_in_halves(self) -> bool:
        # the corner's packed pass splits in two as a dense body's does, from the same size
        return self.corner is not None and self.corner.size >= PACKED_MIN_NQ

    def contractions(self, x: np.ndarray, pool=None) -> np.ndarray:
        """L(x)[a, b] = G2[b][a] x (3, 3, nq): the sparse part by one product, the corner by
        the packed pass (two threads with a pool)."""
        stack, corner = self._split_g2
        x = np.ascontiguousarray(x, dtype=float)
        L = np.asarray(stack @ x).reshape(3, 3, self.nq)
        L[:, :, self.corner] += corner(x[self.corner], pool if self.contracts_in_halves else None)
        return L


def ring_body_from_parts(
    name: str,
    mesh,
    basis,
    parts: BodyParts,
    corner: np.ndarray,
    *,
    damping: Damping | None = None,
) -> RingBody:
    """The RingBody of mesh (nodes X (n, 3) [m]) and ring basis psi (3n, nq) csr with its
    parts (ring_parts) and corner coordinates; damping as bodies.build.body_from_parts."""
    corner = np.asarray(corner, dtype=np.int64)
    return body_from_parts(  # type: ignore[return-value]  # body_type=RingBody
        name, mesh, basis, parts, damping=damping, body_type=RingBody, corner=corner
    )


def ring_body(
    name: str,
    fe: FEModel,
    basis,
    *,
    damping: Damping | None = None,
    parts_cache: Callable[..., tuple[BodyParts, np.ndarray]] | None = None,
) -> RingBody:
    """The body of a ring basis of ``fe`` (kind mvm-sparse's body_builder): its parts and
    corner computed (ring_parts on the corner read back from psi, split_ring_psi), or through
    ``parts_cache(fe, basis, build)`` (the scenarios stage passes the setup cache's
    setup_cache.ring_parts.cached_ring_parts: warm, psi's exterior rows are not read)."""
    nodes = np.asarray(basis.retained_nodes, dtype=np.int64)

    def build() -> tuple[BodyParts, np.ndarray]:
        cols = split_ring_psi(fe, basis.reference, basis.psi, nodes)
        return ring_parts(fe, nodes, cols, basis.nq), cols.corner

    parts, corner = build() if parts_cache is None else parts_cache(fe, basis, build)
    return ring_body_from_parts(name, fe.mesh, basis, parts, corner, damping=damping)


# kind mvm-sparse is registered by the reduction stage, which cannot name this stage's body:
# its builder is attached here, on the first import of any module of bodies/ (bodies/__init__)
_KIND = ModelKind("mvm-sparse")
KINDS[_KIND] = dataclasses.replace(KINDS[_KIND], body_builder=ring_body)  # type: ignore[type-var]  # a frozen dataclass
