"""Massless elastic coordinates held in equilibrium at the end of every step.

Mass redistribution on the contact boundary (fe.mass_redistribution; Khenous, Laborde and
Renard 2008) leaves the contact nodes of a full-FE body without mass: their rows of M_qq are
zero, and with them every inertia term of the floating frame (the inertia invariants are
mass-weighted). Their rows of the Moreau-Jean step (moreau_jean/scheme.py) are then algebraic,

    0 = h F_s(x_m) + (Phi^T lambda)_s,        F_s = -(k_hat q)_s + f_s,

equilibrium at the midpoint configuration q_m = q + theta h v_m. The end position q(t + h) =
q + h v_m is an extrapolation of it, q(t + h) - q_m = ((1 - theta) / theta) (q_m - q(t)): a
node whose q(t) is off the equilibrium alternates about it from step to step, undamped at
theta = 1/2 (amplification -1), and its end velocity v+ = (v_m - (1 - theta) v-) / theta
alternates with it and grew without bound in the position-law runs of docs/contact_law.md.

The cure is the one of the Newmark schemes with redistributed mass (Khenous et al. 2008,
whose equation of motion holds at the time nodes): the massless coordinates are in
equilibrium at the end of the step. After the step, with the massive coordinates at their
end values q_n and the constraint impulses of the step acting as the force lambda / h,

    K_ss q_s = (Phi^T lambda)_s / h + f_s - K_sn q_n        (one solve with K_ss, factored once)

and their velocity is the step's mean velocity (q_s(t + h) - q_s(t)) / h (they carry no
momentum and no kinetic energy, so v+ is no state of theirs: it enters only the next step's
contact prediction). Without contact (and linear elasticity) the end positions of the
midpoint step are already in equilibrium when the start ones are, so this changes nothing;
it acts only where the contact force changes. Linear and angular momentum are unchanged (no
mass moves); the strain energy of the alternation is removed.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from flexmvm.errors import SolverError
from flexmvm.fe.solvers.cholesky import ldl_factor
from flexmvm.integrate.moreau_jean.dense_solve import cho_solve
from flexmvm.integrate.moreau_jean.lcp import regularised_cho
from flexmvm.integrate.moreau_jean.massless_kernels import add_delassus, body_part, body_update
from flexmvm.loads.applied import applied_forces


@dataclass
class MasslessCoordinates:
    """The elastic coordinates s of one body with zero rows in M_qq and the factor of K_ss."""

    s: np.ndarray  # (ns,) indices into q
    K_s: sp.csr_matrix  # rows s of k_hat (ns, nq)
    K_cols: sp.csc_matrix  # columns s of k_hat (nq, ns)
    solve: Callable[[np.ndarray], np.ndarray]  # x = K_ss^-1 b
    # (c, lower): K_ss's dense Cholesky factor (the compiled path)
    cho: tuple[np.ndarray, bool] | None = None

    @classmethod
    def of(cls, body) -> MasslessCoordinates | None:
        """The massless coordinates of body, or None if it has none: a full-FE body's
        redistributed contact nodes, the nodal coordinates of the seed eq. (4) kinds'
        region II (identity columns), or a Craig-Bampton body's redistributed retained nodes
        (their constraint modes split into the nodal unit vector and a static column:
        reduction/basis.py)."""
        if not body.nq:
            return None
        if body.is_sparse:
            M = sp.csr_matrix(body.inv.M_qq)
            row_abs = np.asarray(abs(M).sum(axis=1)).ravel()
        else:
            row_abs = np.abs(np.asarray(body.inv.M_qq)).sum(axis=1)
        s = np.flatnonzero(row_abs == 0.0)
        if not s.size:
            return None
        if body.c_hat is not None and np.any(np.asarray(abs(sp.csr_matrix(body.c_hat)[s]).sum())):
            # damped massless coordinates are not algebraic (C_ss q_s' + K_ss q_s = f_s);
            # mass-proportional and modal damping leave them undamped (bodies.damping)
            raise SolverError(
                f"body {body.name!r}: massless (mass-redistributed) contact nodes with "
                "stiffness-proportional damping are not supported (beta_s = 0, or modal "
                "ratios, leave them undamped)"
            )
        if body.stiffening is not None:
            raise SolverError(
                f"body {body.name!r}: massless (mass-redistributed) contact nodes "
                "with geometric stiffening are not supported"
            )
        K = sp.csr_matrix(body.k_hat)
        K_s = K[s]
        cho = None
        K_ss = sp.csc_matrix(K_s[:, s])
        try:
            if body.is_sparse:
                solve = ldl_factor(K_ss)
            else:
                cho = sla.cho_factor(K_ss.toarray())
                # dpotrs straight (dense_solve): scipy's cho_solve, bit for bit
                solve = lambda b, cho=cho: cho_solve(cho, b)
        except (SolverError, np.linalg.LinAlgError) as exc:
            raise SolverError(
                f"body {body.name!r}: stiffness of the massless contact nodes is singular ({exc})"
            ) from None
        return cls(s, K_s, sp.csc_matrix(K_s.T), solve, cho)

    def free_change(self, q: np.ndarray, force_s: np.ndarray) -> np.ndarray:
        """dq_s (ns,) that brings q[s] to K_ss q_s = force_s - K_sn q_n, the other
        coordinates as they are (no constraint held)."""
        return np.asarray(self.solve(force_s - csr_times(self.K_s, q))).ravel()

    def k_times(self, dq: np.ndarray) -> np.ndarray:
        """K_cols dq (nq,): the change of k_hat q when the massless coordinates move by dq."""
        K = self.K_cols
        return _csc_matvec(K.indptr, K.indices, K.data, np.ascontiguousarray(dq), K.shape[0])


def csr_times(K: sp.csr_matrix, x: np.ndarray) -> np.ndarray:
    """K @ x (K csr): scipy's csr_matvec in the same order (bit for bit), without its ~20 us
    of dispatch per call (four such products a step)."""
    return _csr_matvec(K.indptr, K.indices, K.data, np.ascontiguousarray(x, dtype=float))


@numba.njit(cache=True, nogil=True)
def _csr_matvec(indptr, indices, data, x):  # pragma: no cover - compiled
    m = indptr.shape[0] - 1
    y = np.zeros(m)
    for i in range(m):
        acc = 0.0
        for e in range(indptr[i], indptr[i + 1]):
            acc += data[e] * x[indices[e]]
        y[i] = acc
    return y


@numba.njit(cache=True, nogil=True)
def _csc_matvec(indptr, indices, data, x, n_rows):  # pragma: no cover - compiled
    """scipy's csc_matvec (column by column, y[row] += a x[col]), bit for bit."""
    y = np.zeros(n_rows)
    for j in range(indptr.shape[0] - 1):
        xj = x[j]
        for e in range(indptr[j], indptr[j + 1]):
            y[indices[e]] += data[e] * xj
    return y


