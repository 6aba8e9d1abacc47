"""The massless coordinates' equilibrium at a step's end in compiled kernels (issue 49 item 3).

integrate.moreau_jean.massless.equilibrate_step_end computes, per body with massless coordinates s and
a dense K_ss factor, the force on them (Phi_s^T lambda / h + f_s), the free change
dq0 = K_ss^-1 (force - K_sn q_n), the held rows' columns P = Phi_s and Y = K_ss^-1 P^T, then
over the bodies D = sum P Y and the multipliers mu of the held rows, and per body
dq = dq0 - Y mu, the end position and the mean velocity of the massless coordinates and the
changes k_hat dq, k_hat dq_dot of the carried products. As numpy and scipy calls that is ~60
calls of 5-30 us a step for two bodies (1.4 ms of the seed all-MVM step, profiled); here it
is per body three kernel calls (`body_part`, `add_delassus`, `body_update`) and one dpotrs
with all the right-hand sides [force - K_sn q_n, P^T] at once, and the Delassus factor of the
held rows. The same sums as the reference path, some in another order (Phi_s^T lambda, the
Delassus products): equal to round-off (tests/test_compiled_step.py). The K_ss solves stay
in LAPACK: b1's are 171 x 171 with tens of right-hand sides, where dpotrs (blocked) is ~5 x
faster than a compiled loop.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def body_part(q, k_ptr, k_idx, k_val, s, E, lam, on, h, f_s):  # pragma: no cover - compiled
    """One body's right-hand sides B (ns, 1 + m_on) (Fortran order, for dpotrs) and the rows
    with a nonzero column s (m_on,): B[:, 0] = E[:, s]^T lam / h + f_s - K_s q, the force
    on the massless coordinates s less K_sn q_n (E (m, nq) the held rows' elastic block,
    K_s = (k_ptr, k_idx, k_val) the CSR rows s of k_hat), B[:, 1 + k] = P[k] = E[i_k, s]
    over the rows i_k with on[i] (an impulse)."""
    ns, m = s.shape[0], lam.shape[0]
    m_on = 0
    for i in range(m):
        if on[i]:
            m_on += 1
    Bt = np.empty((1 + m_on, ns))
    force = np.zeros(ns)
    for i in range(m):  # by rows of E (C order)
        li = lam[i]
        for j in range(ns):
            force[j] += E[i, s[j]] * li
    for j in range(ns):
        kq = 0.0
        for e in range(k_ptr[j], k_ptr[j + 1]):
            kq += k_val[e] * q[k_idx[e]]
        Bt[0, j] = (force[j] / h + f_s[j]) - kq
    nonzero = np.zeros(m_on, dtype=np.bool_)
    k = 0
    for i in range(m):
        if on[i]:
            for j in range(ns):
                x = E[i, s[j]]
                Bt[1 + k, j] = x
                if x != 0.0:
                    nonzero[k] = True
            k += 1
    return Bt.T, nonzero


@numba.njit(cache=True, nogil=True)
def add_delassus(B, X, keep, D, rhs):  # pragma: no cover - compiled
    """D += P_k Y_k and rhs += P_k dq0 over the kept rows k (keep: their indices), with
    P_k = B[:, 1 + k], Y_k = X[:, 1 + k] = K_ss^-1 P_k and dq0 = X[:, 0]. P K_ss^-1 P^T is
    symmetric: its upper triangle is computed and mirrored (the reference path symmetrizes
    the full product: the same to round-off)."""
    n = keep.shape[0]
    ns = B.shape[0]
    for a in range(n):
        ka = 1 + keep[a]
        acc = 0.0
        for j in range(ns):
            acc += B[j, ka] * X[j, 0]
        rhs[a] += acc
        for b in range(a, n):
            kb = 1 + keep[b]
            acc = 0.0
            for j in range(ns):
                acc += B[j, ka] * X[j, kb]
            D[a, b] += acc
            if b != a:
                D[b, a] += acc


@numba.njit(cache=True, nogil=True)
def body_update(q, qd, q0, s, X, keep, mu, h, c_ptr, c_idx, c_val, n_rows):  # pragma: no cover
    """dq = dq0 - Y[:, keep] mu (dq0 = X[:, 0], Y = X[:, 1:]) onto q[s] (in place), the mean
    velocity (q[s] - q0[s]) / h onto qd[s] (in place); returns (dq, dv, K_cols dq,
    K_cols dv), dv the change of qd[s] and K_cols = (c_ptr, c_idx, c_val) the CSC columns s
    of k_hat (n_rows rows)."""
    ns = s.shape[0]
    y_mu = np.zeros(ns)
    for a in range(keep.shape[0]):  # by columns of X (Fortran order)
        ka, mu_a = 1 + keep[a], mu[a]
        for j in range(ns):
            y_mu[j] += X[j, ka] * mu_a
    dq = np.empty(ns)
    for j in range(ns):
        dq[j] = X[j, 0] - y_mu[j]
    dv = np.empty(ns)
    for j in range(ns):
        i = s[j]
        q[i] += dq[j]
        v_s = (q[i] - q0[i]) / h
        dv[j] = v_s - qd[i]
        qd[i] = v_s
    k_dq = np.zeros(n_rows)
    k_dv = np.zeros(n_rows)
    for j in range(ns):
        for e in range(c_ptr[j], c_ptr[j + 1]):
            k_dq[c_idx[e]] += c_val[e] * dq[j]
            k_dv[c_idx[e]] += c_val[e] * dv[j]
    return dq, dv, k_dq, k_dv
