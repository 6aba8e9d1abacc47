"""The validation report's stored cases (tools.validation, issue 11): a case is reused only
when the code version and every setting of the run match, never by its folder name alone."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

import flexmvm.runs.run as run_module
from flexmvm.errors import StaleDataWarning
from flexmvm.runs import provenance
from flexmvm.scenarios import ModelConfig, load_scenario, scenario_from_dict
from tools import validation

TINY = Path(__file__).parent / "data" / "tiny_impact.toml"


def _tiny(**time):
    sc = load_scenario(TINY).with_overrides(t_end_s=2e-6)
    if time:
        data = sc.model_dump(mode="json")
        data["time"].update(time)
        sc = scenario_from_dict(data)
    return sc


def _rod(sc, **rod):
    data = sc.model_dump(mode="json")
    data["bodies"][0]["rod"].update(rod)
    return scenario_from_dict(data)


def test_key_changes_with_every_setting_and_the_code(monkeypatch):
    """t_end, dt, theta, a mesh parameter, a model and the code version each change the key;
    an equal scenario built another way has the same key."""
    sc = _tiny()
    base = validation.case_key(sc)
    assert validation.case_key(load_scenario(TINY).with_overrides(t_end_s=2e-6)) == base
    variants = [
        sc.with_overrides(t_end_s=3e-6),
        sc.with_overrides(dt_s=0.125e-6),
        _tiny(theta=0.6),
        _rod(sc, first_element_m=0.4e-3),
        sc.with_overrides(model="mvm"),
        sc.with_overrides(body_models={"b2": ModelConfig(kind="modal", modes=5)}),
    ]
    keys = [validation.case_key(v) for v in variants]
    assert base not in keys and len(set(keys)) == len(keys)
    monkeypatch.setattr(provenance, "run_code_version", lambda: "0" * 16)
    assert validation.case_key(sc) != base


def test_key_holds_the_library_versions(monkeypatch):
    """numpy, scipy, numba, scikit-fem and gmsh versions are in the key: another version of
    one is another key (a new kernel can change a history's last bits; scikit-fem assembles
    the matrices, gmsh writes the parts' meshes)."""
    sc = _tiny()
    base = validation.case_key(sc)
    libraries = {"numpy", "scipy", "numba", "scikit-fem", "gmsh"}
    assert set(validation.case_inputs(sc)["libraries"]) == libraries
    for lib in sorted(libraries):
        real = provenance.library_versions()
        monkeypatch.setattr(
            provenance, "library_versions", lambda real=real, lib=lib: real | {lib: "0.0"}
        )
        assert validation.case_key(sc) != base, lib
        monkeypatch.undo()


def test_stored_case_reused_only_under_its_key(tmp_path, monkeypatch):
    """A stored case is loaded (no run) when the key matches; a different setting in the same
    folder, a changed code version or a damaged key file make it run again."""
    calls = []
    real = run_module.run_scenario

    def counting(sc, **kw):
        calls.append(sc)
        return real(sc, **kw)

    monkeypatch.setattr(run_module, "run_scenario", counting)
    sc = _tiny()
    first = validation.run_case(tmp_path, "c", sc, progress=False)
    meta = json.loads((tmp_path / "c" / "key.json").read_text())
    assert (
        meta["key"] == validation.case_key(sc)
        and meta["inputs"]["scenario"]["time"]["t_end_s"] == 2e-6
    )
    assert re.fullmatch(r"[0-9a-f]{12}(-dirty)?|unknown", meta["commit"])
    again = validation.run_case(tmp_path, "c", sc, progress=False)
    assert len(calls) == 1 and (again.force == first.force).all()
    with pytest.warns(  # same folder
        StaleDataWarning,
        match=r"validation case c: run under another resolved scenario: recomputed",
    ):
        validation.run_case(tmp_path, "c", _tiny(theta=0.6), progress=False)
    assert len(calls) == 2
    monkeypatch.setattr(provenance, "run_code_version", lambda: "f" * 16)
    with pytest.warns(
        StaleDataWarning,
        match=r"validation case c: run under code version "
        r"[0-9a-f]{16} \(now f{16}\): recomputed",
    ):
        validation.run_case(tmp_path, "c", _tiny(theta=0.6), progress=False)
    assert len(calls) == 3
    (tmp_path / "c" / "key.json").write_text("{not json")
    with pytest.warns(
        StaleDataWarning, match=r"validation case c: key.json unreadable: recomputed"
    ):
        validation.run_case(tmp_path, "c", _tiny(theta=0.6), progress=False)
    assert len(calls) == 4
    validation.run_case(tmp_path, "c", _tiny(theta=0.6), progress=False, recompute=True)
    assert len(calls) == 5


def test_edited_or_cut_history_is_recomputed_not_checked(tmp_path, monkeypatch):
    """A stored case whose history.csv was edited (one force value) or cut short, or whose
    summary.json was edited, under a matching key, fails the check of its outputs (their
    SHA-256 and window in key.json) and is recomputed, said in one line naming the case."""
    calls = []
    real = run_module.run_scenario
    monkeypatch.setattr(
        run_module, "run_scenario", lambda sc, **kw: calls.append(sc) or real(sc, **kw)
    )
    sc = _tiny()
    first = validation.run_case(tmp_path, "c", sc, progress=False)
    hist = tmp_path / "c" / "history.csv"
    lines = hist.read_text().splitlines(keepends=True)
    t, f = lines[-1].split(",")[:2]
    lines[-1] = lines[-1].replace(f"{t},{f},", f"{t},{float(f) + 1.0!r},", 1)
    hist.write_text("".join(lines))
    with pytest.warns(
        StaleDataWarning, match="validation case c: history.csv: content differs from the SHA-256"
    ):
        again = validation.run_case(tmp_path, "c", sc, progress=False)
    assert len(calls) == 2 and (again.force == first.force).all()
    hist.write_text("".join(hist.read_text().splitlines(keepends=True)[:3]))
    with pytest.warns(
        StaleDataWarning,
        match=r"validation case c: history.csv: 2 of \d+ "
        r"samples, last at .* \(expected window 0..2 us\)",
    ):
        validation.run_case(tmp_path, "c", sc, progress=False)
    assert len(calls) == 3
    summary = tmp_path / "c" / "summary.json"
    summary.write_text(summary.read_text().replace('"n_steps": ', '"n_steps": 1'))
    with pytest.warns(StaleDataWarning, match="summary.json: content differs"):
        validation.run_case(tmp_path, "c", sc, progress=False)
    assert len(calls) == 4
    validation.run_case(tmp_path, "c", sc, progress=False)
    assert len(calls) == 4


def test_key_holds_a_mesh_file_by_name_and_content_not_its_place(tmp_path):
    """A scenario and its mesh copied to another directory (a fresh clone, another checkout)
    keep their key; the same file name with other content is another key."""
    src = Path(__file__).parents[1] / "scenarios"
    for where in ("a", "b"):
        (tmp_path / where / "meshes").mkdir(parents=True)
        (tmp_path / where / "sphere_block.toml").write_bytes(
            (src / "sphere_block.toml").read_bytes()
        )
        for name in ("block_60x60x30.msh", "sphere_r10.msh", "sphere_r10_cap.msh"):
            (tmp_path / where / "meshes" / name).write_bytes((src / "meshes" / name).read_bytes())
    key_a = validation.case_key(load_scenario(tmp_path / "a" / "sphere_block.toml"))
    assert validation.case_key(load_scenario(tmp_path / "b" / "sphere_block.toml")) == key_a
    block_b = tmp_path / "b" / "meshes" / "block_60x60x30.msh"
    block_b.write_bytes(block_b.read_bytes() + b"\n")
    assert validation.case_key(load_scenario(tmp_path / "b" / "sphere_block.toml")) != key_a
