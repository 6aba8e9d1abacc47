"""The warm command (issue 49, acceptance "3 x in the warm command"): a reduced body built a
second time, its basis and parts in the setup cache, reads its truncation guard and its cost
guard's factor counts from the cache too, so it neither loads its FE model (M, K) nor factors
K_ii again (0.46 s of sphere_block's 5.5 s warm command went to the guard's K_ii factor,
docs/notes/2026-11-29-warm-command.md)."""

from __future__ import annotations

from pathlib import Path

import pytest

import flexmvm as fm
import flexmvm.assembly.build_cache as setup_stage
from flexmvm import setup_cache
from flexmvm.assembly.build import build_scenario
from flexmvm.assembly.build_cache import SetupCache

TINY = Path(__file__).parent / "data" / "tiny_impact.toml"


def _tiny():
    """tiny_impact: b1 full FE, b2 mvm (1 retained node, 13 modes) on rod meshes."""
    return fm.load_scenario(TINY).with_time(t_end_s=1e-6)


def test_a_warm_reduced_build_loads_no_fe_model(tmp_path, monkeypatch):
    """Cold build, then a build in a fresh SetupCache (a new process's) on the same disk
    cache: the reduced b2's FE model is not read (only full-FE b1's) and its truncation guard
    is the cold one, read back exactly, without calling modal_residual; a basis of another
    mode count has its own guard, computed. Before: the cost guard read b2's M and K and the
    truncation guard factored K_ii on every run. ~3 s."""
    monkeypatch.setenv(setup_cache.ENV_DIR, str(tmp_path / "cache"))
    cold = build_scenario(_tiny(), SetupCache())
    guard = cold.info[1].truncation
    assert guard is not None and guard["residual_time_s"] > 0

    loaded = []
    real = setup_cache.cached_fe

    def counting(source, mesh, material, build):
        loaded.append(material.name)
        return real(source, mesh, material, build)

    def no_residual(*args, **kwargs):
        raise AssertionError("modal_residual called on a warm build")

    monkeypatch.setattr(setup_cache, "cached_fe", counting)
    monkeypatch.setattr(setup_stage, "modal_residual", no_residual)
    warm = build_scenario(_tiny(), SetupCache())
    assert loaded == ["brass"]  # b1 (full FE, brass) only; b2 is aluminium
    assert warm.info[1].truncation == guard  # bit for bit: stored as float64
    # another mode count is another basis: its guard is computed, not read
    data = _tiny().model_dump(mode="json")
    data["bodies"][1]["model"]["modes"] = 4
    with pytest.raises(AssertionError, match="modal_residual called"):
        build_scenario(fm.scenario_from_dict(data, base_dir=TINY.parent), SetupCache())


def test_a_corrupt_guard_entry_is_rebuilt(tmp_path, monkeypatch):
    """A guard entry holding NaN fails its check: evicted and recomputed (the store's rule),
    the same guard as the cold build's. ~2 s."""
    import numpy as np

    monkeypatch.setenv(setup_cache.ENV_DIR, str(tmp_path / "cache"))
    guard = build_scenario(_tiny(), SetupCache()).info[1].truncation
    (entry,) = (tmp_path / "cache").glob("truncation-*.npz")
    with np.load(entry) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["residual_time_s"] = np.float64("nan")
    with open(entry, "wb") as f:
        np.savez(f, **arrays)
    with pytest.warns(UserWarning, match="holds NaN or inf in residual_time_s: evicted"):
        again = build_scenario(_tiny(), SetupCache()).info[1].truncation
    assert again == pytest.approx(guard, rel=1e-12)


def test_registering_the_commands_imports_no_numerical_stage():
    """`flexmvm` registers every sub-command before it runs one: that imports click and the
    command modules only (0.03 s), not flexmvm.scenarios and its numpy, scipy, numba (1.2 s,
    through the study command's --kind choices; before). ~1 s (a fresh interpreter)."""
    import subprocess
    import sys

    code = (
        "import sys; from flexmvm.cli import app; app._register(); "
        "print(sorted(m for m in ('numpy', 'scipy', 'numba', 'flexmvm.scenarios') "
        "if m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert out.stdout.strip() == "[]", out.stdout + out.stderr


def test_the_study_kinds_are_the_retaining_model_kinds():
    """The --kind choices of `flexmvm study materials` are the model kinds that retain nodes,
    read from the registry (cli/kind_choice.py)."""
    from flexmvm.cli.study_cmd import materials
    from flexmvm.scenarios import ModelKind

    (kind,) = [p for p in materials.params if p.name == "kind"]
    assert list(kind.type.choices) == [k.value for k in ModelKind if k.retains_nodes]
