"""Onset of yield of a rigid sphere on a free block within 5 % of Hertz's yield speed (issue
37: "sphere onto a block: onset of yield at the Hertz speed where p0 = 1.6 Y, within 5 %").

The case of tests/test_plastic_dynamics.py (its module doc: sphere R 10 mm rigid, 1.03 g; E
70 GPa, nu 0.33, Y 2.35 GPa; Hertz's first yield, von Mises on the axis, at p0 = 1.649 Y,
theory.hertz_yield, with a = 0.77 mm) on a larger free block, 20 x 20 x 10 mm, tet10, 0.2 mm
within 1.2 mm of the contact (3.9 elements per a), 2 mm elsewhere: 27,684 DOF, Hertz's
v_y = 15.8 m/s (converged: at 0.14 mm, 5.5 per a, 34,989 DOF, the peak below moves by
0.14 %). At v_y Hertz's subsurface von Mises maximum is Y, so an elastic run at v_y
measures the FE field's peak as sigma_max / Y, and the mesh's own onset speed is
v_y (Y / sigma_max)^(5/2) (the stresses of a Hertz impact grow as v^(2/5)). sigma_max is
taken where a plastic run returns: at the step midpoints q + theta (q+ - q)
(integrate/plastic_bodies.py); the step ends ring at the step's scale (+-2 % on the 0.2 mm
block at 0.5 us steps) and are not what yields.

What the tests' 10 x 10 x 5 mm block lacked (benchmarks/yield_onset.py; lab note
docs/notes/2026-11-27-yield-onset.md): on it the midpoint sigma_max / Y = 1.033, 0.979, 0.968
at 2.6, 3.9, 5.5 elements per a (onset 0.92, 1.06, 1.08 v_y): the mesh converges to a field
~3 % below Hertz's maximum. At the FE's own peak force the 0.2 mm field is 0.983 of Hertz's on
that block and 1.001 on this one: the small free block (6.5 a thick, 1.35 g) lowers the peak
subsurface stress by ~2 %; the 0.5 us step lowers the peak force by 1.2 % (0.5 % of the
stress) against 0.25 us; a sphere cap with 0.05 mm facets moves the peak by 0.4 %.

Validation tier (`pytest -m validation`): three runs on the 27,684-DOF block, 215 s of CPU
(4 min 47 s wall at load ~4 on the shared 2-core machine; the elastic test 148 s, the plastic
pair 135 s).
"""

from __future__ import annotations

import numpy as np
import pytest
from test_plastic_dynamics import E_STAR, NU, R, Y, _hertz, _impact, _yield_speed

from flexmvm.integrate.theta import theta_for_damping_time
from flexmvm.mesh.gmsh_session import Refinement
from flexmvm.mesh.parts import block
from flexmvm.plasticity.body import PlasticBody
from flexmvm.plasticity.material import J2Plasticity
from flexmvm.plasticity.return_mapping import von_mises
from flexmvm.theory.hertz_yield import yield_onset

DT_S = 0.5e-6
#: theta of the tests' steps (hf_damping_time_s 12.5 us in _impact's scenario).
THETA = theta_for_damping_time(DT_S, 12.5e-6)


@pytest.fixture(scope="module")
def big_block(tmp_path_factory):
    """20 x 20 x 10 mm, 0.2 mm within 1.2 mm of the top centre growing to 2 mm over 2 mm."""
    refine = Refinement((0, 0, 0), 0.2e-3, 1.2e-3, 2e-3)
    path = tmp_path_factory.mktemp("onset_block") / "block_20x10_200um.msh"
    return block(path, 20e-3, 20e-3, 10e-3, 2e-3, order=2, refine=refine)


def _midpoint_peak_von_mises(built, res) -> tuple[float, np.ndarray]:
    """Largest elastic von Mises stress [Pa] at the block's integration points at the step
    midpoints within 3 steps of the peak force, and that point's undeformed position [m]."""
    info, body = built.info[1], built.system.bodies[1]
    elastic = PlasticBody.build(info.mesh, info.material, J2Plasticity(1e30))
    state, q = elastic.virgin_state(), res.q[1]
    k0 = int(np.argmax(res.contact_force))
    worst, where = 0.0, 0
    for k in range(max(k0 - 3, 1), min(k0 + 4, len(res.t))):
        u = body.psi @ (q[k - 1] + THETA * (q[k] - q[k - 1]))
        vm = von_mises(elastic.respond(u, state).stress)
        if vm.max() > worst:
            worst, where = float(vm.max()), int(np.argmax(vm))
    return worst, elastic.point_coordinates()[where]


@pytest.mark.validation  # long: in `pytest -m validation`, not the default run
def test_peak_stress_at_hertz_yield_speed_is_hertz_maximum(big_block):
    """Elastic run at Hertz's v_y: sigma_max / Y within 2 % of 1, which is the issue's 5 %
    in speed (1.0207^(-5/2) = 0.95; measured 0.994, onset at 1.015 v_y), the peak 0.3 a to
    0.7 a deep (Hertz: 0.49 a, a broad maximum; measured 0.55 a). The peak force within 3 %
    of Hertz's: measured 0.979, 0.986 at 0.25 us steps (the rest: the block's vibration and
    its compliance beyond the Hertz zone, which the half-space lacks), so 3 % holds those
    two with a 1 % margin."""
    v_y = _yield_speed(big_block)
    hz = _hertz(big_block, v_y)
    built, res = _impact(big_block, v_y, None, 0.6 * hz.duration_s, DT_S)
    assert res.steps_on_roundoff_floor == 0
    assert abs(res.contact_force.max() / hz.force_max_n - 1.0) < 0.03
    peak, point = _midpoint_peak_von_mises(built, res)
    ratio = peak / Y
    assert abs(ratio - 1.0) < 0.0207, ratio
    depth = -point[2] / yield_onset(Y, E_STAR, R, NU).radius_m
    assert 0.3 < depth < 0.7, depth
    assert abs(ratio**-2.5 - 1.0) < 0.05, ratio**-2.5


@pytest.mark.validation  # long: in `pytest -m validation`, not the default run
def test_block_yields_between_095_and_105_of_hertz_speed(big_block):
    """Elastic-perfectly plastic block: at 0.95 v_y (Hertz) the cells near the contact are
    returned and none of their points yields (alpha exactly 0: a return below the yield
    surface leaves the point untouched); at 1.05 v_y points yield, all where Hertz puts the
    maximum (0.49 a deep, within 6 % of it from 0.3 a to 0.7 a on the axis): between 0.25 a
    and 0.75 a deep. The onset lies between 0.95 and 1.05 of Hertz's speed."""
    v_y = _yield_speed(big_block)
    t_end = 0.6 * _hertz(big_block, v_y).duration_s
    onset = yield_onset(Y, E_STAR, R, NU)
    _, below = _impact(big_block, 0.95 * v_y, {"yield_pa": Y}, t_end, DT_S)
    report = below.plastic["block"]
    assert report.n_set_cells > 0
    assert report.peak_equivalent_plastic_strain == 0.0 and report.plastic_work_j == 0.0
    built, above = _impact(big_block, 1.05 * v_y, {"yield_pa": Y}, t_end, DT_S)
    alpha = above.plastic["block"].point_equivalent_plastic_strain
    assert alpha.max() > 0.0
    points = built.system.plastic[0].model.point_coordinates()[alpha > 0.0]
    depth = -points[:, 2] / onset.radius_m
    assert depth.min() > 0.25 and depth.max() < 0.75, (depth.min(), depth.max())
    assert below.steps_on_roundoff_floor == 0 and above.steps_on_roundoff_floor == 0
