"""The examples/ scripts are tests too (as scikit-fem's): each is imported and its main()
run on a shortened window, and what it prints is checked against the physics it claims."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _example(name: str):
    spec = importlib.util.spec_from_file_location(f"example_{name}", EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_example_is_tested():
    tested = {"rod_impact", "pendulum_joints", "selection_study"}
    assert {p.stem for p in EXAMPLES.glob("*.py")} == tested


def test_rod_impact_example(capsys):
    """60 us of the seed case on 0.1 m rods (the force still rising towards its peak). MVM
    1-3 + 37 against full FE: NCC >= 0.9999 (0.9999999 over the whole 0.25 ms pulse in
    docs/validation.md; a rising pulse is the easier part). Full FE against the 1D wave-Hertz
    theory: NCC >= 0.99 (0.9996 over the whole pulse; the first microseconds, where the
    discrete contact patch has a handful of nodes, weigh more in a short window). Momentum of
    the free pair: conserved to 1e-9 of the initial momentum (the scheme's residual floor)."""
    out = _example("rod_impact").main(t_end_s=6e-5)
    assert out["dof_b2"] == 6 + 3 * 25 + 37
    assert out["mvm_vs_full"].ncc_force >= 0.9999
    assert out["full_vs_theory"].ncc_force >= 0.99
    for run in (out["mvm"], out["full"]):
        p = run.result.momentum
        assert np.abs(p - p[0]).max() <= 1e-9 * np.linalg.norm(p[0])
        assert run.steps.contact_impulse_Ns.sum() == pytest.approx(
            np.sum(run.contact_force[1:] * np.diff(run.t)), rel=1e-12
        )
    assert "force NCC against full FE" in capsys.readouterr().out


def test_pendulum_joints_example():
    """A quarter period and a fifth: the bottom speed is sqrt(2 g h) to 0.1 % (the elastic
    energy of the gravity sag is ~1e-7 of m g h; h = 2e-4 s steps resolve the swing to
    ~1e-5), and the position-level strings keep their length to 1e-12 m."""
    out = _example("pendulum_joints").main()
    assert out["speed_max_mps"] == pytest.approx(out["expected_mps"], rel=1e-3)
    assert out["result"].max_joint_drift < 1e-12


def test_selection_study_example():
    """tests/data/tiny_impact.toml (30 us window): every model of the 2 x 2 x 2 grid has force
    NCC > 0.9999 there, the 7-mode ones below 0.99999 and the 13-mode ones above
    (tests/test_studies.py), so at the target 0.99999 the smallest model is 1-1 + 13 modes, not
    the smallest candidate 1-1 + 7; the a-priori estimate is 1-1 + 13 (studies/selection.py
    module doc)."""
    out = _example("selection_study").main(target=0.99999)
    assert len(out["study"].rows) == 8
    assert all(r["ncc_force"] > 0.9999 for r in out["study"].rows)
    best = out["best"]
    assert (best["layers"], best["laps"], best["modes"], best["dof"]) == (1, 1, 13, 16)
    est = out["estimate"]
    assert (est["layers"], est["laps"], est["modes"]) == (1, 1, 13)
