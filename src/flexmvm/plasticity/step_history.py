"""The plastic history of an FE body through a time-stepping run: the plastic cell set, the
return at a step's midpoint, the force correction it gives, and what an accepted step commits.

The step (integrate/plastic_bodies.py) keeps the elastic force K u of the body and adds the
correction of the plastic points (docs/plasticity.md, "The dynamic step"):

    f_int(u) = K u + c(u),    c(u) = sum_q B_q^T (sigma_q - D_el eps_q) dx_q
                                   = -sum_q B_q^T D_el eps_p,q dx_q             [N]

since the radial return gives sigma = D_el (eps - eps_p) with the updated plastic strain
eps_p (return_mapping.py; plastic strain is deviatoric). c is exactly zero where no point has
plastic strain, so an elastic step is the elastic scheme's step.

Only the cells of the plastic set are returned (PlasticBody.returns on a body made of those
cells: the same integration points, a thin wrapper). The set starts empty and only grows: after
every accepted step the cells whose elastic von Mises stress sqrt(3/2) |dev D_el B u| at the
step's midpoint exceeds SCREEN_FRACTION Y at any point join it. For a cell outside the set the
history is virgin, so its elastic stress is its stress: a joining cell above Y had yielded
without being returned, and the step is refused (``check`` returns False: the step is taken
again, the set already enlarged).
"""

from __future__ import annotations

import math

import numpy as np

from flexmvm.plasticity.body import PlasticBody, PointReturns, strain_matrices
from flexmvm.plasticity.return_mapping import (
    PointState,
    deviator,
    elastic_tangent,
    tensor_norm,
)

#: A cell joins the plastic set when its elastic von Mises stress reaches this fraction of Y:
#: a cell that can yield within the next steps is returned before it does (the stress of a
#: contact rises by a few per cent per step at the contact step; 0.5 leaves a wide margin).
SCREEN_FRACTION = 0.5
_WEIGHT = np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])  # tensor-component inner product


