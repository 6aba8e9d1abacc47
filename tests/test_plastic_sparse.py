"""Plasticity on a kind mvm-sparse body (the ring basis, psi csr: reduction/kinds/mvm_sparse.py)
against the dense kind mvm body of the same region and modes (integrate/plastic_bodies.py;
docs/plasticity.md, "The dynamic step").

The two bases are the same columns (tests/test_ring_body.py: equal to 7e-14), so a plastic run
of one is the other's to round-off. The returns read only the allowed cells' DOFs, where psi is
the identity: u there is a gather of q and psi^T c a scatter into q, with no product with the
exterior rows of the csr basis (dense in the corner columns), which only the guard of the cells
outside the region reads, once per accepted step.

The case: tests/test_plastic_dynamics.py's rigid sphere on its coarse 10 x 10 x 5 mm tet10 block
(0.5 mm within 1 mm of the contact, 3,867 DOF), Y 2.35 GPa, struck at 1.5 v_y; the block reduced
to the nodes within 1.0 mm of the contact (357 coordinates) + 4 modes, 0.5 us steps over the
contact (22 steps, ~0.6 s of CPU a run). Measured: 19 cells yield in both, 7 steps in which 46
cells outside the region reach Y (the guard fires: this region is small for 1.5 v_y), force
histories equal to 2.5e-13 of the peak, plastic work to 2.5e-13, residual displacement to
4.1e-13 of its largest entry.
"""

from __future__ import annotations

import dataclasses
import types

import numpy as np
import pytest
import scipy.sparse as sp
from test_plastic_dynamics import E, Y, _block, _hertz, _impact, _yield_speed

from flexmvm.errors import InputError, SolverError
from flexmvm.integrate.plastic_bodies import PlasticBodies

REGION = {"ball": {"centre_m": [0, 0, 0], "radius_m": 1.0e-3}}

#: The two bases agree to ~1e-13 (test_ring_body.py); over the run's 22 Newton steps the
#: histories measured agree to 2.5e-13 (force, plastic work) - 4.1e-13 (residual field): 1e-10
#: is round-off with a margin, far below any modelling difference (a mode more moves them 1e-3).
ROUND_OFF = 1e-10


@pytest.fixture(scope="module")
def mesh(tmp_path_factory):
    return _block(tmp_path_factory.mktemp("plastic_sparse"), 0.5e-3, 1.0e-3)


def _case(mesh, kind: str, run: bool = True, **model):
    v = 1.5 * _yield_speed(mesh)
    t_end = 1.25 * _hertz(mesh, v).duration_s
    model = {"kind": kind, "region": REGION, "modes": 4, **model}
    return _impact(mesh, v, {"yield_pa": Y}, t_end, 0.5e-6, model=model, run=run)


@pytest.fixture(scope="module")
def runs(mesh):
    """The dense and the sparse body's runs (~0.6 s of CPU each, and their builds)."""
    return {kind: _case(mesh, kind) for kind in ("mvm", "mvm-sparse")}