def equilibrate(
    parts: list[tuple[MasslessCoordinates, np.ndarray, np.ndarray, np.ndarray]],
) -> list[np.ndarray]:
    """Changes dq_s of the massless coordinates of several bodies: equilibrium at the end of
    the step with the constraint rows that carried an impulse held,

        K_ss dq_s + Phi_s^T mu = r_s  (per body),    sum_b Phi_b,s dq_b,s = 0,

    so the step's closed contacts stay closed (their gaps unchanged: no penetration is made
    that the next step would push out, doing work) and the impulses lambda / h do no work on
    dq (minimum of the strain energy under fixed forces: the projection only dissipates).
    parts: per body (coordinates, q (nq,), force_s (ns,), Phi_s (m, ns) the held rows'
    columns s, m the same for every body). Returns dq_s per body; q is not changed."""
    dq0 = [ml.free_change(q, f) for ml, q, f, _ in parts]
    m = parts[0][3].shape[0] if parts else 0
    if not m:
        return dq0
    Y = [
        np.asarray(ml.solve(np.ascontiguousarray(P.T))).reshape(len(ml.s), m)
        for ml, _, _, P in parts
    ]
    D = sum((P @ y for (_, _, _, P), y in zip(parts, Y)), np.zeros((m, m)))
    rhs = sum((P @ d for (_, _, _, P), d in zip(parts, dq0)), np.zeros(m))
    mu = cho_solve(regularised_cho(0.5 * (D + D.T), "massless-node"), rhs)
    return [d - y @ mu for d, y in zip(dq0, Y)]


def check_contact_law(system, massless: list[MasslessCoordinates | None]) -> None:
    """SolverError when a contact under a law for contact nodes with mass (the velocity law:
    ContactLawSpec.massless_nodes) touches a body with massless coordinates (massless: per
    body, MasslessCoordinates.of)."""
    for provider in system.contacts:
        sides = (provider.slave, provider.master)
        if not provider.law.spec.massless_nodes and any(massless[b] is not None for b in sides):
            raise SolverError(
                "massless (mass-redistributed) contact nodes need the position "
                f"contact law: under the {provider.law} law their velocities flip "
                "every step (docs/contact_law.md)"
            )


