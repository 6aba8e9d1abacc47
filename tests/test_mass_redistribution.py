"""Mass redistribution on the contact boundary (fe/mass_redistribution.py): the contact nodes
carry no mass, the body keeps its mass, centre of mass and inertia exactly."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as sla

import flexmvm as fm
from flexmvm.assembly.build import build_scenario
from flexmvm.errors import InputError
from flexmvm.fe.assembly import assemble
from flexmvm.fe.mass_redistribution import moments, redistribute_mass
from flexmvm.integrate.moreau_jean.massless import MasslessCoordinates
from flexmvm.materials import ALUMINIUM
from flexmvm.mesh.rod import EndShape, RodSpec, rod_mesh

SHORT = "scenarios/rod_impact_short.toml"


@pytest.mark.parametrize("end", [EndShape.FLAT, EndShape.HEMISPHERE])
def test_contact_nodes_massless_moments_kept(end):
    """Mass, first and second moments to 1e-14 of the largest (round-off of sums over 3,000
    nodes); the boundary rows exactly zero; the rest positive definite (its smallest
    eigenvalue is above the consistent matrix's own: mass moved onto the diagonal)."""
    rod = rod_mesh(RodSpec(length_m=0.1, radius_m=0.01, end_a=end))
    fe = assemble(rod.mesh, ALUMINIUM)
    B = rod.mesh.facet_set("end_a").nodes
    M = redistribute_mass(fe.M_scalar, rod.mesh.nodes, B)
    m0, m1 = moments(fe.M_scalar, rod.mesh.nodes), moments(M, rod.mesh.nodes)
    assert np.abs(m1 - m0).max() <= 1e-14 * np.abs(m0).max()
    assert abs(M[B]).sum() == 0.0 and abs(M[:, B]).sum() == 0.0
    free = np.setdiff1d(np.arange(rod.mesh.n_nodes), B)
    low = sla.eigsh(M[free][:, free], k=1, sigma=0, which="LM", return_eigenvectors=False)[0]
    low0 = sla.eigsh(fe.M_scalar, k=1, sigma=0, which="LM", return_eigenvectors=False)[0]
    assert low >= low0 > 0


def test_bad_nodes_are_input_errors():
    rod = rod_mesh(RodSpec(length_m=0.1, radius_m=0.01))
    fe = assemble(rod.mesh, ALUMINIUM)
    with pytest.raises(InputError, match="outside the mesh"):
        redistribute_mass(fe.M_scalar, rod.mesh.nodes, [rod.mesh.n_nodes + 3])
    assert redistribute_mass(fe.M_scalar, rod.mesh.nodes, []).nnz == fe.M_scalar.nnz


def test_scenario_option_acts_on_the_retained_contact_nodes():
    """redistribute_mass = true: both bodies' rigid-body inertia is unchanged (mass to 1e-14,
    first moment and inertia to 1e-12 of their scale), and the MVM body's retained contact
    nodes become massless coordinates: their constraint modes are split (reduction/basis.py),
    so their rows of M_qq and of the frame couplings S1, G1 are exactly zero (the integrator's
    test for them is == 0.0), and the other coordinates keep their mass."""
    data = fm.load_scenario(SHORT).model_dump(mode="json")
    data["contacts"][0].update(redistribute_mass=True, law="position")
    redis = build_scenario(fm.scenario_from_dict(data))
    data["contacts"][0].update(redistribute_mass=False)
    plain = build_scenario(fm.scenario_from_dict(data))
    for b in range(2):
        i0, i1 = plain.system.bodies[b].inv, redis.system.bodies[b].inv
        assert i1.mass == pytest.approx(i0.mass, rel=1e-14)
        for name in ("S0", "G0"):
            a0, a1 = np.asarray(getattr(i0, name)), np.asarray(getattr(i1, name))
            assert np.abs(a1 - a0).max() <= 1e-12 * np.abs(a0).max()
    # b2 is MVM 1-3 + 37: its first 75 coordinates are the 25 retained face nodes, all on
    # the contact face; their interior static fields follow as columns of their own
    b2, b2_plain = redis.system.bodies[1], plain.system.bodies[1]
    assert b2_plain.nq == 112 and 112 < b2.nq <= 112 + 75
    d0, d1 = (np.diag(np.asarray(b.inv.M_qq)) for b in (b2_plain, b2))
    assert np.all(d0 > 0) and np.all(d1[:75] == 0.0) and np.all(d1[75:] > 0)
    assert np.all(np.asarray(b2.inv.M_qq)[:75] == 0.0)
    assert np.all(np.asarray(b2.inv.S1)[:, :75] == 0.0)
    assert all(np.all(np.asarray(g)[:75] == 0.0) for row in b2.inv.G1 for g in row)
    assert all(np.all(np.asarray(g)[:75] == 0.0) for row in b2.inv.G2 for g in row)
    assert MasslessCoordinates.of(b2).s.tolist() == list(range(75))


def test_a_contact_surface_too_large_says_what_to_change():
    """The whole side of the tiny rod as the contact surface (240 nodes, 38 % of its mass):
    refused in one line that says how much mass the surface carries and what to change."""
    from pathlib import Path

    import flexmvm as fm
    from flexmvm.assembly.build_cache import default_setup
    from flexmvm.assembly.cache_keys import mesh_key
    from flexmvm.errors import InputError
    from flexmvm.fe.mass_redistribution import redistribute_mass

    sc = fm.load_scenario(Path(__file__).parent / "data" / "tiny_impact.toml")
    cfg = sc.body("b2")
    fe = default_setup().fe_model(mesh_key(cfg), cfg.material_obj())
    with pytest.raises(InputError) as info:
        redistribute_mass(fe.M_scalar, fe.mesh.nodes, fe.mesh.node_set("side"))
    msg = str(info.value)
    assert "\n" not in msg and "carry 38 % of the body's mass" in msg
    assert "patch about the expected contact point" in msg and "redistribute_mass = false" in msg