@pytest.mark.filterwarnings("ignore::flexmvm.assembly.cost.ReducedCostWarning")
def test_sparse_plastic_run_is_the_dense_one_to_round_off(runs):
    """Contact force history, plastic work, hardening energy, the yielded cells and their
    plastic strain, the residual displacement (the dent's field), the energy ledger's plastic
    term and the outside-cells guard of the mvm-sparse block equal the dense block's."""
    (built_d, dense), (built_s, sparse) = runs["mvm"], runs["mvm-sparse"]
    assert built_s.system.bodies[1].is_sparse and not built_d.system.bodies[1].is_sparse
    assert dense.steps_on_roundoff_floor == 0 and sparse.steps_on_roundoff_floor == 0
    f_d, f_s = np.asarray(dense.contact_force), np.asarray(sparse.contact_force)
    assert np.abs(f_s - f_d).max() < ROUND_OFF * np.abs(f_d).max()
    p_d, p_s = dense.plastic["block"], sparse.plastic["block"]
    assert p_d.plastic_work_j > 0
    assert abs(p_s.plastic_work_j - p_d.plastic_work_j) < ROUND_OFF * p_d.plastic_work_j
    assert abs(p_s.hardening_energy_j - p_d.hardening_energy_j) <= ROUND_OFF * max(
        p_d.hardening_energy_j, p_d.plastic_work_j
    )
    yielded = p_d.cell_equivalent_plastic_strain > 0
    assert yielded.sum() > 10
    assert np.array_equal(p_s.cell_equivalent_plastic_strain > 0, yielded)
    eps_d, eps_s = p_d.cell_equivalent_plastic_strain, p_s.cell_equivalent_plastic_strain
    assert np.abs(eps_s - eps_d).max() < ROUND_OFF * eps_d.max()
    r_d, r_s = p_d.residual_displacement, p_s.residual_displacement
    assert np.abs(r_s - r_d).max() < ROUND_OFF * np.abs(r_d).max()
    w_d, w_s = dense.energy_ledger.plastic, sparse.energy_ledger.plastic
    assert np.abs(w_s - w_d).max() < ROUND_OFF * np.abs(w_d).max()
    # the guard: the same steps and cells outside the region at yield (it fires here)
    assert p_d.n_outside_steps > 0 and p_d.outside_cells > 0
    assert (p_s.n_outside_steps, p_s.outside_cells) == (p_d.n_outside_steps, p_d.outside_cells)
    assert (p_s.n_set_cells, p_s.n_refused) == (p_d.n_set_cells, p_d.n_refused)


def _unit_rows(psi: sp.csr_matrix) -> np.ndarray:
    """Rows of psi with a single entry 1.0 (the retained DOFs)."""
    one = np.diff(psi.indptr) == 1
    return np.flatnonzero(one & (psi.data[np.minimum(psi.indptr[:-1], psi.nnz - 1)] == 1.0))


def _poisoned(body, rows: np.ndarray, value: float):
    """A copy of body whose csr psi has ``value`` in every entry of rows ``rows``."""
    psi = body.psi.copy()
    hit = np.zeros(psi.shape[0], bool)
    hit[rows] = True
    psi.data[np.repeat(hit, np.diff(psi.indptr))] = value
    return dataclasses.replace(body, psi=psi, _psi_rows={})


@pytest.mark.filterwarnings("ignore::flexmvm.assembly.cost.ReducedCostWarning")
def test_returns_read_no_exterior_row_of_the_sparse_basis(runs):
    """The midpoint force of the sparse block with its basis's exterior rows set to NaN is
    finite and equal to that of the clean basis: the returns gather q at the allowed DOFs and
    scatter psi^T c into q, with no product with those rows (before: u = psi q and psi^T c over
    the whole csr basis, NaN in every corner coordinate). A uniform strain of 3 Y / E on the
    retained nodes, after one screen has put the cells into the plastic set."""
    built, _ = runs["mvm-sparse"]
    system, b = built.system, 1
    body = system.bodies[b]
    unit = _unit_rows(body.psi)
    exterior = np.setdiff1d(np.arange(body.psi.shape[0]), unit)
    X = body.X
    strain = np.diag([3.0 * Y / E, 0.0, 0.0])
    u_target = (X @ strain.T).ravel()
    q = np.zeros(body.nq)
    q[body.psi.indices[body.psi.indptr[unit]]] = u_target[unit]
    forces = []
    for trial in (body, _poisoned(body, exterior, np.nan)):
        plastic = PlasticBodies(types.SimpleNamespace(bodies=[system.bodies[0], trial],
                                                      plastic=system.plastic))  # fmt: skip
        assert plastic.midpoint_force(b, q) is None  # no set yet
        with pytest.raises(SolverError):  # the screen: cells join above Y, the step refused
            plastic.check()
        forces.append(plastic.midpoint_force(b, q))
    clean, poisoned = forces
    assert clean is not None and np.abs(clean).max() > 0
    assert np.all(np.isfinite(poisoned))
    assert np.array_equal(poisoned, clean)


