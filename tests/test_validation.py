"""Long physics validation (issue 4 acceptance), not in the default run:

    python -m pytest -m validation   (cases stored in docs/validation/, reused when their key
                                      matches: the package source hash and every run setting)
    flexmvm validate                  (the same cases; writes docs/validation.md; also
                                      `python -m flexmvm.validation`)

Every bound, with its reason, is a row of flexmvm.validation.acceptance.ACCEPTANCE, the table
the report states its acceptance from; each test checks every row of its case. Full-FE runs of
the seed rods (two 25,000-DOF bodies) take several minutes each. The short version of the seed
case is checked live in the default run (tests/test_validation_live.py).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from flexmvm import validation
from flexmvm.validation import acceptance

pytestmark = pytest.mark.validation
OUT = Path(__file__).resolve().parents[1] / "docs" / "validation"


def _check(numbers: dict, section: str) -> None:
    assert acceptance.criteria(section), f"no acceptance rows for {section}"
    bad = acceptance.failures(numbers, section)
    assert not bad, "\n".join(bad)


def test_flat_variant_full_fe_against_st_venant():
    """Plateau within 3 % of v0 Z1 Z2/(Z1 + Z2); free end jumps at L/c within 2 %;
    conservation (acceptance rows of "flat_vs_st_venant")."""
    _check(validation.flat_vs_st_venant(OUT), "flat_vs_st_venant")


def test_seed_full_fe_and_mvm_against_theory_and_each_other():
    """Seed case: full FE vs 1D wave-Hertz (force and b2 free-end NCC, peak, end of contact)
    and the MVM (b2 <= 150 DOF) vs full FE; both runs' momentum, LCPs, Newton steps and
    penetration, energy over the shipped window (acceptance rows of "seed"; rod_impact.toml as
    shipped, validation.seed_scenario)."""
    _check(validation.seed_vs_theory(OUT), "seed")


def test_seed_force_converges_with_the_step():
    """Halving the step changes the contact force history little: NCC(h/2 vs h) and peak over
    the first 0.2 ms (acceptance rows of "step_convergence")."""
    _check(
        validation.step_convergence(OUT, 2e-4, 0.5e-6, t_end_h=validation.T_SEED),
        "step_convergence",
    )


def test_pendulum_whole_event():
    """The seed's experiment on its defaults (issue 14 part 1), the whole 0.36 s event: impact
    speed, the impact against the seed case, the momenta at the end against the rigid
    pendulum, string drift, Newton and LCP health (acceptance rows of "pendulum")."""
    _check(validation.pendulum_case(OUT), "pendulum")


def test_arm_spun_up_into_a_stop():
    """Issue 35's showcase: the MVM arm against the full-FE one (force and tip velocity NCC),
    both runs' energy ledger closed to 0.1 % of the motor's work, every step converged
    (acceptance rows of "arm_stop"; the full-FE run takes a quarter of an hour)."""
    _check(validation.arm_stop_case(OUT), "arm_stop")


@pytest.mark.parametrize("section", ["flat_vs_st_venant", "seed", "step_convergence", "pendulum"])
def test_stored_report_meets_the_table(section):
    """The numbers of docs/validation/validation.json (those docs/validation.md shows) meet
    every row of the acceptance table: the page and the table cannot disagree."""
    import json

    report = json.loads((OUT / "validation.json").read_text())
    _check(report[section], section)
