"""Long physics validation (issue 4 acceptance), not in the default run:

    python -m pytest -m validation   (cases stored in docs/validation/, reused when their key
                                      matches: the package source hash and every run setting)
    python -m flexmvm.validation      (the same cases; writes docs/validation.md)

Full-FE runs of the seed rods (two 25,000-DOF bodies) take several minutes each. The short
version of the seed case is checked live in the default run (tests/test_validation_live.py).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from flexmvm import validation

pytestmark = pytest.mark.validation
OUT = Path(__file__).resolve().parents[1] / "docs" / "validation"


def test_flat_variant_full_fe_against_st_venant():
    """Plateau within 3 % of v0 Z1 Z2/(Z1 + Z2); free end jumps at L/c within 2 % (the jump is
    timed at half the 1D amplitude, 2 F0 / Z2)."""
    r = validation.flat_vs_st_venant(OUT, 0.5e-3, 0.5e-6)
    assert abs(r["plateau_err"]) < 0.03
    assert abs(r["jump_err"]) < 0.02
    assert r["momentum_rel_error"] < 1e-9
    assert r["lcp_residual_max"] <= 1e-8 and r["steps_not_converged"] == 0


def test_seed_full_fe_and_mvm_against_theory_and_each_other():
    """Seed case: full FE vs 1D wave-Hertz: force NCC over the contact >= 0.999 (measured
    0.99957 on the stored histories, 0.99960 over the whole 1 ms window; the bound allows
    1 - r to grow 2.3 x: a contact law off by a few percent in stiffness, a mesh one level
    coarser (the short case's coarse-vs-refined 1 - r is 2.7e-3) or a lost wave reflection
    breaks it), b2 free-end NCC >= 0.999 (measured 0.99965), peak within 3 %, end of contact
    within 5 %; MVM (b2 <= 150 DOF) vs full FE: force NCC >= 0.9995 (measured 0.99981 over
    the contact, 0.99992 over the window; 1-1 + 37, the seed's model, reads 0.8976 here, and a
    basis missing its constraint modes (eq. 4) 0.84 on the short case)."""
    r = validation.seed_vs_theory(OUT, 1.0e-3, 0.5e-6)
    th = r["full_vs_theory"]
    assert th["ncc_force"] >= 0.999
    assert th["ncc_b2_free_end"] >= 0.999
    assert abs(th["peak_err"]) < 0.03
    assert abs(th["duration_err"]) < 0.05
    assert r["mvm_dof"]["b2"] <= 150 + 6
    assert r["mvm_vs_full"]["ncc_force"] >= 0.9995
    for key in ("full", "mvm"):
        assert r[key]["momentum_rel_error"] < 1e-9
        # every LCP solved (a tensile impulse or one on an opening gap reads ~1) and every
        # Newton step converged to rtol
        assert r[key]["lcp_residual_max"] <= 1e-8 and r[key]["steps_not_converged"] == 0
        # penetration, of the peak Hertz approach (21.3 um in the 1D solution): b2's slave nodes
        # into b1 (held by the constraint) within 2 %; either way within 10 % (b1's nodes sit
        # in b2's facets by their chord error, 1.8 um measured: docs/validation.md)
        assert r[key]["max_penetration_m"] < 0.10 * 21.3e-6
        by = r[key]["max_penetration_by_direction_m"]
        if by is not None:  # None: a cached run from before the two-way measure
            assert by["b2 nodes into b1"] < 0.02 * 21.3e-6


def test_seed_force_converges_with_the_step():
    """Halving the step changes the contact force history little: NCC(h/2 vs h) >= 0.999 and
    peak within 1 % over the first 0.2 ms."""
    r = validation.step_convergence(OUT, 2e-4, 0.5e-6, t_end_h=validation.T_SEED)["h_half_vs_h"]
    assert r["ncc_force"] >= 0.999
    assert abs(r["peak_err"]) < 0.01


def test_pendulum_whole_event():
    """The seed's experiment on its defaults (issue 14 part 1), the whole 0.36 s event:
    - the impact speed within 0.5 % of sqrt(2 g h) (the issue's bound; measured -8e-5 with
      b2 MVM: the swing's numerical damping and the strings' sag);
    - the impact phase against the seed case with the same models and scheme, aligned at first
      contact: force NCC >= 0.995 (the issue's bound; measured 0.9999: the strings and gravity
      change the 0.66 ms impact by their tilt and weight only);
    - each rod's momentum at the end within 0.1 % of a rigid pendulum swinging on from the
      separation (measured 2e-6 and 6e-6: the rods' vibration moves their centres of mass by
      micrometres, the swing by 4.5 ms of a 1.4 s period);
    - string drift below 1e-9 m (position-level joints: measured 4.0e-13 m); the LCPs solved;
      every Newton step within 2 x its rtol 1e-10 and at most 10 of them stopped on the
      round-off floor (measured: all converged but one of 2,881, residual 1.4e-10; a step
      that stalls is accepted up to ROUNDOFF_FLOOR = 1e-7, so the former bound of 100 x rtol
      let a Newton iteration stall at 1e-8 on every step unseen)."""
    r = validation.pendulum_case(OUT)
    assert abs(r["impact_speed_err"]) < 0.005
    assert r["vs_seed"]["ncc_force"] >= 0.995
    for b in ("b1", "b2"):
        assert abs(r["momenta"][b]["p_end_rel_err_x"]) < 1e-3
    assert r["max_joint_drift_m"] < 1e-9
    assert r["newton_residual_max"] < 2e-10
    assert r["steps_not_converged"] <= 10
    assert r["lcp_residual_max"] <= 1e-8