@pytest.mark.filterwarnings("ignore::flexmvm.assembly.cost.ReducedCostWarning")
def test_sparse_basis_not_the_identity_on_the_allowed_cells_is_refused(runs):
    """A csr basis whose row at an allowed cell's DOF is not a unit row is refused in one line
    when the run starts (before: checked for a dense basis only)."""
    built, _ = runs["mvm-sparse"]
    system = built.system
    (part,) = system.plastic
    node = part.model.blocks[0].nodes[np.flatnonzero(part.allowed[0])[0], 0]
    bad = _poisoned(system.bodies[1], np.array([3 * node]), 0.5)
    with pytest.raises(InputError, match="not the identity") as info:
        PlasticBodies(types.SimpleNamespace(bodies=[system.bodies[0], bad], plastic=(part,)))
    assert "\n" not in str(info.value)


@pytest.mark.filterwarnings("ignore::flexmvm.assembly.cost.ReducedCostWarning")
def test_consistent_tangent_on_the_sparse_block_gives_the_same_run(mesh, runs, monkeypatch):
    """``plastic_tangent = true`` on the mvm-sparse block works (W_t by the Woodbury identity on
    its sparse factor, integrate.moreau_jean.plastic_tangent, installed at least once): the run
    is the elastic-W run's to the Newton tolerance (force within 1e-6 of its peak, plastic work
    1e-6 relative; measured 2.3e-9 and 1.6e-7). About 2 s."""
    from flexmvm.integrate.moreau_jean import plastic_tangent

    installed = []
    update = plastic_tangent.PlasticTangent.update

    def counted(self, *args, **kwargs):
        changed = update(self, *args, **kwargs)
        installed.append(changed)
        return changed

    monkeypatch.setattr(plastic_tangent.PlasticTangent, "update", counted)
    _, res = _case(mesh, "mvm-sparse", plastic_tangent=True)
    _, ref = runs["mvm-sparse"]
    assert any(installed)
    assert res.steps_on_roundoff_floor == 0
    f, f_ref = np.asarray(res.contact_force), np.asarray(ref.contact_force)
    assert np.abs(f - f_ref).max() < 1e-6 * np.abs(f_ref).max()
    w, w_ref = res.plastic["block"].plastic_work_j, ref.plastic["block"].plastic_work_j
    assert abs(w - w_ref) < 1e-6 * w_ref, (w, w_ref)


@pytest.mark.filterwarnings("ignore::flexmvm.assembly.cost.ReducedCostWarning")
def test_returns_alone_are_respond_s_bit_for_bit(runs):
    """PlasticBody.returns (the step's returns without the element forces and tangents that
    the modified Newton does not use) gives respond's stress, trial state and yielding points
    exactly, from a history that has yielded (two displacements in turn)."""
    built, _ = runs["mvm-sparse"]
    (part,) = built.system.plastic
    body = part.model.on_cells(np.flatnonzero(np.concatenate(part.allowed)))
    rng = np.random.default_rng(1)
    state = body.virgin_state()
    for scale in (2e-6, 3e-6):
        u = scale * rng.standard_normal(body.n_dof)
        full, alone = body.respond(u, state), body.returns(u, state)
        assert full.yielding.any()
        assert np.array_equal(alone.stress, full.stress)
        assert np.array_equal(alone.yielding, full.yielding)
        for a, b in zip(
            (alone.state.plastic_strain, alone.state.equivalent_plastic_strain),
            (full.state.plastic_strain, full.state.equivalent_plastic_strain),
        ):
            assert np.array_equal(a, b)
        assert np.array_equal(alone.state.back_stress, full.state.back_stress)
        state = full.state
