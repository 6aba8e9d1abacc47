"""Onset of yield of a rigid sphere on a free block within 5 % of Hertz's yield speed (issue
37: "sphere onto a block: onset of yield at the Hertz speed where p0 = 1.6 Y, within 5 %").

The case of tests/test_plastic_dynamics.py (its module doc): sphere R 10 mm rigid, 1.03 g;
block 10 x 10 x 5 mm tet10, E 70 GPa, nu 0.33, Y 2.35 GPa; Hertz's first yield (von Mises on
the axis, p0 = 1.649 Y; theory.hertz_yield) at v_y = 20.0 m/s, a = 0.77 mm. At v_y Hertz's
subsurface von Mises maximum is Y, so an elastic run at v_y measures the mesh's error as
sigma_max / Y, and the mesh's own onset speed is v_y (Y / sigma_max)^(5/2) (the stresses of
a Hertz impact grow as v^(2/5)).

What the error is made of (benchmarks/yield_onset.py; docs/notes/2026-11-27-yield-onset.md):
the block's element size at the contact. sigma_max / Y = 1.055, 1.002, 0.988 at 2.6, 3.9, 5.5
elements per a (0.3, 0.2, 0.14 mm; observed order ~3 in h); a sphere cap with 0.05 mm facets
instead of the committed 0.1-0.17 mm moves it by 0.4 %, the step (0.25 against 0.5 us) and
the block's size (20 x 20 x 10 mm) by less (the lab note). So the block of 0.2 mm within 1.2
mm (3.9 elements per a, 16,743 DOF) yields first at 0.99 v_y; the plastic runs bracket it:
none of its points yields at 0.95 v_y, some do at 1.05 v_y.

Validation tier (`pytest -m validation`): four runs, about 2 minutes of CPU.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_plastic_dynamics import E_STAR, NU, R, Y, _block, _hertz, _impact, _yield_speed

from flexmvm.plasticity.body import PlasticBody
from flexmvm.plasticity.material import J2Plasticity
from flexmvm.plasticity.return_mapping import von_mises
from flexmvm.theory.hertz_yield import yield_onset

#: The block's fine zone: element size and radius [m] (3.9 elements per contact radius).
FINE_M, FINE_RADIUS_M = 0.2e-3, 1.2e-3


def _peak_von_mises(built, res) -> float:
    """Largest elastic von Mises stress [Pa] at the block's integration points over the
    outputs within 3 of the peak force."""
    info, body = built.info[1], built.system.bodies[1]
    elastic = PlasticBody.build(info.mesh, info.material, J2Plasticity(1e30))
    state = elastic.virgin_state()
    k0 = int(np.argmax(res.contact_force))
    steps = range(max(k0 - 3, 0), min(k0 + 4, len(res.t)))
    return max(
        float(von_mises(elastic.respond(body.psi @ res.q[1][k], state).stress).max()) for k in steps
    )


def _stress_ratio(mesh) -> float:
    """sigma_max / Y of the elastic run at Hertz's v_y (0.5 us steps, to 0.6 of the Hertz
    duration: past the deepest approach)."""
    v_y = _yield_speed(mesh)
    built, res = _impact(mesh, v_y, None, 0.6 * _hertz(mesh, v_y).duration_s, 0.5e-6)
    assert res.steps_not_converged == 0
    return _peak_von_mises(built, res) / Y


@pytest.fixture(scope="module")
def fine_block(tmp_path_factory):
    return _block(tmp_path_factory.mktemp("onset_block"), FINE_M, FINE_RADIUS_M)


@pytest.mark.validation  # long: in `pytest -m validation`, not the default run
def test_peak_stress_converges_to_hertz_and_the_onset_speed_within_5_percent(fine_block, tmp_path):
    """sigma_max / Y at v_y on the tests' 0.3 mm block (2.6 elements per a) and on the
    0.2 mm block (3.9): measured 1.055 and 1.002. The finer is held within 2 % of Hertz's
    maximum, which is the issue's 5 % in speed (1.0207^(-5/2) = 0.95; measured onset
    0.994 v_y); the coarser is held above 1.03 and farther from Hertz than the finer, the
    convergence that makes the finer's agreement a converged stress and not a chance
    crossing (the next refinement, 5.5 per a, gave 0.988: the lab note)."""
    coarse = _stress_ratio(_block(tmp_path, 0.3e-3, 0.8e-3))
    fine = _stress_ratio(fine_block)
    assert coarse > 1.03, coarse
    assert abs(fine - 1.0) < abs(coarse - 1.0), (coarse, fine)
    assert abs(fine - 1.0) < 0.02, fine
    assert abs(fine**-2.5 - 1.0) < 0.05, fine**-2.5


@pytest.mark.validation  # long: in `pytest -m validation`, not the default run
def test_fine_block_yields_between_095_and_105_of_hertz_speed(fine_block):
    """Elastic-perfectly plastic block: at 0.95 v_y (Hertz) the cells near the contact are
    returned and none of their points yields (alpha exactly 0: the return leaves a point
    below the yield surface untouched); at 1.05 v_y points yield, all where Hertz puts the
    maximum (0.49 a deep; a broad maximum, within 6 % of it from 0.3 a to 0.7 a on the axis):
    between 0.25 a and 0.75 a deep. The onset is therefore within 5 % of Hertz's speed."""
    v_y = _yield_speed(fine_block)
    t_end = 0.6 * _hertz(fine_block, v_y).duration_s
    onset = yield_onset(Y, E_STAR, R, NU)
    _, below = _impact(fine_block, 0.95 * v_y, {"yield_pa": Y}, t_end, 0.5e-6)
    report = below.plastic["block"]
    assert report.n_set_cells > 0
    assert report.peak_equivalent_plastic_strain == 0.0 and report.plastic_work_j == 0.0
    built, above = _impact(fine_block, 1.05 * v_y, {"yield_pa": Y}, t_end, 0.5e-6)
    alpha = above.plastic["block"].point_equivalent_plastic_strain
    assert alpha.max() > 0.0
    points = built.system.plastic[0].model.point_coordinates()[alpha > 0.0]
    depth = -points[:, 2] / onset.radius_m
    assert depth.min() > 0.25 and depth.max() < 0.75, (depth.min(), depth.max())
    assert below.steps_not_converged == 0 and above.steps_not_converged == 0
