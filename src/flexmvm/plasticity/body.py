"""Internal force and consistent tangent stiffness of an elastic-plastic FE body.

With the strain at integration point q of cell e, e_q = B_q u_e (engineering shears), the
stress sigma_q and tangent D_q of the radial return (return_mapping.py) give

    f_int = sum_e sum_q B_q^T sigma_q dx_q            [N]
    K_t   = sum_e sum_q B_q^T D_q B_q dx_q            [N/m]

(Simo and Hughes 1998, sect. 3.3; de Souza Neto et al. 2008, sect. 4.3), on the elements and
Gauss rules of fe/assembly.py (fe/points.py): in the elastic range K_t is assembly's K and
f_int = K u. History (plastic strain, equivalent plastic strain, back stress) lives per
integration point in one PointState, points numbered block by block, cell-major.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from flexmvm.errors import InputError
from flexmvm.fe.points import BlockPoints, integration_points
from flexmvm.materials import Material
from flexmvm.mesh.mesh import Mesh
from flexmvm.plasticity.material import J2Plasticity
from flexmvm.plasticity.return_mapping import PointState, radial_return

#: Cells per chunk of element tangents (a HEX27 tangent is 81 x 81 doubles = 52 kB).
_CHUNK = 512

#: Strain row I (Voigt xx, yy, zz, xy, yz, zx) = sum over (component i, gradient j) pairs.
_B_PAIRS = ((0, 0, 0), (1, 1, 1), (2, 2, 2), (3, 0, 1), (3, 1, 0), (4, 1, 2), (4, 2, 1))
_B_PAIRS += ((5, 2, 0), (5, 0, 2))


@dataclass(frozen=True)
class BodyResponse:
    """f_int (3n,) [N], tangent (3n, 3n) csr [N/m], stress (n_points, 6) [Pa], the trial
    state (n_points) and yielding (n_points,) bool, for one displacement u."""

    force: np.ndarray
    tangent: sp.csr_matrix
    stress: np.ndarray
    state: PointState
    yielding: np.ndarray


def strain_matrices(grad: np.ndarray) -> np.ndarray:
    """B (ne, nqp, 6, 3 nloc) from grad N (ne, nloc, 3, nqp): e = B u_e, local DOF 3a + i."""
    ne, nloc, _, nqp = grad.shape
    g = np.moveaxis(grad, 3, 1)  # (ne, nqp, nloc, 3)
    b = np.zeros((ne, nqp, 6, nloc, 3))
    for row, comp, deriv in _B_PAIRS:
        b[:, :, row, :, comp] = g[:, :, :, deriv]
    return b.reshape(ne, nqp, 6, 3 * nloc)


@dataclass(frozen=True)
class PlasticBody:
    """An FE body of ``material`` with J2 plasticity ``plastic`` on ``mesh`` (module doc)."""

    mesh: Mesh
    material: Material
    plastic: J2Plasticity
    blocks: tuple[BlockPoints, ...]

    @classmethod
    def build(cls, mesh: Mesh, material: Material, plastic: J2Plasticity) -> PlasticBody:
        """The body with its integration points (fe/points.py); MeshError as fe.assemble."""
        return cls(mesh, material, plastic, integration_points(mesh))

    @property
    def n_dof(self) -> int:
        return self.mesh.n_dof

    @property
    def n_points(self) -> int:
        return sum(b.n_points for b in self.blocks)

    def virgin_state(self) -> PointState:
        """History of a body that has never yielded."""
        return PointState.virgin(self.n_points)

    def point_coordinates(self) -> np.ndarray:
        """Undeformed positions (n_points, 3) [m] of the integration points, state order."""
        return np.vstack([b.coordinates(self.mesh.nodes) for b in self.blocks])

    def point_volumes(self) -> np.ndarray:
        """Integration weights dx (n_points,) [m^3], state order."""
        return np.concatenate([b.dx.ravel() for b in self.blocks])

    def respond(self, u: np.ndarray, state: PointState) -> BodyResponse:
        """f_int, K_t, stress and trial state at displacement u (3n,) [m] from the converged
        ``state`` of the last step. Raises InputError if the shapes do not match the body."""
        u = np.asarray(u, dtype=float)
        if u.shape != (self.n_dof,) or state.n_points != self.n_points:
            raise InputError(
                f"plastic body: u must have shape ({self.n_dof},) and the state "
                f"{self.n_points} points, got {u.shape} and {state.n_points}"
            )
        parts, start = [], 0
        for block in self.blocks:
            for lo in range(0, len(block.nodes), _CHUNK):
                cells = slice(lo, lo + _CHUNK)
                n_pts = block.dx[cells].size
                pts = _slice(state, slice(start, start + n_pts))
                parts.append(self._chunk(block, cells, u, pts))
                start += n_pts
        force, rows, cols = np.zeros(self.n_dof), [], []
        for ids, f_e, _, _ in parts:  # cell blocks differ in nodes per cell: one by one
            np.add.at(force, ids, f_e)
            rows.append(np.repeat(ids, ids.shape[1], axis=1).ravel())
            cols.append(np.tile(ids, (1, ids.shape[1])).ravel())
        vals = np.concatenate([p[2].ravel() for p in parts])
        tangent = sp.csr_matrix(
            (vals, (np.concatenate(rows), np.concatenate(cols))), shape=(self.n_dof, self.n_dof)
        )
        resp = [p[3] for p in parts]
        return BodyResponse(
            force,
            tangent,
            np.vstack([r.stress for r in resp]),
            _concat([r.state for r in resp]),
            np.concatenate([r.yielding for r in resp]),
        )

    def _chunk(self, block: BlockPoints, cells: slice, u: np.ndarray, state: PointState):
        """Element DOF ids (ne, 3 nloc), element forces (ne, 3 nloc) [N], element tangents
        (ne, 3 nloc, 3 nloc) [N/m] and the PointResponse of the cells ``cells`` of a block."""
        ne, nqp = block.dx[cells].shape
        ids = (3 * block.nodes[cells][:, :, None] + np.arange(3)).reshape(ne, -1)
        b = strain_matrices(block.grad[cells])
        strain = np.einsum("eqIk,ek->eqI", b, u[ids]).reshape(-1, 6)
        resp = radial_return(self.material, self.plastic, strain, state)
        dx = block.dx[cells]
        f_e = np.einsum("eqIk,eqI,eq->ek", b, resp.stress.reshape(ne, nqp, 6), dx)
        d = resp.tangent.reshape(ne, nqp, 6, 6) * dx[:, :, None, None]
        k_e = np.zeros((ne, ids.shape[1], ids.shape[1]))
        for q in range(nqp):
            k_e += np.swapaxes(b[:, q], 1, 2) @ (d[:, q] @ b[:, q])
        return ids, f_e, k_e, resp


def _slice(state: PointState, pts: slice) -> PointState:
    return PointState(
        state.plastic_strain[pts], state.equivalent_plastic_strain[pts], state.back_stress[pts]
    )


def _concat(states: list[PointState]) -> PointState:
    return PointState(
        np.vstack([s.plastic_strain for s in states]),
        np.concatenate([s.equivalent_plastic_strain for s in states]),
        np.vstack([s.back_stress for s in states]),
    )
