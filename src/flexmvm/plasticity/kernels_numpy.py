"""The numpy reference of the compiled plasticity kernels (kernels.py): the radial return
vectorized over points and the body's internal force and tangent assembled with einsum and a
COO matrix. Same equations, other code: tests/test_plastic_kernels.py checks the compiled
path against it to round-off and benchmarks/bench_plasticity.py times the two side by side.
Not used by any run.

Radial return (Simo and Hughes 1998, box 3.2; return_mapping's module doc):

    s_tr  = 2 mu dev(eps - eps_p_n),   xi_tr = s_tr - beta_n
    f_tr  = ||xi_tr|| - sqrt(2/3) (Y + H_iso alpha_n),   dgam = f_tr / (2 mu + 2/3 H)
    C     = kappa 1 (x) 1 + 2 mu theta I_dev - 2 mu theta_bar n (x) n

Body (body.py's module doc): f_int = sum B^T sigma dx, K_t = sum B^T D B dx.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from flexmvm.materials import Material
from flexmvm.plasticity.body import BodyResponse, PlasticBody, strain_matrices
from flexmvm.plasticity.material import J2Plasticity
from flexmvm.plasticity.return_mapping import PointResponse, PointState, deviator, tensor_norm

_WEIGHT = np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])
_ONE = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])
_I_SYM = np.diag([1.0, 1.0, 1.0, 0.5, 0.5, 0.5])
_I_DEV = _I_SYM - np.outer(_ONE, _ONE) / 3.0

#: Cells per chunk of element tangents (a HEX27 tangent is 81 x 81 doubles = 52 kB).
_CHUNK = 512


def radial_return_numpy(
    material: Material, plastic: J2Plasticity, strain: np.ndarray, state: PointState
) -> PointResponse:
    """return_mapping.radial_return in numpy (module doc); strain (n, 6), no shape checks."""
    lam, mu = material.lame
    kappa = lam + 2.0 * mu / 3.0
    h_iso, h_kin = plastic.hardening_pa, plastic.kinematic_hardening_pa
    elastic_strain = (strain - state.plastic_strain) @ _I_SYM  # tensor components
    s_trial = 2.0 * mu * deviator(elastic_strain)
    xi = s_trial - state.back_stress
    xi_norm = tensor_norm(xi)
    radius = math.sqrt(2.0 / 3.0) * (plastic.yield_pa + h_iso * state.equivalent_plastic_strain)
    f_trial = xi_norm - radius
    yielding = f_trial > 0.0
    dgam = np.where(yielding, f_trial / (2.0 * mu + (2.0 / 3.0) * (h_iso + h_kin)), 0.0)
    n = xi / np.where(yielding, xi_norm, 1.0)[:, None]
    step = dgam[:, None] * n
    volumetric = kappa * elastic_strain[:, :3].sum(axis=1)
    stress = s_trial - 2.0 * mu * step + volumetric[:, None] * _ONE
    new_state = PointState(
        plastic_strain=state.plastic_strain + step * _WEIGHT,
        equivalent_plastic_strain=state.equivalent_plastic_strain + math.sqrt(2.0 / 3.0) * dgam,
        back_stress=state.back_stress + (2.0 / 3.0) * h_kin * step,
    )
    theta = 1.0 - 2.0 * mu * dgam / np.where(yielding, xi_norm, 1.0)
    theta_bar = np.where(yielding, 1.0 / (1.0 + (h_iso + h_kin) / (3.0 * mu)) - (1.0 - theta), 0.0)
    tangent = kappa * np.outer(_ONE, _ONE) + 2.0 * mu * theta[:, None, None] * _I_DEV
    tangent -= (2.0 * mu * theta_bar)[:, None, None] * (n[:, :, None] * n[:, None, :])
    return PointResponse(stress, tangent, new_state, yielding)


def respond_numpy(body: PlasticBody, u: np.ndarray, state: PointState) -> BodyResponse:
    """PlasticBody.respond in numpy (module doc), chunks of _CHUNK cells, no shape checks."""
    parts, start = [], 0
    for block in body.blocks:
        for lo in range(0, len(block.nodes), _CHUNK):
            cells = slice(lo, lo + _CHUNK)
            n_pts = block.dx[cells].size
            pts = state.take(np.arange(start, start + n_pts))
            parts.append(_chunk(body, block, cells, u, pts))
            start += n_pts
    force, rows, cols = np.zeros(body.n_dof), [], []
    for ids, f_e, _, _ in parts:  # cell blocks differ in nodes per cell: one by one
        np.add.at(force, ids, f_e)
        rows.append(np.repeat(ids, ids.shape[1], axis=1).ravel())
        cols.append(np.tile(ids, (1, ids.shape[1])).ravel())
    vals = np.concatenate([p[2].ravel() for p in parts])
    tangent = sp.csr_matrix(
        (vals, (np.concatenate(rows), np.concatenate(cols))), shape=(body.n_dof, body.n_dof)
    )
    resp = [p[3] for p in parts]
    return BodyResponse(
        force,
        tangent,
        np.vstack([r.stress for r in resp]),
        PointState(
            np.vstack([r.state.plastic_strain for r in resp]),
            np.concatenate([r.state.equivalent_plastic_strain for r in resp]),
            np.vstack([r.state.back_stress for r in resp]),
        ),
        np.concatenate([r.yielding for r in resp]),
    )


def _chunk(body: PlasticBody, block, cells: slice, u: np.ndarray, state: PointState):
    """Element DOF ids (ne, 3 nloc), element forces (ne, 3 nloc) [N], element tangents
    (ne, 3 nloc, 3 nloc) [N/m] and the PointResponse of the cells ``cells`` of a block."""
    ne, nqp = block.dx[cells].shape
    ids = (3 * block.nodes[cells][:, :, None] + np.arange(3)).reshape(ne, -1)
    b = strain_matrices(block.grad[cells])
    strain = np.einsum("eqIk,ek->eqI", b, u[ids]).reshape(-1, 6)
    resp = radial_return_numpy(body.material, body.plastic, strain, state)
    dx = block.dx[cells]
    f_e = np.einsum("eqIk,eqI,eq->ek", b, resp.stress.reshape(ne, nqp, 6), dx)
    d = resp.tangent.reshape(ne, nqp, 6, 6) * dx[:, :, None, None]
    k_e = np.zeros((ne, ids.shape[1], ids.shape[1]))
    for q in range(nqp):
        k_e += np.swapaxes(b[:, q], 1, 2) @ (d[:, q] @ b[:, q])
    return ids, f_e, k_e, resp
