"""Newton convergence and momentum are reported from the residuals, not assumed.

Every step that stops on the round-off floor above the Newton tolerance is counted
(`steps_not_converged`, with the worst residual `newton_residual_max`), the run says so on the
console, and the linear momentum the solves left unbalanced is summed from the translational
residual rows (`momentum_residual_rel`).
"""

from __future__ import annotations

import functools
from pathlib import Path

import pytest

from flexmvm.integrate import driver
from flexmvm.integrate.moreau_jean import MoreauJeanIntegrator
from flexmvm.scenarios import load_scenario
from flexmvm.scenarios.run import run_scenario

TINY = Path(__file__).parent / "data" / "tiny_impact.toml"
RTOL = 1e-10  # the integrator's Newton tolerance (relative momentum residual)


@functools.cache
def _tiny(model):
    return run_scenario(load_scenario(TINY).with_overrides(model=model, t_end_s=10e-6)).summary


@pytest.mark.parametrize("model", [None, "mvm"])
def test_converged_run_reports_its_residuals(model):
    """The tiny seed case converges every step: no step counted, the worst exit residual below
    rtol, and the momentum left unbalanced by the residuals (a sum over ~40 steps of residuals
    below rtol of each body's momentum scale) far below rtol times the number of steps; the
    measured momentum error (evaluated from the states) is of the same round-off order."""
    s = _tiny(model)
    assert s["steps_not_converged"] == 0
    assert 0.0 < s["newton_residual_max"] <= RTOL
    assert s["momentum_residual_rel"] <= 40 * RTOL
    assert s["momentum_rel_error"] <= 40 * RTOL
    assert s["lcp_residual_max"] <= 1e-8


def test_steps_stopped_on_the_floor_are_counted(monkeypatch, tmp_path):
    """With an unreachable tolerance (1e-18, below double round-off of the momentum sums) every
    contact step stops on the round-off floor: each is counted, the worst residual is above the
    tolerance, and `flexmvm run` prints a warning naming the count."""
    monkeypatch.setattr(driver, "MoreauJeanIntegrator",
                        functools.partial(MoreauJeanIntegrator, rtol=1e-18))
    s = run_scenario(load_scenario(TINY).with_overrides(t_end_s=3e-6)).summary
    assert s["steps_not_converged"] == s["n_steps"] == 12
    assert s["newton_residual_max"] > 1e-18

    from click.testing import CliRunner

    from flexmvm.cli.main import _register, cli

    _register()
    res = CliRunner().invoke(cli, ["run", str(TINY), "--t-end", "3e-6", "--no-fields",
                                   "--no-progress", "--jobs", "1", "--out",
                                   str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    assert "12 step(s) stopped on the round-off floor" in res.output
