"""The truncation guard (issue 51, reduction/truncation.py): a Craig-Bampton body with too few
modes for its contact gets a word; the shipped mode count does not.

Measured on scenarios/sphere_beam.toml (the beam as kind mvm, first 0.2 ms against full FE;
docs/concepts.md, "Too few modes"): 5 modes, modal residual 6.8 %; 10 modes 1.0 % (force NCC
0.905, peak +12.5 %); 30 modes (shipped) 9e-6 (NCC 1.0000, peak -0.1 %).
"""

from __future__ import annotations

import json
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from flexmvm.reduction.truncation import RESIDUAL_WARN, truncation_warnings
from flexmvm.scenarios.build import build_scenario
from flexmvm.scenarios.load import load_scenario

ROOT = Path(__file__).resolve().parents[1]
SPHERE_BEAM = ROOT / "scenarios" / "sphere_beam.toml"


def _beam_case(tmp_path: Path, modes: int) -> Path:
    """sphere_beam.toml with ``modes`` modes on the beam, beside a link to its meshes."""
    text = SPHERE_BEAM.read_text()
    assert text.count("modes = 30\n") == 1
    (tmp_path / "meshes").symlink_to(ROOT / "scenarios" / "meshes")
    path = tmp_path / f"sphere_beam_m{modes}.toml"
    path.write_text(text.replace("modes = 30\n", f"modes = {modes}\n"))
    return path


def _beam_guard(tmp_path: Path, modes: int) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the reduced-cost note of a 10k-DOF beam
        built = build_scenario(load_scenario(_beam_case(tmp_path, modes)).with_kind("mvm"))
    (info,) = [i for i in built.info if i.name == "beam"]
    return info.truncation


def test_few_modes_fire_the_guard(tmp_path):
    """5 modes (force NCC 0.578, peak +73 % against full FE): 6.8 % of the patch's inertia
    flexibility in the cut modes (measured 0.0684), 68x the threshold 1e-3."""
    g = _beam_guard(tmp_path, 5)
    assert g["n_modes"] == 5
    assert g["modal_residual"] == pytest.approx(0.0684, rel=0.05)  # a remesh moves it little
    lines = truncation_warnings({"beam": g})
    assert len(lines) == 1 and "its 5 modes" in lines[0]


def test_shipped_modes_are_quiet(tmp_path):
    """30 modes (the shipped count, NCC 1.0000 against full FE): residual 9.1e-6, 110x
    below the threshold 1e-3."""
    g = _beam_guard(tmp_path, 30)
    assert g["modal_residual"] < 0.1 * RESIDUAL_WARN  # 9.1e-6 measured
    assert truncation_warnings({"beam": g}) == []


def test_run_prints_and_records_it(tmp_path):
    """`flexmvm run` on the 5-mode beam (4 us, contact starts at t = 0): the warning on the
    console and the residual in summary.json."""
    out = tmp_path / "out"
    proc = subprocess.run(
        [sys.executable, "-m", "flexmvm.cli.main", "run", _beam_case(tmp_path, 5)]
        + ["--out", out, "--model", "mvm", "--t-end", "4e-6", "--no-fields", "--no-theory"]
        + ["--no-progress", "--jobs", "1"],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert "warning: body beam: its 5 modes leave" in proc.stdout + proc.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["modal_truncation_guard"]["beam"]["modal_residual"] > RESIDUAL_WARN
