"""A rigid sphere pressed statically into a block (flexmvm.plasticity.indentation): the
machinery of the active set and the plastic body.

Default run (about 5 s): a quarter of a block (HEX27, 4 x 4 x 2 cells, symmetry planes
x = 0 and y = 0 through the sphere's axis), pressed and released. Checked: no face node
above the sphere (to 1e-9 of the depth, the active set's tolerance), no contact force
pulling (every active node's force >= 0), the force growing with the depth; an elastic
block springs back to zero displacement (to 1e-9 of the depth: round-off of the solves),
a plastic one keeps a dent with no force on it.

Validation run only (``pytest -m validation``; about 2 min of CPU, 12 min wall at load 15-20
on the shared two cores): the shipped
gmsh block (scenarios/meshes/block_60x60x30.msh, tet10, 0.3 mm at the contact) of
aluminium 6061-T6 (Y = 276 MPa, ASM Handbook vol. 2) under a sphere R = 60 mm, so that
Hertz's contact radius at first yield (0.53 mm) spans about two elements. Yield starts
where the elastic FE peak von Mises stress reaches Y: the Hertz peak pressure there is
compared with Hertz's p0 = 1.65 Y (nu = 0.33; theory.hertz_yield) within 15 %, the mesh's
accuracy measured in the same run (the FE peak von Mises stress of the elastic step at half
the onset approach is 13.9 % above Hertz's, bound 20 %: two elements across the contact
radius; so the onset comes at p0 = 1.45 Y, -12.2 %); the most strained point lies below the
surface near the axis (measured 0.53 a deep, 0.25 a off the axis; Hertz: 0.49 a on it); the
unloaded block keeps a dent (measured 0.74 um after 9.2 um).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from test_fe import box_hex

from flexmvm.materials import ALUMINIUM, Material
from flexmvm.plasticity import J2Plasticity, PlasticBody
from flexmvm.plasticity.indentation import indent_with_sphere, sphere_surface
from flexmvm.plasticity.return_mapping import von_mises
from flexmvm.theory.hertz_yield import axis_von_mises, yield_onset

STEEL = Material(E=200e9, nu=0.3, rho=7800.0, name="steel")


def _quarter(plastic: J2Plasticity):
    size = (0.01, 0.01, 0.005)
    mesh = box_hex((4, 4, 2), size, order=2)
    x = mesh.nodes
    face = np.flatnonzero(np.isclose(x[:, 2], size[2]))
    support = np.concatenate(
        [
            3 * np.flatnonzero(x[:, 0] == 0),
            3 * np.flatnonzero(x[:, 1] == 0) + 1,
            3 * np.flatnonzero(x[:, 2] == 0) + 2,
        ]
    )
    return PlasticBody.build(mesh, STEEL, plastic), face, support, size[2]


@pytest.mark.parametrize("yield_pa", [1e30, 250e6], ids=["elastic", "plastic"])
def test_quarter_block_press_and_release(yield_pa):
    body, face, support, top = _quarter(J2Plasticity(yield_pa, hardening_pa=1e9))
    radius = 0.02
    depths = np.array([2e-6, 4e-6, 8e-6, 0.0])
    res = indent_with_sphere(body, face, support, radius, depths, z_top_m=top)
    xy = body.mesh.nodes[face, :2]
    for k, d in enumerate(depths):
        target = sphere_surface(xy, d, radius, (0.0, 0.0), top) - top
        uz = res.displacement[k, 3 * face + 2]
        assert np.all(uz <= target + 1e-9 * depths.max())
        assert np.all(res.contact_forces[k] >= 0.0)
    assert 0 < res.force[0] < res.force[1] < res.force[2]
    assert res.force[3] == 0.0 and len(res.contact_nodes[3]) == 0
    dent = -res.displacement[3, 3 * face + 2].min()
    if yield_pa > 1e20:
        assert np.max(np.abs(res.displacement[3])) < 1e-9 * depths.max()
    else:
        assert res.equivalent_plastic_strain[2].max() > 0
        assert 1e-3 * depths.max() < dent < depths.max()


@pytest.mark.validation
def test_gmsh_block_yield_onset_against_hertz():
    from flexmvm.mesh.io import read_mesh

    mesh = read_mesh(Path(__file__).resolve().parents[1] / "scenarios/meshes/block_60x60x30.msh")
    y, radius, nu = 276e6, 0.06, ALUMINIUM.nu
    e_star = ALUMINIUM.E / (1 - nu**2)
    onset = yield_onset(y, e_star, radius, nu)
    body = PlasticBody.build(mesh, ALUMINIUM, J2Plasticity(y))
    bottom = mesh.node_set("bottom")
    support = (3 * bottom[:, None] + np.arange(3)).ravel()
    depths = onset.delta_m * np.array([0.5, 1.25, 2.0, 0.0])
    res = indent_with_sphere(body, mesh.node_set("top"), support, radius, depths)
    plastic = res.equivalent_plastic_strain.max(axis=1) > 0
    assert not plastic[0] and plastic[1:3].all()
    # the elastic step: FE force and peak von Mises stress against Hertz at the FE force
    f = res.force[0]
    p0 = (6 * f * e_star**2 / (math.pi**3 * radius**2)) ** (1 / 3)
    peak_hertz = p0 * float(axis_von_mises(onset.depth_over_a, nu))
    peak_fe = von_mises(res.stress[0]).max()
    f_hertz = 4 / 3 * e_star * math.sqrt(radius) * depths[0] ** 1.5
    assert f == pytest.approx(f_hertz, rel=0.06)
    assert 0.0 < peak_fe / peak_hertz - 1 < 0.2
    # onset: the elastic FE peak stress scales as F^(1/3) (Hertz) and reaches Y at p0_on
    p0_on = p0 * y / peak_fe
    assert p0_on / y == pytest.approx(onset.p0_over_y, rel=0.15)
    # the most strained point of the first plastic step: below the surface, near the axis
    a = math.sqrt(radius * depths[1])
    xp = body.point_coordinates()[np.argmax(res.equivalent_plastic_strain[1])]
    assert xp[2] < -0.1 * a and math.hypot(xp[0], xp[1]) < 1.5 * a
    # unloaded: no force, a dent
    assert res.force[3] == 0.0
    assert -res.displacement[3, 3 * mesh.node_set("top") + 2].min() > 0.01 * depths[2]


def test_hertz_yield_onset_is_johnsons():
    """Johnson (1985, sect. 6.2): von Mises yield first at p0 = 1.60 Y, 0.48 a below the
    centre, for nu = 0.3 (his figures are given to two digits: tolerance 0.01)."""
    onset = yield_onset(250e6, 100e9, 0.01, 0.3)
    assert onset.p0_over_y == pytest.approx(1.60, abs=0.015)
    assert onset.depth_over_a == pytest.approx(0.48, abs=0.01)
    # the force and approach at onset satisfy Hertz: p0 = 3 F / (2 pi a^2), a^2 = R delta
    assert 3 * onset.force_n / (2 * math.pi * onset.radius_m**2) == pytest.approx(
        onset.p0_over_y * 250e6, rel=1e-12
    )
    assert onset.radius_m**2 == pytest.approx(0.01 * onset.delta_m, rel=1e-12)
