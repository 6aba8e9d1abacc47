"""A step whose Newton iteration fails is cut in halves (integrate.driver._advance), down to
dt_s / 2^MAX_STEP_CUTS; a run that still cannot go on raises SimulationFailed carrying what it
computed, and `flexmvm run` writes that (summary status "failed") and exits non-zero.

The failures are injected into the scheme's step (a SolverError for steps longer than a
threshold inside a time window), so that the policy is tested apart from any one mesh."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import numpy as np
import pytest

import flexmvm as fm
from flexmvm.cli import main as cli_main
from flexmvm.errors import SimulationFailed, SolverError
from flexmvm.integrate import driver
from flexmvm.integrate.moreau_jean import MoreauJeanIntegrator

TINY = Path(__file__).parent / "data" / "tiny_impact.toml"
T_END = 6e-6  # 24 steps of the tiny case's dt_s = 0.25 us


def _failing(monkeypatch, longest_ok: float, window=(2e-6, 3e-6)):
    """Steps that start inside window and are longer than longest_ok [s] fail."""
    real = MoreauJeanIntegrator.step

    def step(self, t, states, h):
        if window[0] <= t < window[1] and h > longest_ok * (1 + 1e-9):
            raise SolverError(f"injected: h = {h:.3g} s too long at t = {t:.3g} s")
        return real(self, t, states, h)

    monkeypatch.setattr(MoreauJeanIntegrator, "step", step)


def _tiny():
    return fm.load_scenario(TINY).with_time(t_end_s=T_END)


def test_a_failing_step_is_cut_and_the_run_matches_one_with_that_step(monkeypatch):
    """Steps in [2, 3) us fail above dt/4: each is taken as four quarter steps (3 cuts per
    failed step: one into halves, two for the halves). Steps are exact to the Newton tolerance
    whatever their size, so the contact force at the end agrees with an uncut run to the
    scheme's time-discretisation error, and the step sizes say what happened."""
    ref = fm.run(_tiny())
    _failing(monkeypatch, 0.25e-6 / 4)
    cut = fm.run(_tiny())
    dt = 0.25e-6
    sizes = cut.steps.size_counts()
    assert min(sizes) == pytest.approx(dt / 4)
    n_failed = 4  # steps starting at 2.0, 2.25, 2.5, 2.75 us
    assert sizes[min(sizes)] == 4 * n_failed
    assert cut.summary["step_cuts"] == 3 * n_failed
    assert cut.summary["dt_min_taken_s"] == pytest.approx(dt / 4)
    assert cut.summary["status"] == "completed"
    np.testing.assert_allclose(cut.t, ref.t)
    # outputs away from the cut window agree to the time-discretisation error of the window
    # (second order: quarter steps change the force by ~ (h^2 - (h/4)^2) of its curvature)
    scale = np.abs(ref.contact_force).max()
    assert np.abs(cut.contact_force - ref.contact_force).max() < 0.05 * scale
    assert np.abs(cut.contact_force[:3] - ref.contact_force[:3]).max() == 0.0  # before: same


def test_a_step_that_fails_at_the_smallest_step_stops_the_run_with_what_it_computed(monkeypatch):
    _failing(monkeypatch, 0.0)  # nothing converges inside the window
    with pytest.raises(SimulationFailed) as info:
        fm.run(_tiny())
    msg = str(info.value)
    assert "t = 2e-06 s" in msg and "cut down to" in msg and "injected" in msg
    part = info.value.partial
    assert part.summary["status"] == "failed" and "injected" in part.summary["failure"]
    assert part.t[-1] == pytest.approx(2e-6)  # the last output before the failure
    assert part.summary["t_end_reached_s"] == pytest.approx(2e-6)
    assert len(part.t) == 3 and part.contact_force.shape == (3,)
    monkeypatch.undo()
    ref = fm.run(_tiny())
    np.testing.assert_array_equal(part.contact_force, ref.contact_force[:3])


def test_flexmvm_run_writes_the_history_up_to_the_failure(tmp_path, monkeypatch, capsys):
    _failing(monkeypatch, 0.0)
    out = tmp_path / "out"
    code = 0
    try:
        cli_main.main(
            [
                "run",
                str(TINY),
                "--out",
                str(out),
                "--t-end",
                str(T_END),
                "--model",
                "full",
                "--no-fields",
                "--no-progress",
                "--jobs",
                "1",
            ]
        )
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "histories up to t = 2e-06 s" in err[0], err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and "injected" in summary["failure"]
    rows = (out / "history.csv").read_text().strip().splitlines()
    assert len(rows) == 1 + 3  # header + outputs at 0, 1, 2 us


def test_cut_limit_is_stated():
    assert driver.MAX_STEP_CUTS == 6


def test_the_hook_sees_every_accepted_step_of_the_integrator_the_call_chose():
    """simulate(integrator=..., on_step=...): the run steps with the integrator the factory
    makes (here the Moreau-Jean one whose steps in [2, 3) us fail above dt/2, so each of those
    4 steps is cut once into 2 halves), and the hook is called once per accepted step, cut
    halves included, in order: each step starts from the states the last one ended with (the
    same objects), at the time it ended (to round-off of the tick grid, 1e-12 relative), and
    the hook's step sizes and impulses are the run's step history exactly. ~3 s."""
    from flexmvm.assembly.build import build_scenario

    built = build_scenario(_tiny())
    dt = built.grid.dt_s
    made = []

    def factory(system, grid):
        integ = MoreauJeanIntegrator(system, theta=grid.theta)
        real = integ.step

        def step(t, states, h):
            if 2e-6 <= t < 3e-6 and h > 0.5 * dt * (1 + 1e-9):
                raise SolverError("injected")
            return real(t, states, h)

        integ.step = step
        made.append(integ)
        return integ

    seen = []
    run = driver.simulate(
        built.system,
        built.states,
        built.grid,
        built.probes,
        integrator=factory,
        on_step=seen.append,
    )
    assert len(made) == 1 and run.step_cuts == 4
    assert len(seen) == run.n_steps == 24 + 4
    np.testing.assert_array_equal([s.h_s for s in seen], run.steps.h_s)
    np.testing.assert_array_equal([s.t_end_s for s in seen], run.steps.t_s)
    np.testing.assert_array_equal(
        [s.result.contact.normal_impulse(s.result.contact_impulses) for s in seen],
        run.steps.contact_impulse_Ns,
    )
    for last, step in itertools.pairwise(seen):
        assert step.start is last.states
        assert step.t_s == pytest.approx(last.t_end_s, rel=1e-12)
    assert seen[-1].t_end_s == pytest.approx(T_END, rel=1e-12)
