"""Build a FlexibleBody from an FE model and a basis (seed eq. 5: m = psi^T M psi, k = psi^T K psi)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody


def body_from_fe(name: str, fe, basis, *, rayleigh: tuple[float, float] | None = None) -> FlexibleBody:
    """The floating-frame body of FE model `fe` (M_scalar, K) with basis psi.

    rayleigh = (alpha [1/s], beta [s]) gives damping C = alpha M_qq + beta k_hat (off by default).
    A basis with no columns gives a rigid body with the FE model's mass distribution.
    """
    psi = basis.psi
    if sp.issparse(psi):
        psi = sp.csr_matrix(psi)
        k_hat = sp.csr_matrix(psi.T @ fe.K @ psi)
        k_hat = 0.5 * (k_hat + k_hat.T)
    else:
        k_hat = psi.T @ (fe.K @ psi)
        k_hat = 0.5 * (k_hat + k_hat.T)
    body = FlexibleBody.build(name, fe.mesh.nodes, fe.M_scalar, psi, k_hat, mesh=fe.mesh,
                              label=getattr(basis.kind, "value", ""))
    if rayleigh is not None:
        alpha, beta = rayleigh
        c = alpha * body.inv.M_qq + beta * k_hat
        body = FlexibleBody(body.name, body.X, body.psi, body.inv, body.k_hat, body.mesh, c, body.label)
    return body


def rigid_body_from_fe(name: str, fe) -> FlexibleBody:
    """A rigid body (nq = 0) with the mass distribution of fe."""
    n = fe.mesh.n_nodes
    return FlexibleBody.build(name, fe.mesh.nodes, fe.M_scalar, np.zeros((3 * n, 0)),
                              np.zeros((0, 0)), mesh=fe.mesh, label="rigid")
