"""Command-line behaviour: bad input gives one line on stderr and exit status 2, no traceback."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SEED = ROOT / "scenarios" / "rod_impact.toml"


def _flexmvm(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "flexmvm.cli.main", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=600,
        check=False,
    )


def _one_line_error(proc, *words):
    assert proc.returncode == 2, proc.stderr
    err = proc.stderr.strip()
    assert "Traceback" not in proc.stderr
    assert len(err.splitlines()) == 1, err
    assert err.startswith("flexmvm: error:")
    for w in words:
        assert w in err, err


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--E", "-1"], ["Young's modulus", "-1"]),
        (["--nu", "0.5"], ["Poisson ratio"]),
        (["--radius", "0"], ["radius_m"]),
        (["--length", "-2"], ["length_m"]),
        (["--selection", "9-99"], ["laps", "99"]),
    ],
)
def test_mesh_rod_bad_input(args, words):
    _one_line_error(_flexmvm("mesh", "rod", "--modes", "0", *args), *words)


def test_mesh_rod_prints_the_summary(tmp_path):
    p = _flexmvm("mesh", "rod", "--length", "0.2", "--modes", "8", "--write", tmp_path / "rod.vtu")
    assert p.returncode == 0, p.stderr
    assert "nodes" in p.stdout and "free-free frequencies" in p.stdout
    assert (tmp_path / "rod.vtu").exists()


def _edited(tmp_path, old, new, source=SEED):
    text = source.read_text()
    assert text.count(old) >= 1, old
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize(
    ("old", "new", "words"),
    [
        ('name = "rod_impact"', 'name = "rod_impact"\ncolour = "red"', ["colour", "unknown key"]),
        ('master = "b1.end_a"', 'master = "b9.end_a"', ["contacts[0].master", "b9"]),
        ('slave = "b2.end_a"', 'slave = "b2.nowhere"', ["contacts[0].slave", "nowhere"]),
        (
            'node_set = "end_b_centre"',
            "point_m = [3.0, 0.0, 0.0]",
            ["probes[1].point_m", "off the body"],
        ),
        ("E_pa", "E_pa", []),
    ],
)
def test_run_bad_scenarios(tmp_path, old, new, words):
    """Unknown key, missing body, unknown surface, probe off the body: one line naming the key."""
    if old == "E_pa":
        path = _edited(
            tmp_path,
            'material = "aluminium" ',
            "material = { E_pa = -1.0, nu = 0.33, rho_kg_m3 = 2700.0 } ",
        )
        words = ["E_pa", "-1"]
    else:
        path = _edited(tmp_path, old, new)
    _one_line_error(
        _flexmvm(
            "run",
            path,
            "--out",
            tmp_path / "out",
            "--t-end",
            "4e-6",
            "--model",
            "rigid",
            "--no-fields",
            "--no-progress",
        ),
        *words,
    )


def test_missing_scenario_file(tmp_path):
    _one_line_error(_flexmvm("run", tmp_path / "none.toml", "--out", tmp_path / "o"), "none.toml")


def test_theory_writes_the_history(tmp_path):
    p = _flexmvm("theory", SEED, "--out", tmp_path)
    assert p.returncode == 0, p.stderr
    header = (tmp_path / "history.csv").read_text().splitlines()[0]
    assert header == "t_s,contact_force_N,b2_impact_end_vx_mps,b2_free_end_vx_mps"


def test_run_model_choices_are_the_model_kinds():
    """`flexmvm run --model` takes every registered ModelKind, read from the registry when
    the option is first used (cli/kind_choice.py)."""
    from flexmvm.bodies.build import ModelKind
    from flexmvm.cli.run_cmd import command

    (model,) = [p for p in command.params if p.name == "model"]
    assert list(model.type.choices) == [k.value for k in ModelKind]
