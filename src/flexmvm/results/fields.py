"""Nodal fields of a flexible body at one output time: positions, displacement, velocity and
small-strain von Mises stress, from the histories a RunResult keeps.

Kinematics (seed eq. 1-3; docs/architecture.md "bodies"): node k of a body sits at
x_k = r + A (X_k + psi_k q) and moves with x_dot_k = r_dot + A (omega x s_k + psi_k q_dot),
s_k = X_k + psi_k q, omega in the body frame.

A RunResult stores the frame velocity [r_dot, omega] (6,) and the elastic rates q_dot at each
output, as the scheme integrated them, so nodal velocities written from it are those of the
simulation.

Stress (:func:`von_mises`): small-strain isotropic linear elasticity in the body frame,
sigma = lambda tr(eps) I + 2 mu eps, eps = sym(grad u), with grad u from the isoparametric
shape functions of each cell evaluated at the cell's own nodes; the stress tensors of the cells
sharing a node are averaged (unweighted) and the von Mises stress is taken of the average.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.errors import InputError, MeshError
from flexmvm.materials import Material
from flexmvm.mesh.cells import CELLS
from flexmvm.mesh.mesh import Mesh
from flexmvm.mesh.quality import shape_gradients

__all__ = [
    "NodalFields",
    "StressOperator",
    "body_geometry",
    "displacement",
    "elastic_displacement",
    "nodal_fields",
    "nodal_stress",
    "node_positions",
    "node_velocities",
    "reference_positions",
    "von_mises",
    "von_mises_of",
]

#: Cells per vectorised chunk in the stress evaluation (bounds memory to a few tens of MB).
_CHUNK = 4096


def _frame(r: np.ndarray, A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r = np.asarray(r, dtype=float)
    A = np.asarray(A, dtype=float)
    if r.shape != (3,) or A.shape != (3, 3):
        raise InputError(f"frame: expected r (3,) and A (3, 3), got {r.shape} and {A.shape}")
    return r, A


def elastic_displacement(body: FlexibleBody, q: np.ndarray) -> np.ndarray:
    """u = psi q reshaped to (n, 3): elastic displacement of every node in the body frame [m]."""
    n = len(body.X)
    q = np.asarray(q, dtype=float).ravel()
    if q.shape != (body.nq,):
        raise InputError(f"body {body.name!r}: expected q of shape ({body.nq},), got {q.shape}")
    if body.nq == 0:
        return np.zeros((n, 3))
    return np.asarray(body.psi @ q).reshape(n, 3)


def node_positions(body: FlexibleBody, r: np.ndarray, A: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Global node positions x_k = r + A (X_k + psi_k q), shape (n, 3) [m]."""
    r, A = _frame(r, A)
    return r + (body.X + elastic_displacement(body, q)) @ A.T


def reference_positions(body: FlexibleBody, r0: np.ndarray, A0: np.ndarray) -> np.ndarray:
    """The undeformed body at the frame (r0, A0): x0_k = r0 + A0 X_k, shape (n, 3) [m] (the
    points of a ParaView series, from which its displacement field is measured)."""
    r0, A0 = _frame(r0, A0)
    return r0 + body.X @ A0.T


def displacement(
    body: FlexibleBody, r: np.ndarray, A: np.ndarray, q: np.ndarray, r0: np.ndarray, A0: np.ndarray
) -> np.ndarray:
    """Global displacement x_k(r, A, q) - x0_k, shape (n, 3) [m], from the undeformed body at
    the initial frame: x0_k = r0 + A0 X_k. With x0 as mesh points, ParaView's Warp By Vector of
    this field gives the deformed body exactly (rigid motion included)."""
    return node_positions(body, r, A, q) - reference_positions(body, r0, A0)


def node_velocities(
    body: FlexibleBody,
    A: np.ndarray,
    q: np.ndarray,
    frame_v: np.ndarray,
    q_dot: np.ndarray | None = None,
) -> np.ndarray:
    """Global node velocities x_dot_k = r_dot + A (omega x s_k + psi_k q_dot), (n, 3) [m/s].

    frame_v = [r_dot (global), omega (body frame)] (6,); q_dot (nq,) or None for zero elastic
    rates (the frame part only).
    """
    _, A = _frame(np.zeros(3), A)
    fv = np.asarray(frame_v, dtype=float)
    if fv.shape != (6,):
        raise InputError(f"frame_v: expected [r_dot, omega] of shape (6,), got {fv.shape}")
    s = body.X + elastic_displacement(body, q)
    local = np.cross(fv[3:], s)
    if q_dot is not None:
        local = local + elastic_displacement(body, q_dot)
    return fv[:3] + local @ A.T


