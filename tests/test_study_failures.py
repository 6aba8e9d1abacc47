"""Failed study cases are listed, not dropped (issue 11, item 12): in the console output and
the study's JSON; means over cases say how many cases they cover; a study whose every run
failed ends with an error after writing what it has."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
from _study_cases import chain_eigenvalues

from flexmvm.errors import SolverError
from flexmvm.studies import materials as materials_mod
from flexmvm.studies import selection as selection_mod
from flexmvm.studies.runner import Case, case_path, error_path, run_cases

TINY = Path(__file__).parent / "data" / "tiny_impact.toml"
T_END = 3e-6


def test_run_cases_with_failures_dict_returns_the_others(tmp_path):
    good = Case("good", {"n": 4, "seed": 1})
    bad = Case("bad", {"n": 3, "seed": 0, "fail": True})
    failures: dict[str, str] = {}
    res = run_cases(
        [good, bad], chain_eigenvalues, tmp_path, serial=True, progress=False, failures=failures
    )
    assert list(res) == ["good"]
    assert failures == {"bad": "ValueError: deliberate failure in case bad"}
    assert error_path(tmp_path, "bad").exists() and not case_path(tmp_path, "bad").exists()


def _failing_for(real, keys):
    def fn(case, **kwargs):
        if case.key in keys:
            raise RuntimeError(f"deliberate failure of {case.key}")
        return real(case, **kwargs)

    return fn


def test_selection_study_lists_a_failed_case(tmp_path, monkeypatch):
    monkeypatch.setattr(
        selection_mod,
        "run_selection_case",
        _failing_for(selection_mod.run_selection_case, {"l1-j2-m7"}),
    )
    lines: list[str] = []
    res = selection_mod.run_selection_study(
        TINY,
        "b2",
        tmp_path,
        layers=[1],
        laps=[1, 2],
        modes=[7],
        serial=True,
        progress=False,
        t_end_s=T_END,
        echo=lines.append,
    )
    assert res["failures"] == [
        {"case": "l1-j2-m7", "reason": "RuntimeError: deliberate failure of l1-j2-m7"}
    ]
    assert res["failed_cases"] == ["l1-j2-m7"] and res["runs"] == 2
    stored = json.loads((tmp_path / "selection.json").read_text())
    assert stored["failures"] == res["failures"]
    text = "\n".join(lines)
    assert "1 of 2 runs failed" in text and "deliberate failure of l1-j2-m7" in text
    with open(tmp_path / "ncc.csv", newline="") as fh:
        rows = {(r["laps"]): r for r in csv.DictReader(fh)}
    assert rows["2"]["ncc_force"] == "" and rows["2"]["dof"] != "" and rows["1"]["ncc_force"]
    assert not case_path(tmp_path, "l1-j2-m7").exists()  # a rerun tries it again


def test_selection_study_every_run_failed_is_an_error(tmp_path, monkeypatch):
    monkeypatch.setattr(
        selection_mod,
        "run_selection_case",
        _failing_for(selection_mod.run_selection_case, {"l1-j1-m7"}),
    )
    with pytest.raises(SolverError, match="every run failed"):
        selection_mod.run_selection_study(
            TINY,
            "b2",
            tmp_path,
            layers=[1],
            laps=[1],
            modes=[7],
            serial=True,
            progress=False,
            t_end_s=T_END,
            echo=lambda s: None,
        )
    assert (
        json.loads((tmp_path / "selection.json").read_text())["failures"][0]["case"] == "l1-j1-m7"
    )


def test_materials_study_lists_a_failed_reference_and_counts_the_means(tmp_path, monkeypatch):
    monkeypatch.setattr(
        materials_mod,
        "run_reference_case",
        _failing_for(materials_mod.run_reference_case, {"ref-Al"}),
    )
    lines: list[str] = []
    res = materials_mod.run_materials_study(
        TINY,
        tmp_path,
        materials=["W", "Al"],
        selections=[(1, 1)],
        modes=[7],
        serial=True,
        progress=False,
        t_end_s=T_END,
        echo=lines.append,
    )
    w, al = res["materials"]["W"], res["materials"]["Al"]
    assert w["n_cases"] == 1 and w["mean_ncc_force"] is not None
    assert al["n_cases"] == 0 and al["mean_ncc_force"] is None
    assert "deliberate failure of ref-Al" in al["reference_failed"]
    assert [f["case"] for f in res["failures"]] == ["ref-Al"]
    assert res["seed_ordering_holds"] is False
    assert json.loads((tmp_path / "materials.json").read_text())["failures"] == res["failures"]
    text = "\n".join(lines)
    assert "ref-Al" in text and "W " in text and "over 1 of 1 runs" in text