def equilibrate_step_end(
    massless, bodies, loads: tuple, t_theta: float, h: float, states, new_states, held
) -> list[tuple]:
    """Massless coordinates of every body to equilibrium at the step's end (module doc),
    under the step's constraint impulses as forces lambda / h and the point loads acting at
    t_theta = t + theta h, with the rows that carried an impulse held; their velocity the
    step's mean velocity. new_states are changed in place. held: [(rows, lambda)] of the
    step's constraints (contact, joints). Returns [(body, dq_s, dq_dot_s, K_cols dq_s,
    K_cols dq_dot_s)]: the changes made, and those of the quantities carried with the state
    (k_hat q and k_hat q_dot)."""
    todo = [b for b, ml in enumerate(massless) if ml is not None]
    if not todo:
        return []
    held = [
        (rows, lam, np.flatnonzero(lam != 0.0))
        for rows, lam in held
        if rows is not None and lam is not None and len(lam)
    ]
    applied = applied_forces(loads, bodies, new_states, t_theta)
    if all(massless[b].cho is not None for b in todo):
        return _compiled_step_end(massless, todo, applied, h, states, new_states, held)
    return _reference_step_end(massless, todo, applied, h, states, new_states, held)


def _reference_step_end(massless, todo, applied, h, states, new_states, held) -> list:
    """equilibrate_step_end through equilibrate (any K_ss factor: sparse bodies' LDL^T)."""
    parts = [_step_end_part(massless[b], b, new_states[b], applied.get(b), h, held) for b in todo]
    # rows with no massless column in any body impose nothing here
    if parts and parts[0][3].shape[0]:
        keep = np.any(np.hstack([p[3] for p in parts]) != 0.0, axis=1)
        parts = [(ml, q, f, P[keep]) for ml, q, f, P in parts]
    changes = []
    for b, (ml, q, _, _), dq in zip(todo, parts, equilibrate(parts)):
        st, new = states[b], new_states[b]
        q[ml.s] += dq
        qd = new.v[6:]
        v_s = (q[ml.s] - st.q[ml.s]) / h
        dv = v_s - qd[ml.s]
        qd[ml.s] = v_s
        changes.append((b, dq, dv, ml.k_times(dq), ml.k_times(dv)))
    return changes


def _compiled_step_end(massless, todo, applied, h, states, new_states, held) -> list:
    """equilibrate_step_end for bodies whose K_ss has a dense factor, in the compiled kernels
    of integrate.moreau_jean.massless_kernels (the same sums, equal to round-off)."""
    m = sum(len(lam) for _, lam, _ in held)
    on = np.zeros(m, dtype=np.bool_)
    lam_all = np.zeros(m)
    offset = 0
    for _, lam, nz in held:
        on[offset + nz] = True
        lam_all[offset : offset + len(lam)] = lam
        offset += len(lam)
    parts = []
    for b in todo:
        ml, new = massless[b], new_states[b]
        blocks = [rows.blocks.get(b) for rows, _, _ in held]
        if len(held) == 1 and blocks[0] is not None:
            E = np.ascontiguousarray(blocks[0][1], dtype=float)
        else:
            E = np.zeros((m, len(new.q)))
            offset = 0
            for blk, (_, lam, _) in zip(blocks, held):
                if blk is not None:
                    E[offset : offset + len(lam)] = blk[1]
                offset += len(lam)
        f = applied.get(b)
        f_s = np.zeros(len(ml.s)) if f is None else np.ascontiguousarray(f[6:][ml.s])
        K = ml.K_s
        B, nonzero = body_part(new.q, K.indptr, K.indices, K.data, ml.s, E, lam_all, on, h, f_s)
        parts.append((B, cho_solve(ml.cho, B), nonzero))  # [dq0, Y]: one dpotrs
    keep = np.zeros(int(on.sum()), dtype=np.bool_)
    for part in parts:
        keep |= part[2]
    kept = np.flatnonzero(keep)
    mu = np.zeros(0)
    if kept.size:
        D, rhs = np.zeros((kept.size, kept.size)), np.zeros(kept.size)
        for B, X, _ in parts:
            add_delassus(B, X, kept, D, rhs)
        mu = cho_solve(regularised_cho(0.5 * (D + D.T), "massless-node"), rhs)
    changes = []
    for b, (_, X, _) in zip(todo, parts):
        ml, new = massless[b], new_states[b]
        Kc = ml.K_cols
        made = body_update(
            new.q, new.v[6:], states[b].q, ml.s, X, kept, mu, h,
            Kc.indptr, Kc.indices, Kc.data, Kc.shape[0],
        )  # fmt: skip
        changes.append((b, *made))
    return changes


def _step_end_part(ml: MasslessCoordinates, b: int, new, f_applied, h: float, held) -> tuple:
    """(coordinates, q, force on them, held rows' columns) of body b for equilibrate."""
    force = np.zeros(len(ml.s))  # on the massless coordinates only
    Phi = [np.zeros((len(on), len(ml.s))) for _, _, on in held]
    for k, (rows, lam, on) in enumerate(held):
        blk = rows.blocks.get(b)
        if blk is not None:
            cols = blk[1][:, ml.s]
            force += cols.T @ lam
            Phi[k] = cols[on]
    force /= h
    if f_applied is not None:
        force += f_applied[6:][ml.s]
    P = np.vstack(Phi) if Phi else np.zeros((0, len(ml.s)))
    return ml, new.q, force, P
