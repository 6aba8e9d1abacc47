"""scenarios/sphere_block.toml against Hertz (issue "Your own geometry", part 2): the coarse
form, on the committed meshes (tet10 block, 0.3 mm at the contact, 11,748 DOF; the sphere's
0.1 mm facets as master), full FE over 110 us (220 steps of 0.5 us).

Hertz with the free block's recoil (flexmvm.runs.showcases.hertz_block.hertz_reference): 615.1 N,
86.7 us. Measured: peak 623.7 N (+1.4 %), duration 85.5 us (-1.4 %): a static indentation of
the same mesh (tests/test_quadratic_contact.py) is 3.6 % stiffer than Hertz at the peak's
approach, and a contact stiffer by c changes the peak by c^(2/5) and the duration by
c^(-2/5): +1.4 % and -1.4 %. The issue's tolerance, 3 %, holds at this mesh size and at
0.2 mm (+0.9 %, -0.8 %: the validation's form, hertz_block_check). The duration is read from
the steps with contact, to one step (0.5 us, 0.6 %). Energy: the theta scheme's damping
(theta = 0.51) takes 0.13 %; held to 0.5 %. About 12 s of one core.
"""

from __future__ import annotations

import pytest

from flexmvm.errors import InputError
from flexmvm.runs.showcases.hertz_block import (
    SPHERE_BLOCK,
    compare_with_hertz,
    hertz_block_check,
    hertz_reference,
)
from flexmvm.scenarios.load import load_scenario


@pytest.fixture(scope="module")
def check():
    return compare_with_hertz(load_scenario(SPHERE_BLOCK))


def test_peak_force_and_duration_within_3_percent_of_hertz(check):
    assert check["status"] == "completed" and check["steps_on_roundoff_floor"] == 0
    assert check["hertz_peak_N"] == pytest.approx(615.1, abs=0.5)  # the reference itself
    assert abs(check["peak_err"]) < 0.03, check
    assert abs(check["duration_err"]) < 0.03, check


def test_energy_through_the_impact(check):
    assert abs(check["energy_rel_change"]) < 5e-3, check


def test_bad_input_is_one_line():
    """A mesh size that cannot resolve the contact radius, a body the scenario lacks: one-line
    InputErrors (no mesh is made, nothing runs)."""
    with pytest.raises(InputError, match=r"fine_m must be in \(0, 1e-3\] m, got 0.002"):
        hertz_block_check(2e-3)
    with pytest.raises(InputError, match="no body 'anvil'"):
        hertz_reference(load_scenario(SPHERE_BLOCK), target="anvil")
