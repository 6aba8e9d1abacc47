"""Compiled radial return and element assembly of small-strain J2 plasticity: the hot loops
of return_mapping.radial_return and body.PlasticBody.respond, on flat arrays.

The equations are return_mapping's (Simo and Hughes 1998, box 3.2 and eq. 3.3.13), written
per point with scalars so that a point allocates nothing; the assembly is body.py's

    f_int = sum_e sum_q B_q^T sigma_q dx_q,    K_t = sum_e sum_q B_q^T D_q B_q dx_q

with B never formed: column 3a + i of B_q (node a, component i) has three nonzeros, grad N_a
along i in normal row i and along the two other axes in the shear rows (_ROWS, _DERIV), so
D B costs 18 and B^T (D B) 3 multiply-adds per entry. The element tangent is symmetric (D of
associative J2 is), so its upper triangle is computed and added to both halves of the CSR
data through a precomputed slot map. Voigt order (xx, yy, zz, xy, yz, zx), engineering
shear strains, tensor-component stresses, as return_mapping.
"""

from __future__ import annotations

import math

import numba
import numpy as np

#: Rows of the nonzeros of B's column for displacement component i (normal row, two shears).
_ROWS = np.array([[0, 3, 5], [1, 3, 4], [2, 4, 5]], dtype=np.int64)
#: The derivative (x, y, z) of N_a in each of those rows: e_xy = du_x/dy + du_y/dx, ...
_DERIV = np.array([[0, 1, 2], [1, 0, 2], [2, 1, 0]], dtype=np.int64)
_SQRT_2_3 = math.sqrt(2.0 / 3.0)


@numba.njit(cache=True)
def _identity_dev(i, j):  # pragma: no cover - compiled
    """I_dev[i, j] = I_sym - 1 (x) 1 / 3 in the strain-to-stress Voigt pairing."""
    sym = 0.0
    if i == j:
        sym = 0.5 if i >= 3 else 1.0
    one = 1.0 if (i < 3 and j < 3) else 0.0
    return sym - one / 3.0


@numba.njit(cache=True)
def return_point(
    strain, eps_p, alpha, beta, mat, stress, tangent, eps_p_new, beta_new, xi
):  # pragma: no cover - compiled
    """Radial return of one point (Simo and Hughes box 3.2). strain, eps_p (6,) engineering
    shears; alpha the equivalent plastic strain; beta (6,) [Pa]; mat = (kappa, mu, Y, H_iso,
    H_kin) [Pa]. Writes stress (6,) [Pa], tangent (6, 6) [Pa], eps_p_new, beta_new (6,);
    xi (6,) is work space. Returns (alpha_new, yielding)."""
    kappa, mu, y, h_iso, h_kin = mat[0], mat[1], mat[2], mat[3], mat[4]
    e0 = strain[0] - eps_p[0]
    e1 = strain[1] - eps_p[1]
    e2 = strain[2] - eps_p[2]
    mean = (e0 + e1 + e2) / 3.0
    volumetric = kappa * (e0 + e1 + e2)
    norm2 = 0.0
    for k in range(6):
        e = strain[k] - eps_p[k]
        dev = e - mean if k < 3 else 0.5 * e  # dev of the tensor-component elastic strain
        stress[k] = 2.0 * mu * dev  # the trial deviator s_tr
        xi[k] = stress[k] - beta[k]
        norm2 += (1.0 if k < 3 else 2.0) * xi[k] * xi[k]
    norm = math.sqrt(norm2)
    f_trial = norm - _SQRT_2_3 * (y + h_iso * alpha)
    yielding = f_trial > 0.0
    dgam, theta, theta_bar = 0.0, 1.0, 0.0
    if yielding:
        dgam = f_trial / (2.0 * mu + (2.0 / 3.0) * (h_iso + h_kin))
        theta = 1.0 - 2.0 * mu * dgam / norm
        theta_bar = 1.0 / (1.0 + (h_iso + h_kin) / (3.0 * mu)) - (1.0 - theta)
        for k in range(6):
            xi[k] = xi[k] / norm  # the flow direction n
    for k in range(6):
        step = dgam * xi[k]
        stress[k] = stress[k] - 2.0 * mu * step + (volumetric if k < 3 else 0.0)
        eps_p_new[k] = eps_p[k] + step * (1.0 if k < 3 else 2.0)
        beta_new[k] = beta[k] + (2.0 / 3.0) * h_kin * step
    c_dev, c_n = 2.0 * mu * theta, 2.0 * mu * theta_bar
    for i in range(6):
        for j in range(6):
            one = 1.0 if (i < 3 and j < 3) else 0.0
            d = kappa * one + c_dev * _identity_dev(i, j)
            if yielding:
                d -= c_n * (xi[i] * xi[j])
            tangent[i, j] = d
    return alpha + _SQRT_2_3 * dgam, yielding


@numba.njit(cache=True)
def return_points(
    strain, eps_p, alpha, beta, mat, stress, tangent, eps_p_new, alpha_new, beta_new, yielding
):  # pragma: no cover - compiled
    """return_point over n points: strain, eps_p, beta (n, 6), alpha (n,); outputs stress,
    eps_p_new, beta_new (n, 6), tangent (n, 6, 6), alpha_new (n,), yielding (n,) bool."""
    xi = np.empty(6)
    for p in range(strain.shape[0]):
        a, y = return_point(
            strain[p],
            eps_p[p],
            alpha[p],
            beta[p],
            mat,
            stress[p],
            tangent[p],
            eps_p_new[p],
            beta_new[p],
            xi,
        )
        alpha_new[p] = a
        yielding[p] = y


