"""The validation report's stored cases (flexmvm.validation, issue 11): a case is reused only
when the code version and every setting of the run match, never by its folder name alone."""

from __future__ import annotations

import json
import re
from pathlib import Path

import flexmvm.scenarios.run as run_module
from flexmvm import validation
from flexmvm.scenarios import ModelConfig, load_scenario, scenario_from_dict

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
    variants = [sc.with_overrides(t_end_s=3e-6), sc.with_overrides(dt_s=0.125e-6),
                _tiny(theta=0.6), _rod(sc, first_element_m=0.4e-3), sc.with_overrides(model="mvm"),
                sc.with_overrides(body_models={"b2": ModelConfig(kind="modal", modes=5)})]
    keys = [validation.case_key(v) for v in variants]
    assert base not in keys and len(set(keys)) == len(keys)
    monkeypatch.setattr(validation, "run_code_version", lambda: "0" * 16)
    assert validation.case_key(sc) != base


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
    assert meta["key"] == validation.case_key(sc) and meta["inputs"]["scenario"]["time"]["t_end_s"] == 2e-6
    assert re.fullmatch(r"[0-9a-f]{12}(-dirty)?|unknown", meta["commit"])
    again = validation.run_case(tmp_path, "c", sc, progress=False)
    assert len(calls) == 1 and (again.force == first.force).all()
    validation.run_case(tmp_path, "c", _tiny(theta=0.6), progress=False)  # same folder
    assert len(calls) == 2
    monkeypatch.setattr(validation, "run_code_version", lambda: "f" * 16)
    validation.run_case(tmp_path, "c", _tiny(theta=0.6), progress=False)
    assert len(calls) == 3
    (tmp_path / "c" / "key.json").write_text("{not json")
    validation.run_case(tmp_path, "c", _tiny(theta=0.6), progress=False)
    assert len(calls) == 4
    validation.run_case(tmp_path, "c", _tiny(theta=0.6), progress=False, recompute=True)
    assert len(calls) == 5