# von_mises_series takes as many fields at a time as keep their gradients within this [bytes]
SERIES_GRADIENT_BYTES = 32 << 20


@numba.njit(cache=True, nogil=True)
def _average_stress(h, conn, w, lam, mu, S):  # pragma: no cover - compiled
    """S[node, :, f] += w[node] sigma of h[c, p, :, :, f] = grad u (du_a/dx_i as [i, a]) at
    cell c's node p = conn[c, p]; sigma's six components (xx, yy, zz, xy, yz, zx)."""
    nc, npt, nf = h.shape[0], h.shape[1], h.shape[4]
    for c in range(nc):
        for p in range(npt):
            node = conn[c, p]
            wn = w[node]
            g = h[c, p]
            for k in range(nf):
                exx, eyy, ezz = g[0, 0, k], g[1, 1, k], g[2, 2, k]
                lt = lam * (exx + eyy + ezz)
                S[node, 0, k] += wn * (lt + 2.0 * mu * exx)
                S[node, 1, k] += wn * (lt + 2.0 * mu * eyy)
                S[node, 2, k] += wn * (lt + 2.0 * mu * ezz)
                S[node, 3, k] += wn * mu * (g[0, 1, k] + g[1, 0, k])
                S[node, 4, k] += wn * mu * (g[1, 2, k] + g[2, 1, k])
                S[node, 5, k] += wn * mu * (g[2, 0, k] + g[0, 2, k])


@numba.njit(cache=True, nogil=True)
def _von_mises_rows(S, out):  # pragma: no cover - compiled
    """out[f, node] = the von Mises stress of the six components S[node, :, f]:
    sqrt(((sxx - syy)^2 + (syy - szz)^2 + (szz - sxx)^2) / 2 + 3 (sxy^2 + syz^2 + szx^2))."""
    for node in range(S.shape[0]):
        for k in range(S.shape[2]):
            a, b, c = S[node, 0, k], S[node, 1, k], S[node, 2, k]
            d, e, f = S[node, 3, k], S[node, 4, k], S[node, 5, k]
            out[k, node] = np.sqrt(
                0.5 * ((a - b) ** 2 + (b - c) ** 2 + (c - a) ** 2) + 3.0 * (d * d + e * e + f * f)
            )


