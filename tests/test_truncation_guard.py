"""The truncation guard (issue 51, reduction/truncation.py): a Craig-Bampton body with too few
modes for its contact gets a word; the shipped mode count does not.

Measured on scenarios/sphere_beam.toml (the beam as kind mvm, against full FE; docs/concepts.md,
"Too few modes"): 10 modes, residual time 3.7 us against the first contact's ~78 us (force
NCC 0.905, peak +12.5 %); 30 modes (shipped) 0.11 us (NCC 1.0000, peak -0.1 %).
"""

from __future__ import annotations

import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from flexmvm.assembly.build import build_scenario
from flexmvm.reduction.truncation import RATIO_WARN, first_contact_duration
from flexmvm.scenarios.load import load_scenario

ROOT = Path(__file__).resolve().parents[1]
SPHERE_BEAM = ROOT / "scenarios" / "sphere_beam.toml"


def _beam_case(tmp_path: Path, modes: int) -> Path:
    """sphere_beam.toml with ``modes`` modes on the beam, beside a link to its meshes."""
    text = SPHERE_BEAM.read_text()
    assert text.count("modes = 30\n") == 1
    tmp_path.mkdir(exist_ok=True)
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


def test_residual_time_grows_as_modes_are_cut(tmp_path):
    """The beam's residual time (build time, no run): 10 modes 3.66 us, 30 modes 0.110 us
    (measured; 3 % tolerance: the mode solve's tolerance and a BLAS's round-off move it
    less)."""
    few, shipped = _beam_guard(tmp_path / "a", 10), _beam_guard(tmp_path / "b", 30)
    assert few["n_modes"] == 10 and shipped["n_modes"] == 30
    assert few["residual_time_s"] == pytest.approx(3.66e-6, rel=0.03)
    assert shipped["residual_time_s"] == pytest.approx(1.10e-7, rel=0.03)


def test_first_contact_duration():
    """One pulse of 4 steps of 1 us (a 0.5 % tail ignored), then a second: 4 us; a pulse open
    at the end: None."""
    h = np.full(10, 1e-6)
    t = np.cumsum(h)
    x = np.array([0, 1, 3, 3, 1, 0.004, 0, 2, 2, 0]) * 1e-6
    assert first_contact_duration(t, x, h) == pytest.approx(4e-6, rel=1e-12)
    assert first_contact_duration(t, np.r_[x[:5], np.ones(5) * 1e-6], h) is None
    assert first_contact_duration(t, np.zeros(10), h) is None


def _run(tmp_path: Path, modes: int) -> tuple[str, dict]:
    """`flexmvm run` on the beam with ``modes`` modes over its first contact (0.12 ms)."""
    tmp_path.mkdir()
    out = tmp_path / "out"
    proc = subprocess.run(
        [sys.executable, "-m", "flexmvm.cli.main", "run", _beam_case(tmp_path, modes)]
        + ["--out", out, "--model", "mvm", "--t-end", "1.2e-4", "--no-fields", "--no-theory"]
        + ["--no-progress", "--jobs", "1"],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    return proc.stdout + proc.stderr, json.loads((out / "summary.json").read_text())


def test_few_modes_warn(tmp_path):
    """10 modes (NCC 0.905, peak +12.5 % against full FE): T_r / T_c = 0.047 measured,
    above the threshold 0.015; the warning printed and the ratio in summary.json."""
    text, summary = _run(tmp_path / "r", 10)
    g = summary["modal_truncation_guard"]["beam"]
    assert g["residual_to_contact"] > RATIO_WARN
    assert "warning: body beam: the inertia its 10 modes cut" in text


def test_shipped_modes_are_quiet(tmp_path):
    """30 modes (the shipped count, NCC 1.0000): T_r / T_c = 0.0014 measured, 10x below."""
    text, summary = _run(tmp_path / "r", 30)
    g = summary["modal_truncation_guard"]["beam"]
    assert g["residual_to_contact"] < RATIO_WARN / 5
    assert "modes cut" not in text