@numba.njit(cache=True)
def _point_strain(g, ue, strain):  # pragma: no cover - compiled
    """strain (6,) = B u_e from grad N (nloc, 3) at the point and u_e (3 nloc,)."""
    strain[:] = 0.0
    for a in range(g.shape[0]):
        for i in range(3):
            u = ue[3 * a + i]
            for m in range(3):
                strain[_ROWS[i, m]] += g[a, _DERIV[i, m]] * u


@numba.njit(cache=True)
def _add_point(g, stress, tangent, w, fe, ke, db):  # pragma: no cover - compiled
    """fe += B^T stress w, upper triangle of ke += B^T (D w) B, for grad N g (nloc, 3);
    db (6, 3 nloc) is work space."""
    nd = 3 * g.shape[0]
    for a in range(g.shape[0]):
        for i in range(3):
            col = 3 * a + i
            acc = 0.0
            for m in range(3):
                acc += g[a, _DERIV[i, m]] * stress[_ROWS[i, m]]
            fe[col] += acc * w
            for r in range(6):  # (D w) B: three columns of D per column of B
                s = 0.0
                for m in range(3):
                    s += tangent[r, _ROWS[i, m]] * g[a, _DERIV[i, m]]
                db[r, col] = s * w
    for a in range(g.shape[0]):
        for i in range(3):
            k = 3 * a + i
            r0, r1, r2 = _ROWS[i, 0], _ROWS[i, 1], _ROWS[i, 2]
            b0, b1, b2 = g[a, _DERIV[i, 0]], g[a, _DERIV[i, 1]], g[a, _DERIV[i, 2]]
            for col in range(k, nd):
                ke[k, col] += b0 * db[r0, col] + b1 * db[r1, col] + b2 * db[r2, col]


@numba.njit(cache=True)
def block_response(
    nodes,
    grad,
    dx,
    u,
    eps_p,
    alpha,
    beta,
    mat,
    slots,
    force,
    data,
    stress,
    eps_p_new,
    alpha_new,
    beta_new,
    yielding,
):  # pragma: no cover - compiled
    """One cell block: nodes (ne, nloc), grad N (ne, nloc, 3, nqp) [1/m], dx (ne, nqp) [m^3],
    u (3n,) [m], the points' state eps_p, beta (ne nqp, 6), alpha (ne nqp,) cell-major and
    mat as return_point. Adds the element forces to force (3n,) [N] and the element tangents
    to data[slots[e]] (slots (ne, 3 nloc, 3 nloc): CSR positions), writes the points' stress,
    new state and yielding."""
    ne, nloc, _, nqp = grad.shape
    nd = 3 * nloc
    ue, fe, ke = np.empty(nd), np.empty(nd), np.empty((nd, nd))
    g, strain, tangent = np.empty((nloc, 3)), np.empty(6), np.empty((6, 6))
    db, xi = np.empty((6, nd)), np.empty(6)
    for e in range(ne):
        for a in range(nloc):
            for i in range(3):
                ue[3 * a + i] = u[3 * nodes[e, a] + i]
        fe[:] = 0.0
        ke[:, :] = 0.0
        for q in range(nqp):
            p = e * nqp + q
            for a in range(nloc):
                for j in range(3):
                    g[a, j] = grad[e, a, j, q]
            _point_strain(g, ue, strain)
            alpha_new[p], yielding[p] = return_point(
                strain,
                eps_p[p],
                alpha[p],
                beta[p],
                mat,
                stress[p],
                tangent,
                eps_p_new[p],
                beta_new[p],
                xi,
            )
            _add_point(g, stress[p], tangent, dx[e, q], fe, ke, db)
        for a in range(nloc):
            for i in range(3):
                force[3 * nodes[e, a] + i] += fe[3 * a + i]
        for k in range(nd):
            data[slots[e, k, k]] += ke[k, k]
            for col in range(k + 1, nd):
                data[slots[e, k, col]] += ke[k, col]
                data[slots[e, col, k]] += ke[k, col]


@numba.njit(cache=True)
def block_returns(
    nodes, grad, u, eps_p, alpha, beta, mat, stress, eps_p_new, alpha_new, beta_new, yielding
):  # pragma: no cover - compiled
    """block_response's returns alone (the same strains and return_point, so the same stress
    and state, bit for bit), without the element forces and tangents: what a time step's
    correction needs (plasticity.step_history), whose force is that of the plastic strain."""
    ne, nloc, _, nqp = grad.shape
    ue, g = np.empty(3 * nloc), np.empty((nloc, 3))
    strain, tangent, xi = np.empty(6), np.empty((6, 6)), np.empty(6)
    for e in range(ne):
        for a in range(nloc):
            for i in range(3):
                ue[3 * a + i] = u[3 * nodes[e, a] + i]
        for q in range(nqp):
            p = e * nqp + q
            for a in range(nloc):
                for j in range(3):
                    g[a, j] = grad[e, a, j, q]
            _point_strain(g, ue, strain)
            alpha_new[p], yielding[p] = return_point(
                strain,
                eps_p[p],
                alpha[p],
                beta[p],
                mat,
                stress[p],
                tangent,
                eps_p_new[p],
                beta_new[p],
                xi,
            )