class StressOperator:
    """The linear map u_local (n, 3) [m] -> node-averaged small-strain stress (n, 3, 3) [Pa] of
    one mesh and material, built once (cell gradients, Jacobian inverses, averaging weights)
    and applied to many displacement fields (one batched product and one sparse average each).

    sigma = lambda tr(eps) I + 2 mu eps, eps = sym(grad u), grad u at each cell's own nodes from
    the isoparametric shape functions: grad u (c, p) = u[conn[c]]^T G[c, p] with
    G[c, p] = dN/dxi (p) (dx/dxi)^-1 (n_nodes_per_cell, 3). Raises InputError for an
    unsupported cell type, MeshError for a cell with a non-positive Jacobian at a node.
    """

    def __init__(self, mesh: Mesh, material: Material):
        self.n = n = mesh.n_nodes
        self.lam, self.mu = material.lame
        self._blocks = []  # (connectivity (c, k), G^T (c, p*3, k))
        rows, cols = [], []
        offset = 0
        for block in mesh.cells:
            if block.cell_type not in CELLS:
                raise InputError(
                    f"von Mises: cell type {block.cell_type.value!r} is not supported; expected "
                    f"one of {', '.join(ct.value for ct in CELLS)}"
                )
            conn = np.asarray(block.connectivity)
            if len(conn) == 0:
                continue
            # (p, k, 3) at the cell type's nodes
            grads = shape_gradients(block.cell_type, CELLS[block.cell_type].reference_nodes)
            p, k = grads.shape[0], grads.shape[1]
            Gt = np.empty((len(conn), p * 3, k))
            for lo in range(0, len(conn), _CHUNK):
                c = conn[lo : lo + _CHUNK]
                # jac[c, p, i, j] = dx_i/dxi_j = sum_n X[c, n, i] dN_n/dxi_j (p)
                jac = np.matmul(mesh.nodes[c].transpose(0, 2, 1)[:, None], grads[None])
                det = np.linalg.det(jac)
                if np.any(det <= 0.0):
                    bad = lo + int(np.argwhere(det <= 0.0)[0, 0])
                    raise MeshError(
                        f"{block.cell_type.value} cell {bad} has a non-positive Jacobian at a "
                        "node; expected a valid mesh (see mesh.quality.check_quality)"
                    )
                # G[c, p, n, i] = sum_j dN_n/dxi_j (J^-1)_ji, stored as (c, p, i, n)
                G = np.matmul(
                    np.linalg.inv(jac).transpose(0, 1, 3, 2), grads.transpose(0, 2, 1)[None]
                )
                Gt[lo : lo + _CHUNK] = G.reshape(len(c), p * 3, k)
            self._blocks.append((conn, Gt))
            rows.append(conn.ravel())
            cols.append(offset + np.arange(conn.size))
            offset += conn.size
        row = np.concatenate(rows) if rows else np.zeros(0, int)
        col = np.concatenate(cols) if cols else np.zeros(0, int)
        count = np.bincount(row, minlength=n).astype(float)
        self._node_weight = 1.0 / np.maximum(count, 1.0)  # (n,)
        w = self._node_weight[row]
        # average over the cells sharing a node (unweighted); nodes in no cell get zero
        self._average = sp.csr_matrix((w, (row, col)), shape=(n, offset))

    def nodal_stress(self, u_local: np.ndarray) -> np.ndarray:
        """Node-averaged stress (n, 3, 3) [Pa] of u_local (n, 3) or (3 n,) [m]."""
        n = self.n
        u = np.asarray(u_local, dtype=float)
        if u.shape == (3 * n,):
            u = u.reshape(n, 3)
        if u.shape != (n, 3):
            raise InputError(f"u_local: expected shape ({n}, 3) or ({3 * n},), got {u.shape}")
        parts = []
        eye = np.eye(3)
        for conn, Gt in self._blocks:
            h = np.matmul(Gt, u[conn])  # (c, p*3, 3): h[c, p, i, a] = du_a/dx_i
            h = h.reshape(len(conn), -1, 3, 3)
            eps = 0.5 * (h + np.swapaxes(h, -1, -2))
            tr = np.trace(eps, axis1=-2, axis2=-1)
            sig = self.lam * tr[..., None, None] * eye + 2.0 * self.mu * eps
            parts.append(sig.reshape(-1, 9))
        if not parts:
            return np.zeros((n, 3, 3))
        return (self._average @ np.concatenate(parts)).reshape(n, 3, 3)

    def von_mises(self, u_local: np.ndarray) -> np.ndarray:
        """Nodal von Mises stress (n,) [Pa] of the node-averaged stress of u_local."""
        return von_mises_of(self.nodal_stress(u_local))

    def von_mises_series(self, U: np.ndarray) -> np.ndarray:
        """von_mises of every field of U (k, n, 3) [m] -> (k, n) [Pa]: the gradients of all
        fields as the columns of one product per cell (BLAS-3), then one compiled pass that
        averages the stresses at the nodes and takes their von Mises stress; a few fields at a
        time, so that the gradients stay within ~32 MB."""
        U = np.asarray(U, dtype=float)
        if U.ndim != 3 or U.shape[1:] != (self.n, 3):
            raise InputError(f"U: expected shape (k, {self.n}, 3), got {U.shape}")
        k = len(U)
        out = np.zeros((k, self.n))
        if not self._blocks or not k:
            return out
        per_field = max(Gt.shape[0] * Gt.shape[1] * 3 * 8 for _, Gt in self._blocks)
        step = max(1, min(k, SERIES_GRADIENT_BYTES // per_field))
        for lo in range(0, k, step):
            f = min(step, k - lo)
            # (n, 3 f): node rows, (component, field) columns
            Uc = U[lo : lo + f].transpose(1, 2, 0).reshape(self.n, 3 * f)
            S = np.zeros((self.n, 6, f))
            for conn, Gt in self._blocks:
                c, p3 = Gt.shape[0], Gt.shape[1]
                h = np.matmul(Gt, Uc[conn])  # (c, p*3, 3 f): h[c, (p, i), (a, field)]
                _average_stress(
                    h.reshape(c, p3 // 3, 3, 3, f), conn, self._node_weight, self.lam, self.mu, S
                )
            _von_mises_rows(S, out[lo : lo + f])
        return out


def nodal_stress(mesh: Mesh, material: Material, u_local: np.ndarray) -> np.ndarray:
    """Node-averaged small-strain Cauchy stress (n, 3, 3) [Pa] of the elastic displacement
    u_local (n, 3) [m] (body frame, same frame as mesh.nodes).

    Each cell's stress is evaluated at its nodes from the isoparametric shape-function gradients
    and the values of all cells sharing a node are averaged. Nodes in no cell get zero. Supports
    every CellType (hexahedron, hexahedron27, tetra, tetra10, wedge). Raises InputError for a
    u_local of the wrong shape or an unsupported cell type, MeshError for a cell with a
    non-positive Jacobian at a node. For many fields on one mesh use :class:`StressOperator`.
    """
    n = mesh.n_nodes
    u = np.asarray(u_local, dtype=float)
    if u.shape not in ((3 * n,), (n, 3)):
        raise InputError(f"u_local: expected shape ({n}, 3) or ({3 * n},), got {u.shape}")
    return StressOperator(mesh, material).nodal_stress(u)


def von_mises_of(stress: np.ndarray) -> np.ndarray:
    """Von Mises stress sqrt(3/2 s:s), s the deviator, of stress tensors (..., 3, 3) [Pa]."""
    s = np.asarray(stress, dtype=float)
    dev = s - np.trace(s, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) / 3.0
    return np.sqrt(1.5 * np.einsum("...ij,...ij->...", dev, dev))


def von_mises(mesh: Mesh, material: Material, u_local: np.ndarray) -> np.ndarray:
    """Nodal von Mises stress (n,) [Pa] of the node-averaged stress (see :func:`nodal_stress`)."""
    return von_mises_of(nodal_stress(mesh, material, u_local))


@dataclass(frozen=True)
class NodalFields:
    """Fields of one body at one output time, node order of the body's mesh.

    reference: (n, 3) undeformed global positions at the initial frame, r0 + A0 X [m];
    displacement: (n, 3) global, from reference [m]; velocity: (n, 3) global [m/s];
    von_mises: (n,) [Pa].
    """

    reference: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    von_mises: np.ndarray


def body_geometry(body: FlexibleBody) -> Mesh:
    """The body's mesh with the body's own node coordinates X (what psi refers to)."""
    if body.mesh is None:
        raise InputError(f"body {body.name!r} has no mesh; expected a body built with mesh=...")
    if body.mesh.n_nodes != len(body.X):
        raise InputError(
            f"body {body.name!r}: mesh has {body.mesh.n_nodes} nodes, X has {len(body.X)}"
        )
    return Mesh(body.X, body.mesh.cells)


def nodal_fields(
    body: FlexibleBody,
    material: Material,
    r: np.ndarray,
    A: np.ndarray,
    q: np.ndarray,
    frame_v: np.ndarray,
    q_dot: np.ndarray | None,
    r0: np.ndarray,
    A0: np.ndarray,
    geometry: Mesh | None = None,
    *,
    stress: StressOperator | None = None,
    u: np.ndarray | None = None,
    u_dot: np.ndarray | None = None,
    von_mises: np.ndarray | None = None,
) -> NodalFields:
    """All nodal fields of `body` in state (r, A, q, [r_dot, omega], q_dot), displacement from
    the undeformed body at (r0, A0). geometry: :func:`body_geometry`, stress: its
    :class:`StressOperator`, u / u_dot: :func:`elastic_displacement` of q / q_dot (pass them
    to reuse them over many outputs), von_mises: its (n,) [Pa] when already known
    (StressOperator.von_mises_series of many outputs)."""
    geometry = body_geometry(body) if geometry is None else geometry
    stress = StressOperator(geometry, material) if stress is None else stress
    r, A = _frame(r, A)
    fv = np.asarray(frame_v, dtype=float)
    if fv.shape != (6,):
        raise InputError(f"frame_v: expected [r_dot, omega] of shape (6,), got {fv.shape}")
    u = elastic_displacement(body, q) if u is None else u
    s = body.X + u
    local = np.cross(fv[3:], s)
    if u_dot is None and q_dot is not None:
        u_dot = elastic_displacement(body, q_dot)
    if u_dot is not None:
        local = local + u_dot
    reference = reference_positions(body, r0, A0)
    return NodalFields(
        reference=reference,
        displacement=r + s @ A.T - reference,
        velocity=fv[:3] + local @ A.T,
        von_mises=stress.von_mises(u) if von_mises is None else von_mises,
    )
