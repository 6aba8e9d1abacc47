"""The compiled plastic response (flexmvm.plasticity.kernels via PlasticBody.respond and
radial_return) against its numpy reference (flexmvm.plasticity.kernels_numpy), and the body on a
subset of its cells (PlasticBody.on_cells, point_ids).

Both paths evaluate the same equations (Simo and Hughes 1998, box 3.2; f_int = sum B^T
sigma dx, K_t = sum B^T D B dx) in another order of summation: the compiled one skips the
zeros of B and sums an element's points in another order, so they agree to round-off. The
largest sums are the tangent entries of a HEX27 node (27 points x 3 nonzeros of B x 6 terms
of D, of mixed sign where the plastic tangent cancels the elastic one): ~500 rounding errors
of 1.1e-16 each, at most ~6e-14 of the largest entry, so 1e-12 relative to the largest
entry of each array leaves a margin of 15 and still fails on any real difference (a wrong
sign or index changes entries by O(1) of the scale). The yield flags must be identical
(a random strain lands within 1e-12 of the yield surface with probability ~1e-12).

The displacements: a random nodal field scaled so that its first application (from the
virgin state) yields about half of the points, then a second random field of the same size
applied from that history, so that the second call holds points that never yielded (virgin,
elastic), points that yield again (plastic loading with history) and points that yielded
before and now unload elastically. Each case runs in well under a second after the kernels
are compiled (the first run in a checkout compiles them: about 20 s at load 7). About 4 s
in all (3-5 s measured at load 7).
"""

from __future__ import annotations

import numpy as np
import pytest
from test_fe import box_hex, box_tet10, hex_wedge_mesh

from flexmvm.errors import InputError
from flexmvm.materials import Material
from flexmvm.plasticity.body import PlasticBody
from flexmvm.plasticity.kernels_numpy import radial_return_numpy, respond_numpy
from flexmvm.plasticity.material import J2Plasticity
from flexmvm.plasticity.return_mapping import PointState, radial_return, von_mises

STEEL = Material(E=200e9, nu=0.3, rho=7800.0, name="steel")
Y = 250e6
HARDENING = {
    "isotropic": J2Plasticity(Y, hardening_pa=10e9),
    "kinematic": J2Plasticity(Y, kinematic_hardening_pa=10e9),
    "combined": J2Plasticity(Y, hardening_pa=4e9, kinematic_hardening_pa=6e9),
}
MESHES = {
    "tet10": box_tet10,
    "hex8": lambda: box_hex(order=1),
    "hex27": lambda: box_hex(order=2),
    "hex8+wedge6": hex_wedge_mesh,
}
RTOL = 1e-12


def _close(got, want, what):
    scale = np.max(np.abs(want))
    err = np.max(np.abs(got - want)) / scale
    assert err < RTOL, f"{what}: relative error {err:.3g}"


def _same_response(got, want):
    _close(got.force, want.force, "f_int")
    _close(got.tangent.toarray(), want.tangent.toarray(), "tangent")
    _close(got.stress, want.stress, "stress")
    _close(got.state.plastic_strain, want.state.plastic_strain, "plastic strain")
    _close(got.state.equivalent_plastic_strain, want.state.equivalent_plastic_strain, "alpha")
    if np.any(want.state.back_stress):
        _close(got.state.back_stress, want.state.back_stress, "back stress")
    else:
        assert not np.any(got.state.back_stress)
    np.testing.assert_array_equal(got.yielding, want.yielding)


def _two_steps(body, seed=0):
    """u1 (about half the points yield from virgin) and u2 = u1 + a field of the same size."""
    rng = np.random.default_rng(seed)
    u = rng.normal(0.0, 1.0, body.n_dof)
    elastic = PlasticBody(body.mesh, body.material, J2Plasticity(1e30), body.blocks)
    trial = elastic.respond(u, elastic.virgin_state()).stress
    scale = Y / np.median(von_mises(trial))
    u1 = scale * u
    u2 = u1 + scale * rng.normal(0.0, 1.0, body.n_dof)
    return u1, u2