class StepHistory:
    """History of one PlasticBody through a run (module doc). ``state``: the committed
    PointState of every point of the body (state order of PlasticBody); ``plastic_work``: the
    sum over the accepted steps of sigma : d eps_p dx [J] (sigma of the step's return);
    ``n_refused``: steps refused because a cell outside the set reached Y."""

    def __init__(self, body: PlasticBody, fraction: float = SCREEN_FRACTION, allowed=None) -> None:
        """allowed: per cell block a bool mask (n_cells,) of the cells that may be returned
        (a reduced body: the cells whose nodes are all retained); None: every cell."""
        self.body = body
        self.fraction = fraction
        self.d_el = elastic_tangent(body.material)
        self._b = [strain_matrices(bl.grad) for bl in body.blocks]
        self._ids = [
            (3 * bl.nodes[:, :, None] + np.arange(3)).reshape(len(bl.nodes), -1)
            for bl in body.blocks
        ]
        starts = np.cumsum([0] + [bl.n_points for bl in body.blocks])
        self._first = starts[:-1]
        self.in_set = [np.zeros(len(bl.nodes), bool) for bl in body.blocks]
        self.allowed = (
            [np.ones(len(bl.nodes), bool) for bl in body.blocks]
            if allowed is None
            else [np.asarray(a, bool) for a in allowed]
        )
        # cells outside ``allowed`` whose elastic stress reached Y: in how many screens (one
        # or two per step), and the most at once
        self.n_outside_steps, self.outside_cells = 0, 0
        self.state = body.virgin_state()
        self.plastic_work = 0.0
        self.n_refused = 0
        self._sub: PlasticBody | None = None
        self._sub_points = np.zeros(0, np.int64)
        # (returns, their point ids, their dx, the u and committed state they were made
        # from) of the last return
        self._trial: tuple[PointReturns, np.ndarray, np.ndarray, np.ndarray, PointState] | None
        self._trial = None
        self._k_el = None  # (the set's body, its elastic tangent): tangent_difference

    # ------------------------------------------------------------------ the plastic set
    @property
    def n_set_cells(self) -> int:
        return int(sum(s.sum() for s in self.in_set))

    def _points_of(self, k: int, cells: np.ndarray) -> np.ndarray:
        nqp = self.body.blocks[k].dx.shape[1]
        return (self._first[k] + cells[:, None] * nqp + np.arange(nqp)).ravel()

    def _rebuild(self) -> None:
        """The body of the set's cells (same integration points) and their point ids."""
        blocks, points = [], []
        for k, bl in enumerate(self.body.blocks):
            cells = np.flatnonzero(self.in_set[k])
            if cells.size:
                blocks.append(
                    type(bl)(
                        bl.cell_type,
                        bl.nodes[cells],
                        bl.values[cells],
                        bl.grad[cells],
                        bl.dx[cells],
                    )
                )
                points.append(self._points_of(k, cells))
        body = self.body
        self._sub = PlasticBody(body.mesh, body.material, body.plastic, tuple(blocks))
        self._sub_points = np.concatenate(points)

    def _von_mises(self, k: int, u: np.ndarray, cells) -> np.ndarray:
        """Elastic von Mises stress (ne, nqp) [Pa] of cells ``cells`` of block k at u."""
        # over the whole block, then the cells: no copy of the block's strain matrices
        strain = np.einsum("eqIk,ek->eqI", self._b[k], u[self._ids[k]])[cells]
        s = deviator(strain @ self.d_el.T)
        return math.sqrt(1.5) * tensor_norm(s)

    def check(self, u: np.ndarray) -> bool:
        """Screen the cells outside the set at the accepted midpoint displacement u (3n,) [m]:
        the allowed ones above fraction Y join the set; the others above Y are counted
        (n_outside_steps, outside_cells: a reduced body's guard). False (the step must be
        taken again) if a joining cell is above Y."""
        y = self.body.plastic.yield_pa
        grew, missed, outside = False, False, 0
        for k in range(len(self.body.blocks)):
            out = np.flatnonzero(~self.in_set[k])
            if not out.size:
                continue
            vm = self._von_mises(k, u, out).max(axis=1)
            beyond = ~self.allowed[k][out]
            outside += int(np.count_nonzero(beyond & (vm > y)))
            vm, out = vm[~beyond], out[~beyond]
            join = vm >= self.fraction * y
            if join.any():
                self.in_set[k][out[join]] = True
                grew = True
                missed |= bool((vm[join] > y).any())
        if outside:  # the guard of a reduced body: its elastic rest would yield there
            self.n_outside_steps += 1
            self.outside_cells = max(self.outside_cells, outside)
        if grew:  # the trial keeps its own points: commit() takes it as returned
            self._rebuild()
        if missed:
            self.n_refused += 1
        return not missed

    # ------------------------------------------------------------------ the step
    def correction(self, u: np.ndarray) -> np.ndarray | None:
        """c(u) (3n,) [N] of the return at u (3n,) [m] from the committed history (module
        doc), None where no point of the set has plastic strain (c = 0 exactly). The return
        is kept as the step's trial (commit)."""
        self._trial = None
        if self._sub is None:
            return None
        pts = self._sub_points
        sub_state = PointState(
            self.state.plastic_strain[pts],
            self.state.equivalent_plastic_strain[pts],
            self.state.back_stress[pts],
        )
        resp = self._sub.returns(u, sub_state)  # no force, no tangent: c is eps_p's (_force)
        self._trial = (resp, pts, self._sub.point_volumes(), u, sub_state)
        eps_p = resp.state.plastic_strain
        return self._force(eps_p) if eps_p.any() else None

    def yielding_points(self) -> np.ndarray:
        """Ids (body state order) of the points that yield in the last return."""
        if self._trial is None:
            return np.zeros(0, np.int64)
        resp, pts = self._trial[:2]
        return pts[resp.yielding]

    def tangent_difference(self):
        """K_t - K_el (3n, 3n) csr [N/m] of the last return (Simo and Taylor 1985's consistent
        tangent, PlasticBody.respond) over the set's cells, None when no point of it yields:
        nonzero on the DOFs of the yielding cells only (the elastic points' element tangents
        are D_el's, added in the same order as K_el's, so they cancel exactly)."""
        if self._trial is None or not self._trial[0].yielding.any():
            return None
        if self._k_el is None or self._k_el[0] is not self._sub:
            virgin = self._sub.virgin_state()
            self._k_el = (self._sub, self._sub.respond(np.zeros(self.body.n_dof), virgin).tangent)
        _, _, _, u, sub_state = self._trial  # the return's own tangent, made again here
        diff = self._sub.respond(u, sub_state).tangent - self._k_el[1]
        diff.eliminate_zeros()
        return diff

    def committed_correction(self) -> np.ndarray:
        """c (3n,) [N] of the committed plastic strain (independent of u: module doc)."""
        if self._sub is None:
            return np.zeros(self.body.n_dof)
        return self._force(self.state.plastic_strain[self._sub_points])

    def _force(self, eps_p: np.ndarray) -> np.ndarray:
        """-sum B^T D_el eps_p dx (3n,) [N] over the set's points with plastic strain eps_p
        (n_set_points, 6)."""
        assert self._sub is not None  # called with a plastic set only
        force, start = np.zeros(self.body.n_dof), 0
        for bl in self._sub.blocks:
            ne, nqp = bl.dx.shape
            plastic = eps_p[start : start + ne * nqp].reshape(ne, nqp, 6)
            start += ne * nqp
            cells = np.flatnonzero(plastic.any(axis=(1, 2)))
            if not cells.size:
                continue
            b = strain_matrices(bl.grad[cells])
            sig = -(plastic[cells] @ self.d_el.T) * bl.dx[cells][:, :, None]
            f_e = np.einsum("eqIk,eqI->ek", b, sig)
            ids = (3 * bl.nodes[cells][:, :, None] + np.arange(3)).reshape(len(cells), -1)
            np.add.at(force, ids, f_e)
        return force

    def commit(self) -> None:
        """The last return's state becomes the committed history; its plastic work
        sigma : (eps_p - eps_p,n) dx is added to plastic_work."""
        trial, self._trial = self._trial, None
        if trial is None:
            return
        resp, pts, dx = trial[:3]
        d_eps_p = resp.state.plastic_strain - self.state.plastic_strain[pts]
        # sigma (tensor components) . d eps_p (engineering shears) = sigma : d eps_p
        self.plastic_work += float(np.sum(np.sum(resp.stress * d_eps_p, axis=1) * dx))
        self.state.plastic_strain[pts] = resp.state.plastic_strain
        self.state.equivalent_plastic_strain[pts] = resp.state.equivalent_plastic_strain
        self.state.back_stress[pts] = resp.state.back_stress

    # ------------------------------------------------------------------ energies, outputs
    def strain_energy_correction(self, u: np.ndarray) -> float:
        """1/2 (eps - eps_p) : C (eps - eps_p) - 1/2 eps : C eps summed over the points [J]
        (committed history, displacement u (3n,) [m]): the elastic energy is 1/2 u^T K u
        plus this."""
        if self._sub is None or not self.state.plastic_strain[self._sub_points].any():
            return 0.0
        total, start = 0.0, 0
        eps_p = self.state.plastic_strain[self._sub_points]
        for bl in self._sub.blocks:
            ne, nqp = bl.dx.shape
            ep = eps_p[start : start + ne * nqp].reshape(ne, nqp, 6)
            start += ne * nqp
            b = strain_matrices(bl.grad)
            ids = (3 * bl.nodes[:, :, None] + np.arange(3)).reshape(ne, -1)
            eps = np.einsum("eqIk,ek->eqI", b, u[ids])
            c_ep = ep @ self.d_el.T
            total += float(
                np.sum((0.5 * np.sum(ep * c_ep, axis=2) - np.sum(eps * c_ep, axis=2)) * bl.dx)
            )
        return total

    def hardening_energy(self) -> float:
        """Stored energy of the hardening [J]: sum of (1/2 H_iso alpha^2 + 3 / (4 H_kin)
        beta : beta) dx over the points (Simo and Hughes 1998, sect. 2.3)."""
        p, dx = self.body.plastic, self.body.point_volumes()
        e = 0.5 * p.hardening_pa * self.state.equivalent_plastic_strain**2
        if p.kinematic_hardening_pa > 0:
            beta = self.state.back_stress
            e = e + 0.75 / p.kinematic_hardening_pa * np.sum(_WEIGHT * beta * beta, axis=1)
        return float(np.sum(e * dx))

    def cell_equivalent_plastic_strain(self) -> np.ndarray:
        """Volume average of alpha over each cell's points (n_cells,) [-], cells in the
        mesh's block order."""
        out, start = [], 0
        for bl in self.body.blocks:
            ne, nqp = bl.dx.shape
            a = self.state.equivalent_plastic_strain[start : start + ne * nqp].reshape(ne, nqp)
            start += ne * nqp
            out.append(np.sum(a * bl.dx, axis=1) / np.sum(bl.dx, axis=1))
        return np.concatenate(out) if out else np.zeros(0)
