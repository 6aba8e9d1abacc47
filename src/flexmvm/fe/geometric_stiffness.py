"""Geometric stiffness of a prestressed solid, and the prestress of a steady spin.

A body under an initial Cauchy stress sigma_0 gains the stiffness of the nonlinear part of the
Green-Lagrange strain worked by that stress (the initial-stress matrix; Bathe, *Finite Element
Procedures*, 1996, sec. 6.3.2, the matrix K_NL = int G^T S G dV; Zienkiewicz and Taylor,
*The Finite Element Method* vol. 2, the initial-stress matrix):

    K_G[3a + i, 3b + j] = delta_ij  int_e  grad N_a . sigma_0 grad N_b  dV

so K_G = kron(S_G, I3) with the scalar (n, n) matrix S_G_ab = sum_e int grad N_a^T sigma_0
grad N_b dV, integrated on the Gauss rule of fe.assembly (the same scikit-fem bases, so the
element types are those the package assembles: hex8, hex27, wedge6, tet4, tet10).

Prestress of a steady spin (Wallrapp and Schwertassek 1991, "Representation of geometric
stiffening in multibody system simulation", Int. J. Numer. Meth. Eng. 32, 1833-1850): the
static solution of the centrifugal body force of a unit spin (1 rad/s) about the axis n
through the point p, with the body's supports,

    K u_1 = f_1,     f_1 = int N^T rho (I - n n^T)(X - p) dV = M r_perp

(exact for the consistent mass: the distance r_perp is linear in X, which the isoparametric
shape functions interpolate exactly), sigma_1 = D eps(u_1) at the Gauss points, and
K_G(Omega) = Omega^2 K_G(sigma_1): the stress of a steady spin scales with Omega^2.
Units: f_1 [N s^2] (N per (rad/s)^2), u_1 [m s^2], sigma_1 [Pa s^2], K_G(sigma_1) [kg]
(N/m per (rad/s)^2).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from flexmvm.errors import InputError
from flexmvm.fe.assembly import ELEMENT_CHUNK, FEModel, block_basis, scatter, shape_arrays
from flexmvm.fe.solvers import spd_solver


def spin_axis(axis) -> np.ndarray:
    """The unit vector (3,) of a spin axis; InputError for a zero or non-finite vector."""
    n = np.asarray(axis, dtype=float).reshape(-1)
    norm = float(np.linalg.norm(n)) if n.shape == (3,) else 0.0
    if not (np.isfinite(norm) and norm > 0.0):
        raise InputError(f"spin axis must be a non-zero 3-vector, got {np.asarray(axis).tolist()}")
    return n / norm


def centrifugal_load(fe: FEModel, axis, point=(0.0, 0.0, 0.0)) -> np.ndarray:
    """f_1 = M r_perp (3n,) [N s^2]: the consistent nodal load of the centrifugal body force
    rho Omega^2 r_perp of a unit spin about ``axis`` through ``point`` (body frame [m]),
    r_perp = (I - n n^T)(X - p) the distance vector from the axis (module doc)."""
    n = spin_axis(axis)
    rel = fe.mesh.nodes - np.asarray(point, dtype=float)
    r_perp = rel - np.outer(rel @ n, n)
    return np.asarray(fe.M @ r_perp.ravel()).ravel()


def static_displacement(fe: FEModel, load: np.ndarray, fixed_dofs) -> np.ndarray:
    """u (3n,) [m] of K u = load with the DOFs ``fixed_dofs`` held at zero (one sparse
    factorization of K's free block). Raises InputError for DOF ids outside the model or
    supports that leave a rigid motion free (a singular K_ff)."""
    n_dof = fe.n_dof
    fixed = np.unique(np.asarray(fixed_dofs, dtype=np.int64))
    if not fixed.size or fixed[0] < 0 or fixed[-1] >= n_dof:
        raise InputError(f"supports must be DOF ids in 0..{n_dof - 1}, got {fixed.tolist()[:12]}")
    free = np.setdiff1d(np.arange(n_dof), fixed)
    K = sp.csr_matrix(fe.K)
    k_ff = sp.csr_matrix(K[free][:, free])
    u = np.zeros(n_dof)
    u[free] = np.asarray(spd_solver(k_ff)(np.ascontiguousarray(load[free]))).ravel()
    residual = float(np.abs(k_ff @ u[free] - load[free]).max())
    if not residual <= 1e-6 * max(float(np.abs(load).max()), 1e-300):
        raise InputError(
            f"the supports {fixed.size} DOFs leave the body free to move: K u = f not solvable "
            f"(relative residual {residual / max(float(np.abs(load).max()), 1e-300):.2e})"
        )
    return u


def _point_stress(grad: np.ndarray, u_cells: np.ndarray, lam: float, mu: float) -> np.ndarray:
    """Cauchy stress (ne, nqp, 3, 3) [Pa] of the cells' nodal displacements u_cells (ne, nloc,
    3) at their Gauss points (grad N (ne, nloc, 3, nqp)): isotropic Hooke law."""
    H = np.einsum("eai,eajq->eqij", u_cells, grad)  # displacement gradient du_i/dx_j
    eps = 0.5 * (H + np.swapaxes(H, 2, 3))
    tr = np.trace(eps, axis1=2, axis2=3)
    return 2.0 * mu * eps + lam * tr[:, :, None, None] * np.eye(3)


def _scalar_geometric(grad: np.ndarray, sigma: np.ndarray, dx: np.ndarray) -> np.ndarray:
    """S_G of the cells (ne, nloc, nloc): sum_q dx_q grad N_a^T sigma_q grad N_b."""
    sg = np.einsum("eqkl,eblq->ebkq", sigma, grad)  # sigma grad N_b (ne, nloc, 3, nqp)
    return np.einsum("eakq,ebkq,eq->eab", grad, sg, dx)


def prestress_geometric_stiffness(fe: FEModel, u: np.ndarray) -> sp.csr_matrix:
    """K_G(sigma_0) (3n, 3n) csr [N/m] of the prestress sigma_0 = D eps(u) of the static
    displacement u (3n,) [m] (module doc): the stress at each Gauss point from u, integrated
    on the cells of every block of fe.mesh, in chunks of fe.assembly's size."""
    mesh = fe.mesh
    n = mesh.n_nodes
    lam, mu = fe.material.lame
    u_nodes = np.asarray(u, dtype=float).reshape(n, 3)
    s_sum = sp.csr_matrix((n, n))
    for block in mesh.cells:
        if len(block.connectivity) == 0:
            continue
        basis, dof_to_node = block_basis(mesh.nodes, block)
        cell_nodes = dof_to_node[basis.element_dofs.T]  # (ne, nloc) our node ids
        for start in range(0, len(cell_nodes), ELEMENT_CHUNK):
            sub = slice(start, start + ELEMENT_CHUNK)
            _, grad, dx = shape_arrays(basis, sub)
            sigma = _point_stress(grad, u_nodes[cell_nodes[sub]], lam, mu)
            s_sum = s_sum + scatter(_scalar_geometric(grad, sigma, dx), cell_nodes[sub], n)
    s_sum = 0.5 * (s_sum + s_sum.T)
    return sp.csr_matrix(sp.kron(s_sum, sp.identity(3, format="csr"), format="csr"))


def spin_geometric_stiffness(
    fe: FEModel, axis, fixed_dofs, point=(0.0, 0.0, 0.0)
) -> tuple[sp.csr_matrix, np.ndarray]:
    """(K_G(sigma_1) (3n, 3n) csr [kg], u_1 (3n,) [m s^2]): the geometric stiffness of the
    prestress of a unit spin about ``axis`` through ``point`` (body frame [m]) and the static
    displacement it comes from, the body held at ``fixed_dofs`` (a clamped root, or the six
    DOFs of its 3-2-1 reference condition). K_G(Omega) = Omega^2 K_G(sigma_1) (module doc)."""
    u1 = static_displacement(fe, centrifugal_load(fe, axis, point), fixed_dofs)
    return prestress_geometric_stiffness(fe, u1), u1


__all__ = [
    "centrifugal_load",
    "prestress_geometric_stiffness",
    "spin_axis",
    "spin_geometric_stiffness",
    "static_displacement",
]
