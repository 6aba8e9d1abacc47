"""Elastic-plastic bodies in the Moreau-Jean step: full FE, and MVM bodies in the cells whose
nodes are all retained (docs/plasticity.md, "The dynamic step").

The internal force of a plastic body at the step's midpoint q_m is the return mapping at
eps(u_m), u_m = psi q_m, from the last accepted history (the flow rule integrated by backward
Euler on the grid of midpoints: plan item 1, docs/notes/2026-11-27-plastic-region-plan.md):

    F_q = -(k_hat q_m + psi^T c(psi q_m))        c: plasticity/step_history.py

so the carried k_hat q of the elastic step stays as it is and the correction is one return
over the plastic cell set per iterate. The iteration matrix stays the elastic W (factored once
per h): modified Newton, the residual exact. The accepted iterate's return becomes the next
step's history; a refused or cut step never commits its return. Energy: the work of the
correction, sum over the steps of psi^T c(q_m) . (q(t + h) - q(t)), less the difference between
the elastic energy and 1/2 q^T k_hat q at the output (StepHistory.strain_energy_correction), is
the plastic work (dissipation and stored hardening, to the scheme's order): the ledger's
``plastic`` term, which closes the balance to the Newton tolerance (integrate.energy_ledger).

A reduced body (the MVM kinds, psi dense or csr as kind mvm-sparse's) returns only the cells
whose nodes are all retained, where psi is the identity (RetainedRows, checked at the start):
its u there is a gather of q and psi^T c a scatter into q, with no product with psi's other
rows (mvm-sparse: dense in its corner columns); the screen of the cells outside the set, whose
guard covers every cell, takes the whole u = psi q_m once per accepted step. Full FE and the
dense kind get the products' values exactly (a unit row times q is the entry).

The history lives here, beside the BodyState: a run without plastic bodies makes none of it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from flexmvm.errors import InputError, SolverError
from flexmvm.plasticity.body import PlasticBody
from flexmvm.plasticity.step_history import StepHistory

if TYPE_CHECKING:
    from flexmvm.integrate.system import System

#: The modified Newton iteration on the elastic W contracts by 0.3 to 0.6 per iterate while
#: points yield (the elastic tangent is stiffer than the plastic one; measured on the sphere
#: impacts of tests/test_plastic_dynamics.py and sphere_block.toml): within 0.9 it is still
#: converging, not on the round-off floor where moreau_jean accepts a residual that no longer
#: halves. A step whose returns yield is on its floor only when an iterate gains less than
#: this factor.
STALL_RATIO = 0.9


@dataclass(frozen=True)
class PlasticPart:
    """A plastic body of a System: its index in System.bodies and its PlasticBody (mesh,
    elastic material and J2Plasticity; the mesh the body's psi maps to); allowed: per cell
    block a bool mask of the cells that may yield (a reduced body: those whose nodes are all
    retained, where psi is the identity), None: all (full FE); tangent: its Newton iteration
    matrix while it yields is the consistent tangent W_t (integrate.moreau_jean.plastic_tangent),
    else the elastic W; stop_outside: a reduced body whose cells outside the allowed ones reach
    yield stops the run (PlasticBodies.outside_stop), else the run counts them and goes on."""

    body: int
    model: PlasticBody
    allowed: tuple | None = None
    tangent: bool = False
    stop_outside: bool = False


@dataclass(frozen=True)
class PlasticReport:
    """What a run leaves in a plastic body: cell_equivalent_plastic_strain (n_cells,) [-]
    (volume average per cell, mesh block order) at the end and cell_history (n_out, n_cells)
    [-] at the outputs, point_equivalent_plastic_strain (n_points,)
    [-], plastic_work_j (sum of sigma : d eps_p dx over the steps) [J], hardening_energy_j
    (stored, at the end) [J], residual_displacement (3n,) [m] (the body's static field of its
    final plastic strain: unloaded and at rest, in its frame, relative to its reference
    condition), n_set_cells (cells returned) and n_refused (steps taken again because a cell
    outside the set reached yield); a reduced body's guard: n_outside_steps (steps at whose
    midpoint a cell it may not return reached Y) and outside_cells (the most such cells)."""

    cell_equivalent_plastic_strain: np.ndarray
    cell_history: np.ndarray
    point_equivalent_plastic_strain: np.ndarray
    plastic_work_j: float
    hardening_energy_j: float
    residual_displacement: np.ndarray
    n_set_cells: int
    n_refused: int
    n_outside_steps: int = 0
    outside_cells: int = 0

    @property
    def peak_equivalent_plastic_strain(self) -> float:
        return float(self.point_equivalent_plastic_strain.max(initial=0.0))


class PlasticBodies:
    """The plastic bodies of a system through a run (module doc)."""

    def __init__(self, system: System):
        self.bodies = system.bodies
        self.history: dict[int, StepHistory] = {}
        # a reduced body: its allowed cells' DOFs and the coordinates psi maps them to
        self.gather: dict[int, RetainedRows] = {}
        for part in system.plastic:
            body = self.bodies[part.body]
            if body.psi.shape[0] != part.model.n_dof:
                raise InputError(
                    f"body {body.name!r}: plasticity needs psi of {part.model.n_dof} rows "
                    f"(the plastic mesh's DOFs), got a psi of shape {body.psi.shape}"
                )
            if part.allowed is not None or not body.is_sparse:
                self.gather[part.body] = retained_rows(body, part)
            self.history[part.body] = StepHistory(part.model, allowed=part.allowed)
        self.parts = {part.body: part for part in system.plastic}
        # per body, the last midpoint: (q_m, u_m on the rows the returns read, psi^T c)
        self._mid: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray | None]] = {}

    def __bool__(self) -> bool:
        return bool(self.history)

    def __contains__(self, b: int) -> bool:
        return b in self.history

    @property
    def yielding(self) -> bool:
        """True if the last midpoint force of a body was not zero (its returns yield)."""
        return any(mid[2] is not None for mid in self._mid.values())

    def stall_ratio(self, elastic: float) -> float:
        """The factor of the round-off floor test: STALL_RATIO while the returns yield, else
        ``elastic`` (the scheme's own)."""
        return STALL_RATIO if self.yielding else elastic

    def displacement(self, b: int, q: np.ndarray) -> np.ndarray:
        """u = psi q (3n,) [m] of body b where its returns read it: full FE the whole field; a
        reduced body its allowed cells' DOFs (q's entries there: psi is the identity on them,
        no product with the other rows), zero elsewhere."""
        rows = self.gather.get(b)
        if rows is None:
            return self.bodies[b].psi @ q
        u = np.zeros(self.history[b].body.n_dof)
        u[rows.dofs] = q[rows.coordinates]
        return u

    def project(self, b: int, c: np.ndarray) -> np.ndarray:
        """psi^T c (nq,) [N] of body b for a nodal force c (3n,) of its returned cells: a
        reduced body's a scatter of c's allowed DOFs into their coordinates (c is zero on
        the other rows: the returned cells are allowed ones)."""
        rows = self.gather.get(b)
        if rows is None:
            return _project(self.bodies[b].psi, c)
        c_q = np.zeros(self.bodies[b].nq)
        c_q[rows.coordinates] = c[rows.dofs]
        return c_q

    def midpoint_force(self, b: int, q_m: np.ndarray) -> np.ndarray | None:
        """psi^T c(psi q_m) (nq,) [N] of body b at the midpoint q_m, None where it is zero;
        the return is the step's trial."""
        u = self.displacement(b, q_m)
        c = self.history[b].correction(u)
        c_q = None if c is None else self.project(b, c)
        self._mid[b] = (np.array(q_m, dtype=float), u, c_q)
        return c_q

    def elastic_step(self, states, new_states, theta: float) -> bool:
        """True if the step states -> new_states (the linear non-rotating step) leaves every
        plastic body elastic at its midpoint q + theta (q+ - q): then it is the step of the
        plastic scheme as well; False: the step must be taken by Newton."""
        for b, hist in self.history.items():
            q_m = states[b].q + theta * (new_states[b].q - states[b].q)
            if not hist.check(self.bodies[b].psi @ q_m):
                return False
            if self.midpoint_force(b, q_m) is not None:
                return False
        return True

    def _screened_field(self, b: int) -> np.ndarray:
        """The whole u = psi q_m (3n,) [m] of body b's last midpoint, which the screen of its
        cells outside the set reads (a reduced body's guard: every cell): full FE the
        midpoint's own field, a reduced body one product with psi per accepted step."""
        q_m, u, _ = self._mid[b]
        return u if b not in self.gather else self.bodies[b].psi @ q_m

    def check(self) -> None:
        """Screen the accepted iterate's midpoints (StepHistory.check); SolverError (the
        driver takes the step again in halves, the set enlarged) if a cell outside the set
        had reached yield."""
        for b, hist in self.history.items():
            if not hist.check(self._screened_field(b)):
                raise SolverError(
                    f"body {self.bodies[b].name!r}: a cell outside the plastic set reached "
                    "yield; the set grew and the step is taken again"
                )

    def outside_stop(self) -> str | None:
        """The reason to stop the run (one line) if a body whose part has stop_outside had
        cells outside its allowed ones at yield in an accepted step, else None."""
        for b, hist in self.history.items():
            if self.parts[b].stop_outside and hist.n_outside_steps:
                return (
                    f"body {self.bodies[b].name!r}: {hist.outside_cells} cells outside the "
                    "retained region reached the yield stress (model.plastic_outside = "
                    '"stop"): retain a larger region'
                )
        return None

    def commit(self, states, new_states) -> float:
        """Commit the accepted returns; the work [J] of the correction over the step,
        sum of psi^T c(q_m) . (q+ - q)."""
        work = 0.0
        for b, hist in self.history.items():
            c_q = self._mid[b][2]
            if c_q is not None:
                work += float(c_q @ (new_states[b].q - states[b].q))
            hist.commit()
        self._mid.clear()
        return work

    def strain_energy_correction(self, states) -> float:
        """Elastic energy minus 1/2 q^T k_hat q of the plastic bodies at states [J]."""
        return sum(
            hist.strain_energy_correction(self.displacement(b, states[b].q))
            for b, hist in self.history.items()
        )

    def cell_fields(self) -> dict[int, np.ndarray]:
        """Per plastic body: its cells' equivalent plastic strain (n_cells,) [-] now."""
        return {b: hist.cell_equivalent_plastic_strain() for b, hist in self.history.items()}

    def reports(self, outputs=()) -> dict[str, PlasticReport]:
        """PlasticReport per plastic body name (one sparse factorization of k_hat each);
        outputs: cell_fields() of every output, in order."""
        out = {}
        for b, hist in self.history.items():
            cells = hist.cell_equivalent_plastic_strain()
            history = np.array([row[b] for row in outputs]).reshape(len(outputs), len(cells))
            body = self.bodies[b]
            c_q = self.project(b, hist.committed_correction())
            q_res = np.zeros(body.nq)
            if np.any(c_q) and sp.issparse(body.k_hat):
                q_res = spla.spsolve(sp.csc_matrix(body.k_hat), -c_q)
            elif np.any(c_q):
                q_res = np.linalg.solve(np.asarray(body.k_hat), -c_q)
            out[body.name] = PlasticReport(
                cells,
                history,
                hist.state.equivalent_plastic_strain.copy(),
                hist.plastic_work,
                hist.hardening_energy(),
                body.psi @ q_res,
                hist.n_set_cells,
                hist.n_refused,
                hist.n_outside_steps,
                hist.outside_cells,
            )
        return out


def _project(psi, c: np.ndarray) -> np.ndarray:
    """psi^T c (nq,) for a nodal force c (3n,): sparse psi as is; a dense (reduced) psi on the
    rows where c is nonzero only (the returned cells' nodes)."""
    if sp.issparse(psi):
        return psi.T @ c
    rows = np.flatnonzero(c)
    return psi[rows].T @ c[rows]


@dataclass(frozen=True)
class RetainedRows:
    """A reduced plastic body's gather: dofs (m,) the DOFs of the nodes of the cells it may
    return, coordinates (m,) the q entry psi maps each to (psi[dofs[i]] is the unit row of
    coordinates[i]), so that u[dofs] = q[coordinates] and psi^T c = scatter of c[dofs]."""

    dofs: np.ndarray
    coordinates: np.ndarray


def retained_rows(body, part: PlasticPart) -> RetainedRows:
    """The RetainedRows of a reduced body (dense or csr psi), read from psi's rows at the
    DOFs of the allowed cells' nodes; InputError unless psi is the identity there, each row
    one entry 1.0 in a column of its own (their strain is then that of their coordinates,
    exactly: the plan's MVM form)."""
    if part.allowed is None:
        raise InputError(f"body {body.name!r}: a reduced plastic body needs its allowed cells")
    nodes = np.unique(
        np.concatenate(
            [
                bl.nodes[np.asarray(a, bool)].ravel()
                for bl, a in zip(part.model.blocks, part.allowed)
            ]
        )
    )
    dofs = (3 * nodes[:, None] + np.arange(3)).ravel()
    if sp.issparse(body.psi):
        rows = sp.csr_matrix(body.psi[dofs])
        rows.eliminate_zeros()
        ones = np.diff(rows.indptr) == 1
        unit = bool(np.all(ones)) and bool(np.all(rows.data == 1.0))
        coordinates = rows.indices.astype(np.int64) if unit else None
    else:
        rows = np.asarray(body.psi)[dofs]
        ones = np.count_nonzero(rows, axis=1) == 1
        unit = bool(np.all(ones)) and bool(np.all(rows.max(axis=1) == 1.0))
        coordinates = np.argmax(rows, axis=1) if unit else None
    if coordinates is None or np.unique(coordinates).size != dofs.size:
        raise InputError(
            f"body {body.name!r}: its basis is not the identity on the nodes of the cells "
            "allowed to yield (retained nodes)"
        )
    return RetainedRows(dofs, coordinates)
