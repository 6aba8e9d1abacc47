"""Internal force and consistent tangent stiffness of an elastic-plastic FE body.

With the strain at integration point q of cell e, e_q = B_q u_e (engineering shears), the
stress sigma_q and tangent D_q of the radial return (return_mapping.py) give

    f_int = sum_e sum_q B_q^T sigma_q dx_q            [N]
    K_t   = sum_e sum_q B_q^T D_q B_q dx_q            [N/m]

(Simo and Hughes 1998, sect. 3.3; de Souza Neto et al. 2008, sect. 4.3), on the elements and
Gauss rules of fe/assembly.py (fe/points.py): in the elastic range K_t is assembly's K and
f_int = K u. History (plastic strain, equivalent plastic strain, back stress) lives per
integration point in one PointState, points numbered block by block, cell-major.

respond runs the compiled kernels (kernels.block_response: return and element assembly per
cell, the element tangents added straight into the CSR data through a slot map found once
per body); kernels_numpy.py keeps the numpy form they are checked against. A body restricted to
some cells (on_cells) costs what those cells cost: the time step evaluates only the cells
that can yield.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from flexmvm.errors import InputError
from flexmvm.fe.points import BlockPoints, integration_points
from flexmvm.materials import Material
from flexmvm.mesh.mesh import Mesh
from flexmvm.plasticity.kernels import block_response, block_returns
from flexmvm.plasticity.material import J2Plasticity
from flexmvm.plasticity.return_mapping import PointState, material_constants

#: Strain row I (Voigt xx, yy, zz, xy, yz, zx) = sum over (component i, gradient j) pairs.
_B_PAIRS: tuple[tuple[int, int, int], ...] = (
    (0, 0, 0),
    (1, 1, 1),
    (2, 2, 2),
    (3, 0, 1),
    (3, 1, 0),
    (4, 1, 2),
    (4, 2, 1),
)
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


@dataclass(frozen=True)
class PointReturns:
    """The returns of one displacement u: stress (n_points, 6) [Pa], the trial state and
    yielding (n_points,) bool (BodyResponse's without its force and tangent)."""

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
    """An FE body of ``material`` with J2 plasticity ``plastic`` on ``mesh`` (module doc),
    on all its cells or on the cells ``cell_ids`` (ids in Mesh.cells order, block by block,
    ascending; None: all) of a body restricted by on_cells."""

    mesh: Mesh
    material: Material
    plastic: J2Plasticity
    blocks: tuple[BlockPoints, ...]
    cell_ids: np.ndarray | None = None

    @classmethod
    def build(cls, mesh: Mesh, material: Material, plastic: J2Plasticity) -> PlasticBody:
        """The body with its integration points (fe/points.py); MeshError as fe.assemble."""
        blocks = integration_points(mesh)
        return cls(mesh, material, plastic, tuple(_take_cells(b, slice(None)) for b in blocks))

    @property
    def cells(self) -> np.ndarray:
        """Ids (Mesh.cells order) of the body's cells, in state order (ascending)."""
        return np.arange(self.mesh.n_cells) if self.cell_ids is None else self.cell_ids

    def on_cells(self, cells) -> PlasticBody:
        """This body on the cells ``cells`` (ids as in ``cells``, any order, no repeats) only:
        the same mesh, DOFs and kernels, its state the points of those cells in this body's
        order (point_ids gives their positions in this body's state), its force and tangent
        the part of theirs (3n,), (3n, 3n). Slicing only; the tangent's structure is found on
        its first respond. Raises InputError for an empty set, repeats or foreign ids."""
        pos = self._positions(cells)
        blocks, start = [], 0
        for b in self.blocks:
            local = pos[(pos >= start) & (pos < start + len(b.nodes))] - start
            if len(local):
                blocks.append(_take_cells(b, local))
            start += len(b.nodes)
        return PlasticBody(self.mesh, self.material, self.plastic, tuple(blocks), self.cells[pos])

    def point_ids(self, cells) -> np.ndarray:
        """Positions in this body's state of the points of ``cells``, in the state order of
        ``on_cells(cells)``: ``state.take(body.point_ids(c))`` is the sub-body's state and
        ``state.put(ids, response.state)`` writes its new state back. InputError as on_cells."""
        pos = self._positions(cells)
        per_cell = np.concatenate([np.full(len(b.nodes), b.dx.shape[1]) for b in self.blocks])
        first = np.concatenate([[0], np.cumsum(per_cell)])[pos]
        count = per_cell[pos]
        ends = np.cumsum(count)
        return np.repeat(first - (ends - count), count) + np.arange(ends[-1])

    def _positions(self, cells) -> np.ndarray:
        """Sorted positions in self.cells of the ids ``cells``; InputError unless valid."""
        ids = np.asarray(cells).ravel()
        if ids.size == 0 or not np.issubdtype(ids.dtype, np.integer):
            raise InputError(
                f"plastic body: cells must be a non-empty set of cell ids, got {cells!r}"
            )
        own = self.cells
        pos = np.searchsorted(own, ids)
        bad = (pos >= len(own)) | (own[np.minimum(pos, len(own) - 1)] != ids)
        if bad.any():
            raise InputError(f"plastic body: cell {int(ids[bad][0])} is not a cell of this body")
        pos = np.sort(pos)
        if np.any(np.diff(pos) == 0):
            raise InputError("plastic body: cells must not repeat")
        return pos

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
        ``state`` of the last step, by the compiled kernels (kernels.block_response). Raises
        InputError if the shapes do not match the body."""
        u = np.ascontiguousarray(u, dtype=float)
        self._check_shapes(u, state)
        pattern = self._pattern
        n = self.n_points
        force, data = np.zeros(self.n_dof), np.zeros(len(pattern.indices))
        stress, yielding = np.empty((n, 6)), np.empty(n, dtype=np.bool_)
        new = PointState(np.empty((n, 6)), np.empty(n), np.empty((n, 6)))
        old = [np.ascontiguousarray(a, dtype=float) for a in _arrays(state)]
        mat = material_constants(self.material, self.plastic)
        start = 0
        for block, slots in zip(self.blocks, pattern.slots, strict=True):
            pts = slice(start, start + block.n_points)
            block_response(
                block.nodes, block.grad, block.dx, u, *(a[pts] for a in old), mat, slots,
                force, data, stress[pts], *(a[pts] for a in _arrays(new)), yielding[pts],
            )  # fmt: skip
            start += block.n_points
        tangent = sp.csr_matrix(
            (data, pattern.indices.copy(), pattern.indptr.copy()),
            shape=(self.n_dof, self.n_dof),
        )
        tangent.has_canonical_format = True  # sorted, no duplicates: np.unique made it
        return BodyResponse(force, tangent, stress, new, yielding)

    def _check_shapes(self, u: np.ndarray, state: PointState) -> None:
        if u.shape != (self.n_dof,) or state.n_points != self.n_points:
            raise InputError(
                f"plastic body: u must have shape ({self.n_dof},) and the state "
                f"{self.n_points} points, got {u.shape} and {state.n_points}"
            )

    def returns(self, u: np.ndarray, state: PointState) -> PointReturns:
        """respond's stress, trial state and yielding at u (3n,) [m] from ``state`` (the same
        values), without its force and tangent (kernels.block_returns): measured on 400 tet10
        cells of the aluminium block, 0.74 ms a call against 4.5-5.0 ms."""
        u = np.ascontiguousarray(u, dtype=float)
        self._check_shapes(u, state)
        n = self.n_points
        stress, yielding = np.empty((n, 6)), np.empty(n, dtype=np.bool_)
        new = PointState(np.empty((n, 6)), np.empty(n), np.empty((n, 6)))
        old = [np.ascontiguousarray(a, dtype=float) for a in _arrays(state)]
        mat = material_constants(self.material, self.plastic)
        start = 0
        for block in self.blocks:
            pts = slice(start, start + block.n_points)
            block_returns(
                block.nodes, block.grad, u, *(a[pts] for a in old), mat, stress[pts],
                *(a[pts] for a in _arrays(new)), yielding[pts],
            )  # fmt: skip
            start += block.n_points
        return PointReturns(stress, new, yielding)

    @cached_property
    def _pattern(self) -> _Pattern:
        """The tangent's CSR structure and each element entry's position in it, computed on
        the first respond (np.unique over the element entries) and kept with the body."""
        ids = [
            (3 * b.nodes[:, :, None] + np.arange(3)).reshape(len(b.nodes), -1) for b in self.blocks
        ]
        keys = np.concatenate([(i[:, :, None] * self.n_dof + i[:, None, :]).ravel() for i in ids])
        unique, inverse = np.unique(keys, return_inverse=True)
        dtype = np.int32 if len(unique) < 2**31 - 1 else np.int64
        indptr = np.zeros(self.n_dof + 1, dtype=dtype)
        np.cumsum(np.bincount(unique // self.n_dof, minlength=self.n_dof), out=indptr[1:])
        slots, start = [], 0
        for i in ids:
            count = i.shape[0] * i.shape[1] ** 2
            slots.append(
                inverse[start : start + count].astype(dtype).reshape(len(i), *[i.shape[1]] * 2)
            )
            start += count
        return _Pattern((unique % self.n_dof).astype(dtype), indptr, tuple(slots))


@dataclass(frozen=True)
class _Pattern:
    """CSR indices (nnz,) and indptr (3n + 1,) of a body's tangent and, per cell block, the
    position slots (ne, 3 nloc, 3 nloc) of each element entry in its data."""

    indices: np.ndarray
    indptr: np.ndarray
    slots: tuple[np.ndarray, ...]


def _take_cells(block: BlockPoints, cells) -> BlockPoints:
    """The cells ``cells`` of a block, as C-contiguous arrays (node ids int64) the kernels
    take without copying."""
    return BlockPoints(
        block.cell_type,
        np.ascontiguousarray(block.nodes[cells], dtype=np.int64),
        np.ascontiguousarray(block.values[cells]),
        np.ascontiguousarray(block.grad[cells]),
        np.ascontiguousarray(block.dx[cells]),
    )


def _arrays(state: PointState) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return state.plastic_strain, state.equivalent_plastic_strain, state.back_stress
