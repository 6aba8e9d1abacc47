"""The truncation guard of a Craig-Bampton body (issue 51): the time scale of the inertia its
cut modes miss at the contact patch, against the contact's duration.

A Craig-Bampton basis is statically exact for loads on its retained nodes (its constraint
modes), so a static compliance test passes whatever the mode count. What the cut loses is the
interior's inertia: when the retained patch moves by its static shape x_s (the constraint
modes of a unit normal translation of the patch, the body on its reference condition), the
interior carries the inertia load r = (M x_s)_i. At frequency w the patch's dynamic
stiffness is k_s - w^2 m_s - w^4 sum_j (phi_j^T r)^2 / (lambda_j - w^2) (m_s = x_s^T M x_s,
phi_j the M-normalised fixed-interface modes); the cut modes' part is, below the cut,
w^4 R with the static residual R = r^T K_ii^-1 r - sum_{kept} (phi_j^T r)^2 / lambda_j. Against
the inertia term w^2 m_s it is (w T_r)^2 with the residual time T_r = sqrt(R / m_s): the
reduced body's apparent mass at the patch is right to (2 pi T_r / T_c)^2 for a contact of
duration T_c. The guard is T_r / T_c (T_c: the run's first contact, the summary's).

Why not the share 1 - kept / total of the static flexibility (modal_residual, kept as
information): the seed rod's 1-3 + 37 modes (force NCC 0.9999 against full FE) leave 0.988
of it cut, since its patch's static shape is a local dent whose inertia only modes far above
the contact's frequencies carry; its T_r is 5 ns against the arm's and beam's 0.1-12 us.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from flexmvm.fe.assembly import FEModel
from flexmvm.fe.solvers.spd import solver_pool, spd_solver
from flexmvm.reduction.kinds.mvm import node_dofs
from flexmvm.reduction.kinds.spec import Basis

#: A reduced body whose residual time exceeds this share of the first contact's duration
#: gets a ReducedBasisWarning. Measured against full FE (docs/concepts.md, "Too few modes"):
#: the worst good model, the arm's 30 modes (force NCC 0.9997), 0.0098; the best bad one, the
#: beam's 15 modes (NCC 0.985, peak -3.9 %), 0.020; 0.015 lies between.
RATIO_WARN = 0.015


def patch_normal(X: np.ndarray) -> np.ndarray:
    """The unit axis of least spread of the points X (n, 3) about their centroid (the normal of
    a surface patch); +z for fewer than three points (no plane to fit)."""
    if len(X) < 3:
        return np.array([0.0, 0.0, 1.0])
    d = X - X.mean(axis=0)
    return np.linalg.eigh(d.T @ d)[1][:, 0]


def modal_residual(fe: FEModel, basis: Basis) -> dict:
    """{residual_time_s, modal_residual, n_modes, highest_mode_hz} of a Craig-Bampton basis
    (module doc): the time scale T_r of the inertia its cut modes miss at the retained patch
    and the share of the patch's static inertia flexibility they carry."""
    nodes = basis.retained_nodes
    n = patch_normal(fe.mesh.nodes[nodes])
    b = node_dofs(nodes)
    free = basis.reference.free_dofs(fe.n_dof)
    interior = np.setdiff1d(free, b)
    psi = basis.psi
    cols = basis.retained_columns()  # (nb, 3)
    if sp.issparse(psi):  # psi times the patch's unit loads spread over its columns: a column
        # slice of a sparse basis copies the ring's columns, dense over the body (8 GB on a
        # 3,000-node region of a 274k-DOF plate); the zero columns add exact zeros
        z = np.zeros(psi.shape[1])
        z[cols.ravel()] = np.tile(n, len(nodes))
        x_s = np.asarray(psi @ z).ravel()
    else:
        x_s = np.asarray(psi[:, cols.ravel()] @ np.tile(n, len(nodes))).ravel()
    m_x = np.asarray(fe.M @ x_s).ravel()
    r = m_x[interior]
    k_ii = sp.csc_matrix(fe.K[interior][:, interior])
    with solver_pool() as pool:
        total = float(r @ np.asarray(spd_solver(k_ii, pool)(r[:, None])).ravel())
    kept = 0.0
    if basis.n_modes:
        phi = psi[:, basis.nq - basis.n_modes :]
        phi = np.asarray(phi[interior].toarray() if sp.issparse(phi) else phi[interior])
        lam = (2.0 * np.pi * np.asarray(basis.mode_freqs_hz)) ** 2
        kept = float((((phi.T @ r) ** 2) / lam).sum())
    m_s = float(x_s @ m_x)
    cut = max(total - kept, 0.0)
    return {
        "residual_time_s": float(np.sqrt(cut / m_s)) if m_s > 0 else 0.0,
        "modal_residual": cut / total if total > 0 else 0.0,
        "n_modes": int(basis.n_modes),
        "highest_mode_hz": float(basis.mode_freqs_hz[-1]) if basis.n_modes else None,
    }


def first_contact_duration(t_s: np.ndarray, impulse_ns: np.ndarray, h_s: np.ndarray):
    """The duration [s] of a run's first contact: its steps' force (impulse / step) above 1 %
    of the largest, from the first such step to the last of its unbroken run; None without
    contact or when it lasts to the run's end (a lower bound only)."""
    force = np.asarray(impulse_ns) / np.asarray(h_s)
    if not force.size or not force.max() > 0:
        return None
    on = force > 0.01 * force.max()
    first = int(np.argmax(on))
    off = np.flatnonzero(~on[first:])
    if not off.size:
        return None
    last = first + int(off[0]) - 1
    return float(t_s[last] - t_s[first] + h_s[first])


def truncation_report(built, steps) -> dict:
    """{body: its modal_residual entries + contact_duration_s, residual_to_contact} for the
    guarded bodies of a built scenario, with the run's StepHistory ``steps`` (None: no ratio)."""
    t_c = None
    if steps is not None:
        t_c = first_contact_duration(steps.t_s, steps.contact_impulse_Ns, steps.h_s)
    out = {}
    for info in built.info:
        if info.truncation:
            ratio = info.truncation["residual_time_s"] / t_c if t_c else None
            out[info.name] = {
                **info.truncation,
                "contact_duration_s": t_c,
                "residual_to_contact": ratio,
            }
    return out


def truncation_warnings(report: dict, threshold: float = RATIO_WARN) -> list[str]:
    """One line per reduced body of summary ``modal_truncation_guard`` whose residual time
    exceeds ``threshold`` of the first contact's duration."""
    lines = []
    for name, g in report.items():
        ratio = g.get("residual_to_contact")
        if ratio is not None and ratio > threshold:
            lines.append(
                f"body {name}: the inertia its {g['n_modes']} modes cut has a time scale of "
                f"{1e6 * g['residual_time_s']:.3g} us, {100 * ratio:.1f} % of the first "
                f"contact's {1e6 * g['contact_duration_s']:.3g} us (above "
                f"{100 * threshold:.2g} % the contact force drifts from full FE); raise "
                "model.modes (summary.json modal_truncation_guard)"
            )
    return lines