@pytest.mark.parametrize("mesh_name", sorted(MESHES))
@pytest.mark.parametrize("name", sorted(HARDENING))
def test_body_response_equals_numpy_reference(mesh_name, name):
    body = PlasticBody.build(MESHES[mesh_name](), STEEL, HARDENING[name])
    u1, u2 = _two_steps(body)
    first = body.respond(u1, body.virgin_state())
    _same_response(first, respond_numpy(body, u1, body.virgin_state()))
    second = body.respond(u2, first.state)
    _same_response(second, respond_numpy(body, u2, first.state))
    history = first.state.equivalent_plastic_strain > 0
    kinds = {
        "virgin elastic": ~history & ~second.yielding,
        "plastic loading": history & second.yielding,
        "unloading": history & ~second.yielding,
    }
    for kind, mask in kinds.items():
        assert mask.sum() >= 0.05 * body.n_points, f"too few {kind} points: {mask.sum()}"


def test_point_return_equals_numpy_reference():
    """radial_return (compiled) against the numpy form on 400 points, two steps."""
    rng = np.random.default_rng(5)
    eps_y = Y / STEEL.E
    for plastic in HARDENING.values():
        state = PointState.virgin(400)
        for _ in range(2):
            strain = rng.normal(0.0, 2 * eps_y, (400, 6))
            got = radial_return(STEEL, plastic, strain, state)
            want = radial_return_numpy(STEEL, plastic, strain, state)
            _close(got.stress, want.stress, "stress")
            _close(got.tangent, want.tangent, "tangent")
            _close(got.state.plastic_strain, want.state.plastic_strain, "plastic strain")
            np.testing.assert_array_equal(got.yielding, want.yielding)
            state = got.state


def test_cell_subsets_add_up_to_the_body():
    """Two sub-bodies over a partition of the cells: their forces and tangents add up to the
    whole body's (same sums, split: 1e-12 relative), their states put back give the whole
    body's state exactly (each point is computed alone), and a sub-body equals the numpy
    reference of itself."""
    body = PlasticBody.build(hex_wedge_mesh(), STEEL, HARDENING["combined"])
    u1, u2 = _two_steps(body, seed=3)
    state = body.respond(u1, body.virgin_state()).state
    whole = body.respond(u2, state)
    cells = np.random.default_rng(1).permutation(body.mesh.n_cells)
    parts = (cells[:5], cells[5:])
    force, tangent, merged = 0.0, 0.0, state
    for part in parts:
        sub, ids = body.on_cells(part), body.point_ids(part)
        assert sub.n_points == len(ids) and np.array_equal(sub.cells, np.sort(part))
        resp = sub.respond(u2, state.take(ids))
        _same_response(resp, respond_numpy(sub, u2, state.take(ids)))
        force, tangent = force + resp.force, tangent + resp.tangent
        merged = merged.put(ids, resp.state)
        np.testing.assert_array_equal(resp.stress, whole.stress[ids])
    _close(force, whole.force, "f_int")
    _close(tangent.toarray(), whole.tangent.toarray(), "tangent")
    for a, b in zip(
        (merged.plastic_strain, merged.equivalent_plastic_strain, merged.back_stress),
        (
            whole.state.plastic_strain,
            whole.state.equivalent_plastic_strain,
            whole.state.back_stress,
        ),
        strict=True,
    ):
        np.testing.assert_array_equal(a, b)
    # a sub-body of a sub-body: ids stay the mesh's, points map through both levels
    sub = body.on_cells(parts[1])
    inner = parts[1][:3]
    np.testing.assert_array_equal(
        body.point_ids(parts[1])[sub.point_ids(inner)], body.point_ids(inner)
    )


def test_bad_cell_sets_are_one_line_errors():
    body = PlasticBody.build(box_hex(order=1), STEEL, HARDENING["isotropic"])
    with pytest.raises(InputError, match="non-empty set of cell ids"):
        body.on_cells([])
    with pytest.raises(InputError, match="cell 12 is not a cell of this body"):
        body.on_cells([0, 12])
    with pytest.raises(InputError, match="must not repeat"):
        body.point_ids([1, 1])
    with pytest.raises(InputError, match="cell 0 is not a cell of this body"):
        body.on_cells([1, 2]).on_cells([0])
    with pytest.raises(InputError, match="state 8 points"):
        body.on_cells([1]).respond(np.zeros(body.n_dof), body.virgin_state())
