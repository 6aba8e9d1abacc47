"""A flexible body in a floating frame of reference (seed eq. 1-6).

Position of node k: x_k = r + A s_k, s_k = X_k + psi_k q (body frame). Generalized velocity
v = [r_dot (global), omega (body frame), q_dot] (seed eq. 1-3). A rigid body is nq = 0.

Equations of motion (virtual work, Shabana ch. 5), with S = S0 + S1 q, J = tr(G) I - G:

    [ m I      -A S~     A S1  ] [r_ddot]   [Q_r]
    [ S~ A^T    J        M_wq  ] [w_dot ] = [Q_w]
    [ S1^T A^T  M_wq^T   M_qq  ] [q_ddot]   [Q_q]

Q holds the elastic force -k_hat q, gravity, nodal loads and the quadratic-velocity terms
-L^T M (w x (w x s) + 2 w x s_dot), all written as contractions of the inertia invariants.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from flexmvm.bodies.contraction import G2Contraction
from flexmvm.bodies.invariants import InertiaInvariants, inertia_invariants
from flexmvm.bodies.nodal_contraction import NodalContraction
from flexmvm.bodies.rotation import cross3, cross_rows, skew
from flexmvm.mesh.mesh import Mesh

if TYPE_CHECKING:
    from flexmvm.bodies.stiffening import GeometricStiffening

_CYCLIC = ((0, 1, 2), (1, 2, 0), (2, 0, 1))
# From this many coordinates the packed one-pass G2 contraction beats the stacked product
# (one BLAS thread, seed case: nq = 553 0.47 ms against 0.81 ms; nq = 112 0.024 against
# 0.011 ms)
PACKED_MIN_NQ = 300


@dataclass(frozen=True)
class FlexibleBody:
    """Constant data of one body; the state (r, A, q, v) lives in the integrator.

    X: (n, 3) undeformed node positions in the body frame [m]; psi: (3n, nq) basis (dense or
    csr); k_hat: (nq, nq) reduced stiffness [N/m]; c_hat: optional reduced damping [N s/m].
    """

    name: str
    X: np.ndarray
    psi: np.ndarray | sp.spmatrix
    inv: InertiaInvariants
    k_hat: np.ndarray | sp.spmatrix
    mesh: Mesh | None = None
    c_hat: np.ndarray | sp.spmatrix | None = None
    label: str = ""
    _psi_rows: dict = field(default_factory=dict, compare=False, repr=False)
    #: An elimination order of the pattern of M_qq + k_hat (+ c_hat) for the integrator's
    #: sparse factors (fe.ordering.dissection_order; empty: none exists, SuperLU's minimum
    #: degree; None: not made, the integrator makes it if needed)
    elimination_order: np.ndarray | None = field(default=None, compare=False, repr=False)
    #: The geometric stiffening of the body's spin (bodies.stiffening); None: off
    stiffening: GeometricStiffening | None = field(default=None, compare=False, repr=False)

    @classmethod
    def build(cls, name, X, M_scalar, psi, k_hat, *, mesh=None, c_hat=None, label=""):
        """Compute the inertia invariants once and return the body."""
        inv = inertia_invariants(X, M_scalar, psi)
        if sp.issparse(psi):
            psi = sp.csr_matrix(psi)
        return cls(name, np.asarray(X, float), psi, inv, k_hat, mesh, c_hat, label)

    # -- sizes ----------------------------------------------------------------------------
    # cached: a step asks them ~50 times per body (0.1 ms of property calls a step)
    @functools.cached_property
    def nq(self) -> int:
        return self.inv.nq

    @functools.cached_property
    def nv(self) -> int:
        return 6 + self.nq

    @functools.cached_property
    def is_sparse(self) -> bool:
        return sp.issparse(self.psi)

    # -- invariant contractions -------------------------------------------------------------
    def first_moment(self, q: np.ndarray) -> np.ndarray:
        """S = S0 + S1 q (body frame) [kg m]."""
        return self.inv.S0 + self.inv.S1 @ q

    @functools.cached_property
    def _g2_stack(self) -> np.ndarray:
        """Dense bases: the nine G2 blocks stacked as one (9 nq, nq) array, block 3a + b =
        G2[b][a], so that all nine G2[b][a] x come from one matrix-vector product."""
        G2 = self.inv.G2
        stack = np.vstack([np.asarray(G2[b][a]) for a in range(3) for b in range(3)])
        return np.ascontiguousarray(stack)

    @functools.cached_property
    def _g2_packed(self) -> G2Contraction | None:
        """Dense bases from PACKED_MIN_NQ coordinates: the six distinct G2 blocks, read once
        per contraction (bodies.contraction)."""
        if self.inv.Ms is not None or self.nq < PACKED_MIN_NQ:
            return None
        return G2Contraction(self.inv.G2)

    @functools.cached_property
    def nodal(self) -> NodalContraction | None:
        """The compact contraction of a basis that selects nodal DOFs (full FE), else None."""
        return NodalContraction.of(self.psi, self.inv.Ms, self.X)

    @property
    def _nodal_basis(self) -> NodalContraction:
        """nodal, where a compact (2D) carried contraction is used: only a basis selecting
        nodal DOFs makes one (carried_contractions)."""
        nodal = self.nodal
        assert nodal is not None, "a compact contraction comes from a nodal basis"
        return nodal

    def node_of_coordinate(self, k: int) -> tuple[int, int] | None:
        """(mesh node, direction 0/1/2) of elastic coordinate k for a basis that selects
        nodal DOFs (full FE), else None."""
        nodal = self.nodal
        if nodal is None or not 0 <= k < len(nodal.node):
            return None
        return int(nodal.node[k]), int(nodal.comp[k])

    def carried_contractions(self, x: np.ndarray, pool=None) -> np.ndarray:
        """L(x) in the form an integrator carries: Y(x) (3, n nodes) for a basis selecting
        nodal DOFs (bodies.nodal_contraction), else L(x) (3, 3, nq). Linear in x either way;
        contraction_trace, inertia_terms and rotational_coupling take both. pool: see
        contractions."""
        nodal = self.nodal
        return nodal(x) if nodal is not None else self.contractions(x, pool)

    @property
    def contracts_in_halves(self) -> bool:
        """Whether contractions make one compiled pass over half of the G2 blocks (dense
        bases from PACKED_MIN_NQ coordinates), which a thread pool can split in two."""
        return self._g2_packed is not None

    def contraction_trace(self, Lc: np.ndarray) -> np.ndarray:
        """M_qq x from a carried contraction Lc of x (M_qq = sum_a G2[a][a])."""
        if Lc.ndim == 2:
            return self._nodal_basis.trace(Lc)
        return Lc[0, 0] + Lc[1, 1] + Lc[2, 2]

    def contractions(self, x: np.ndarray, pool=None) -> np.ndarray:
        """L(x)[a, b] = G2[b][a] x, shape (3, 3, nq): every G2 contraction of the equations of
        motion is one of these, and L is linear, so an integrator can carry L(q) and
        L(q_dot) along with the state (integrate.moreau_jean). One pass over the G2 blocks;
        with a thread pool (contracts_in_halves) in two parts on two threads, bit for bit."""
        inv = self.inv
        packed = self._g2_packed
        if packed is not None:
            return packed(x, pool)
        if inv.Ms is not None:
            assert inv.PT is not None  # set with Ms (bodies.invariants)
            # G2[b][a] x = P_b^T M_s (P_a x): one M_s product with 3 columns instead of nine
            # products with the G2 blocks (each as large as M_s)
            U = np.column_stack([inv.PT[a].T @ x for a in range(3)])
            MU = inv.Ms @ U
            PMU = [inv.PT[b] @ MU for b in range(3)]
            return np.array([[PMU[b][:, a] for b in range(3)] for a in range(3)])
        return (self._g2_stack @ x).reshape(3, 3, self.nq)

    @functools.cached_property
    def G1_array(self) -> np.ndarray:
        """G1 as one C-ordered (3, 3, nq) array, [a, b] = inv.G1[a][b]."""
        return np.ascontiguousarray(
            np.array([[self.inv.G1[a][b] for b in range(3)] for a in range(3)], dtype=float)
        )

    def inertia_terms(self, q: np.ndarray, Lq: np.ndarray | None = None):
        """(S, J, M_wq, C) at q: first moment, inertia about the frame origin, the omega-q
        coupling (3, nq) and C[a][b] = s_a^T M_s P_b = G1[a][b] + G2[b][a] q (3, 3, nq),
        reused by the velocity terms. Lq = contractions(q) when already known, or Lq in the
        compact form of carried_contractions, which gives C = None (S, J and M_wq only)."""
        S = self.first_moment(q)
        if not self.nq:
            G = self.inv.G0
            return S, np.trace(G) * np.eye(3) - G, np.zeros((3, 0)), np.zeros((3, 3, 0))
        if Lq is not None and Lq.ndim == 2:
            # compact form (bodies.nodal_contraction): G = G0 + Q^T (M_s X) + Cq Q
            nodal = self._nodal_basis
            Cq = nodal.first_moment_matrix(Lq)
            Q = nodal.scattered(q)
            G = self.inv.G0 + Q.T @ nodal.MsX + Cq @ Q
            G = 0.5 * (G + G.T)
            return S, np.trace(G) * np.eye(3) - G, nodal.antisymmetric(Cq), None
        C = self.G1_array + (self.contractions(q) if Lq is None else Lq)
        # G[a, b] = G0[a, b] + G1[b][a] q + C[a][b] q
        G = self.inv.G0 + self.G1_array.transpose(1, 0, 2) @ q + C @ q
        G = 0.5 * (G + G.T)
        J = np.trace(G) * np.eye(3) - G
        M_wq = np.array([C[a, b] - C[b, a] for _, a, b in _CYCLIC])
        return S, J, M_wq, C

    def frame_inertia_first_order(self, q: np.ndarray) -> np.ndarray:
        """J(q) without its quadratic part q^T G2 q (relative size (|u|/L)^2): cheap, for
        iteration matrices, never for residuals."""
        G = self.inv.G0.copy()
        nodal = self.nodal
        if nodal is not None:
            Gq = nodal.MsX.T @ nodal.scattered(q)  # G1[a][b] q = sum_n (M_s X)[n, a] Q[n, b]
            G += Gq + Gq.T
        elif self.nq:
            Gq = self.G1_array @ q  # Gq[a, b] = G1[a][b] q
            G += Gq + Gq.T
        G = 0.5 * (G + G.T)
        return np.trace(G) * np.eye(3) - G

    @functools.cached_property
    def _rotational_coupling(self) -> tuple[np.ndarray, np.ndarray | None]:
        """M_wq(0) (3, nq) and, for dense bases, the stacked antisymmetric blocks
        [G2[b][a] - G2[a][b]] over cyclic (c, a, b) as one (3 nq, nq) array, so that
        M_wq(q) = M_wq(0) + (stack @ q).reshape(3, nq) is one matrix-vector product."""
        G1, G2 = self.inv.G1, self.inv.G2
        Mw0 = np.array([G1[a][b] - G1[b][a] for _, a, b in _CYCLIC]).reshape(3, self.nq)
        if self.inv.Ms is not None or not self.nq:
            return Mw0, None
        stack = np.vstack([np.asarray(G2[b][a]) - np.asarray(G2[a][b]) for _, a, b in _CYCLIC])
        return Mw0, np.ascontiguousarray(stack)

    def rotational_coupling(self, q: np.ndarray, Lq: np.ndarray | None = None) -> np.ndarray:
        """M_wq(q) (3, nq), the omega-q inertia coupling, alone: 3 nq^2 operations for a dense
        basis instead of the 9 nq^2 of inertia_terms (sparse bases: three M_s products);
        free when Lq = contractions(q) (or carried_contractions(q)) is known."""
        Mw0, stack = self._rotational_coupling
        if not self.nq:
            return Mw0
        if Lq is not None and Lq.ndim == 2:
            nodal = self._nodal_basis
            return nodal.antisymmetric(nodal.first_moment_matrix(Lq))
        if Lq is None and stack is not None:
            return Mw0 + (stack @ q).reshape(3, self.nq)
        L = self.contractions(q) if Lq is None else Lq
        return Mw0 + np.array([L[a, b] - L[b, a] for _, a, b in _CYCLIC])

    def frame_mass(self, A: np.ndarray, S: np.ndarray, J: np.ndarray) -> np.ndarray:
        """6 x 6 frame block [[m I, -A S~], [S~ A^T, J]]."""
        Mff = np.zeros((6, 6))
        Mff[:3, :3] = self.inv.mass * np.eye(3)
        ASt = A @ skew(S)
        Mff[:3, 3:] = -ASt
        Mff[3:, :3] = -ASt.T
        Mff[3:, 3:] = J
        return Mff

    def coupling_mass(self, A: np.ndarray, M_wq: np.ndarray) -> np.ndarray:
        """6 x nq frame-elastic block [[A S1], [M_wq]]."""
        return np.vstack([A @ self.inv.S1, M_wq])

    def mass_times(
        self, A, q, a_vec: np.ndarray, terms=None, mqq_a: np.ndarray | None = None
    ) -> np.ndarray:
        """M(A, q) @ a_vec without forming the full matrix (a_vec: (6 + nq,)); mqq_a =
        M_qq @ a_vec[6:] when already known (the only nq^2 part)."""
        S, J, M_wq, _ = terms if terms is not None else self.inertia_terms(q)
        Mff = self.frame_mass(A, S, J)
        out = np.empty(self.nv)
        af, aq = a_vec[:6], a_vec[6:]
        out[:6] = Mff @ af
        if self.nq:
            Mfq = self.coupling_mass(A, M_wq)
            out[:6] += Mfq @ aq
            out[6:] = Mfq.T @ af + (self.inv.M_qq @ aq if mqq_a is None else mqq_a)
        return out

    def velocity_forces(self, A, q, v, terms=None, Lqd: np.ndarray | None = None) -> np.ndarray:
        """Quadratic-velocity vector Q_v (6 + nq,): centrifugal and Coriolis terms.
        Lqd = contractions(v[6:]) when already known."""
        S, J, _, C = terms if terms is not None else self.inertia_terms(q)
        w, qd = v[3:6], v[6:]
        W = skew(w)
        Om = W @ W
        out = np.zeros(self.nv)
        S1qd = self.inv.S1 @ qd if self.nq else np.zeros(3)
        out[:3] = -A @ (Om @ S + 2.0 * W @ S1qd)
        H = C @ qd if self.nq else np.zeros((3, 3))  # H[a, b] = C[a][b] . q_dot
        out[3:6] = -(cross3(w, J @ w) + 2.0 * (np.trace(H) * w - H.T @ w))
        if self.nq and np.any(w):
            # sum_ab Om[a, b] C[b][a] and sum_ab W[a, b] G2[a][b] q_dot = sum_c w_c A_c q_dot
            # with the antisymmetric blocks A_c = G2[b][a] - G2[a][b] of rotational_coupling
            Qq = -np.einsum("ab,bak->k", Om, C)
            _, anti = self._rotational_coupling
            if Lqd is not None:
                Qq -= 2.0 * (w @ np.array([Lqd[a, b] - Lqd[b, a] for _, a, b in _CYCLIC]))
            elif anti is not None:
                Qq -= 2.0 * (w @ (anti @ qd).reshape(3, self.nq))
            else:
                G2 = self.inv.G2
                for a in range(3):
                    for b in range(3):
                        if W[a, b] != 0.0:
                            Qq -= 2.0 * W[a, b] * (G2[a][b] @ qd)
            out[6:] = Qq
        return out

    def gravity_forces(self, A, q, g: np.ndarray, S=None) -> np.ndarray:
        """Generalized gravity force for global acceleration g [m/s^2] (6 + nq,)."""
        S = self.first_moment(q) if S is None else S
        gb = A.T @ g
        out = np.zeros(self.nv)
        out[:3] = self.inv.mass * g
        out[3:6] = cross3(S, gb)
        if self.nq:
            out[6:] = self.inv.S1.T @ gb
        return out

    def elastic_forces(self, q, qd=None) -> np.ndarray:
        """-k_hat q - c_hat q_dot on the elastic coordinates (nq,)."""
        f = -(self.k_hat @ q) if self.nq else np.zeros(0)
        if self.c_hat is not None and qd is not None and self.nq:
            f = f - self.c_hat @ qd
        return np.asarray(f).ravel()

    # -- nodes --------------------------------------------------------------------------------
    def psi_rows(self, k: int):
        """psi_k: the (3, nq) rows of node k (dense for reduced bases, csr for full FE)."""
        rows = self._psi_rows.get(k)
        if rows is None:
            rows = self.psi[3 * k : 3 * k + 3, :]
            self._psi_rows[k] = rows
        return rows

    def local_displacements(self, nodes: np.ndarray, q: np.ndarray) -> np.ndarray:
        """u_k = psi_k q in the body frame for the given node ids, shape (len(nodes), 3)."""
        nodes = np.asarray(nodes, dtype=np.int64)
        if not self.nq:
            return np.zeros((len(nodes), 3))
        idx = (3 * nodes[:, None] + np.arange(3)).ravel()
        return np.asarray(self.psi[idx, :] @ q).reshape(-1, 3)

    def node_positions(self, nodes, r, A, q) -> np.ndarray:
        """Global positions x_k = r + A (X_k + u_k), shape (len(nodes), 3)."""
        s = self.X[nodes] + self.local_displacements(nodes, q)
        return r + s @ A.T

    def node_velocities(self, nodes, A, q, v) -> np.ndarray:
        """Global velocities x_dot_k = r_dot + A (w x s_k + psi_k q_dot), (len(nodes), 3)."""
        s = self.X[nodes] + self.local_displacements(nodes, q)
        sd = self.local_displacements(nodes, v[6:]) if self.nq else np.zeros_like(s)
        return v[:3] + (cross_rows(v[3:6], s) + sd) @ A.T

    def point_jacobian(self, k: int, A, q, direction: np.ndarray):
        """Row d^T dx_k/dv for a global direction d: returns (frame part (6,), q part (nq,))."""
        s = self.X[k] + (self.psi_rows(k) @ q if self.nq else 0.0)
        dl = A.T @ direction
        frame = np.concatenate([direction, cross3(s, dl)])
        if not self.nq:
            return frame, np.zeros(0)
        qpart = self.psi_rows(k).T @ dl
        return frame, np.asarray(qpart).ravel()

    # -- integrals of motion ----------------------------------------------------------------------
    def kinetic_energy(self, A, q, v, terms=None, mqq_v: np.ndarray | None = None) -> float:
        """1/2 v^T M v [J]; mqq_v = M_qq v[6:] when already known."""
        return 0.5 * float(v @ self.mass_times(A, q, v, terms, mqq_v))

    def strain_energy(self, q, kq: np.ndarray | None = None) -> float:
        """1/2 q^T k_hat q [J]; kq = k_hat q when already known."""
        if not self.nq:
            return 0.0
        return 0.5 * float(q @ (self.k_hat @ q if kq is None else kq))

    def linear_momentum(self, A, q, v, terms=None) -> np.ndarray:
        """p = m r_dot + A (w x S + S1 q_dot) [kg m/s], global."""
        S = self.first_moment(q) if terms is None else terms[0]
        inner = cross3(v[3:6], S) + (self.inv.S1 @ v[6:] if self.nq else 0.0)
        return self.inv.mass * v[:3] + A @ inner

    def angular_momentum(self, r, A, q, v, terms=None) -> np.ndarray:
        """Angular momentum about the global origin [kg m^2/s]:
        r x p + A (S x A^T r_dot + J w + M_wq q_dot)."""
        S, J, M_wq, _ = terms if terms is not None else self.inertia_terms(q)
        p = self.linear_momentum(A, q, v, (S, J, M_wq, None))
        h_o = cross3(S, A.T @ v[:3]) + J @ v[3:6] + (M_wq @ v[6:] if self.nq else 0.0)
        return cross3(r, p) + A @ h_o
