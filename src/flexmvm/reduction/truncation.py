"""The truncation guard of a Craig-Bampton body (issue 51): the share of its contact patch's
dynamic flexibility carried by the fixed-interface modes it cuts (the modal residual).

A Craig-Bampton basis is statically exact for loads on its retained nodes (its constraint
modes), so a static compliance test passes whatever the mode count. What the cut loses is the
interior's inertia: when the retained patch moves by its static shape x_s (the constraint
modes of a unit normal translation of the patch, the body on its reference condition), the
interior carries the inertia load r = (M x_s)_i, and the interior's response to it is
K_ii^-1 r, with the flexibility F = r^T K_ii^-1 r = sum_j (phi_j^T r)^2 / lambda_j over all
the fixed-interface modes phi_j (M-normalised). The kept modes carry the first n_modes terms;

    residual = 1 - sum_{j <= n_modes} (phi_j^T r)^2 / lambda_j / F

is the share the reduced body lacks: the part of the patch's apparent mass the cut holds
stiff (0: nothing cut that the patch's motion excites; 1: no mode kept). It is computed once
from the body's K, M and basis (one factorisation of K_ii, as the basis's own).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from flexmvm.fe.assembly import FEModel
from flexmvm.fe.solvers.spd import solver_pool, spd_solver
from flexmvm.reduction.kinds.mvm import node_dofs
from flexmvm.reduction.kinds.spec import Basis

#: A reduced body whose modal residual exceeds this gets a ReducedBasisWarning. Measured on
#: the sphere on beam against full FE (docs/concepts.md, "Too few modes"): residual 1.9e-3
#: (15 modes) gave force NCC 0.985, peak -3.9 %; 2.6e-4 (20 modes) NCC 0.9994, peak +1.0 %;
#: 1e-3 lies between.
RESIDUAL_WARN = 1e-3


def patch_normal(X: np.ndarray) -> np.ndarray:
    """The unit axis of least spread of the points X (n, 3) about their centroid (the normal of
    a surface patch); +z for fewer than three points (no plane to fit)."""
    if len(X) < 3:
        return np.array([0.0, 0.0, 1.0])
    d = X - X.mean(axis=0)
    return np.linalg.eigh(d.T @ d)[1][:, 0]


def modal_residual(fe: FEModel, basis: Basis) -> dict:
    """{modal_residual, n_modes, highest_mode_hz, patch_normal} of a Craig-Bampton basis
    (module doc): the share of the retained patch's inertia flexibility its cut modes carry."""
    nodes = basis.retained_nodes
    n = patch_normal(fe.mesh.nodes[nodes])
    b = node_dofs(nodes)
    free = basis.reference.free_dofs(fe.n_dof)
    interior = np.setdiff1d(free, b)
    psi = basis.psi
    cols = basis.retained_columns()  # (nb, 3)
    x_s = np.asarray(psi[:, cols.ravel()] @ np.tile(n, len(nodes))).ravel()
    r = np.asarray(fe.M @ x_s).ravel()[interior]
    k_ii = sp.csc_matrix(fe.K[interior][:, interior])
    with solver_pool() as pool:
        total = float(r @ np.asarray(spd_solver(k_ii, pool)(r[:, None])).ravel())
    kept = 0.0
    if basis.n_modes:
        phi = psi[:, basis.nq - basis.n_modes :]
        phi = np.asarray(phi[interior].toarray() if sp.issparse(phi) else phi[interior])
        lam = (2.0 * np.pi * np.asarray(basis.mode_freqs_hz)) ** 2
        kept = float((((phi.T @ r) ** 2) / lam).sum())
    residual = 1.0 - kept / total if total > 0 else 0.0
    top = float(basis.mode_freqs_hz[-1]) if basis.n_modes else None
    return {
        "modal_residual": max(residual, 0.0),
        "n_modes": int(basis.n_modes),
        "highest_mode_hz": top,
        "patch_normal": [float(v) for v in n],
    }


def truncation_warnings(report: dict, threshold: float = RESIDUAL_WARN) -> list[str]:
    """One line per reduced body of summary ``modal_truncation_guard`` whose modal residual
    exceeds ``threshold``."""
    lines = []
    for name, g in report.items():
        if g["modal_residual"] > threshold:
            lines.append(
                f"body {name}: its {g['n_modes']} modes leave {100 * g['modal_residual']:.1f} % "
                f"of the contact patch's inertia flexibility to the modes cut (above "
                f"{100 * threshold:.2g} % the contact force drifts from full FE); raise "
                "model.modes (summary.json modal_truncation_guard)"
            )
    return lines
