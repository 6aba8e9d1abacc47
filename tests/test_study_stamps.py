"""A study's summary JSON carries the provenance stamps of the study and of its reference
(issue 51 item 4): selection.json and materials.json, copied under docs/, are stamped on their
own (tests/test_doc_records.py's rule), and a stored study whose reference or cases were made
under another stamp is rerun, not reused.

One selection study of one case (layer 1, lap 1, 7 modes) and one material study of one
material and one case, on the tiny scenario tests/data/tiny_impact.toml (serial).
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from test_doc_records import is_stamp, stamped

from flexmvm.results.atomic import file_sha256
from flexmvm.runs.provenance import stamp
from flexmvm.scenarios import load_scenario
from flexmvm.studies.grid import reference_scenario, seed_scheme
from flexmvm.studies.materials import SEED_MATERIALS, material_scenario, run_materials_study
from flexmvm.studies.selection import run_selection_study

TINY = Path(__file__).parent / "data" / "tiny_impact.toml"
GRID = {"layers": [1], "laps": [1], "modes": [7]}


def _select(out: Path, lines: list[str] | None = None) -> dict:
    echo = (lambda s: None) if lines is None else lines.append
    return run_selection_study(TINY, "b2", out, **GRID, serial=True, progress=False, echo=echo)


@pytest.fixture(scope="module")
def study(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("select")
    _select(out)
    return out


def _study_scenario():
    """The scenario a selection study of b2 in TINY runs its cases from (seed scheme)."""
    return seed_scheme(load_scenario(TINY), "b2")


def _check_provenance(prov: dict, sc, ref_dir: Path) -> None:
    """``prov`` holds the current stamps of the study scenario ``sc`` and of its reference,
    the one stored in ``ref_dir``."""
    stored = json.loads((ref_dir / "reference.json").read_text())["provenance"]
    assert prov["study"] == stamp(sc)
    assert prov["reference"] == stored == stamp(reference_scenario(sc, "b2"))
    assert prov["reference_sha256"] == file_sha256(ref_dir / "history.csv")
    assert is_stamp(prov["study"]) and is_stamp(prov["reference"])


def test_selection_json_carries_the_study_and_reference_stamps(study, tmp_path):
    summary = json.loads((study / "selection.json").read_text())
    _check_provenance(summary["provenance"], _study_scenario(), study / "reference")
    # a copy of selection.json alone (as under docs/) is a stamped record
    copy = tmp_path / "selection.json"
    shutil.copy(study / "selection.json", copy)
    assert stamped(copy)


def test_a_study_stored_under_another_stamp_is_rerun(study, tmp_path):
    out = tmp_path / "stale"
    shutil.copytree(study, out)
    meta = out / "reference" / "reference.json"
    ref = json.loads(meta.read_text())
    ref["provenance"] |= {"code": "0" * 16, "key": "0" * 32}  # made by another code
    meta.write_text(json.dumps(ref))
    case = out / "cases" / "l1-j1-m7.json"
    record = json.loads(case.read_text())
    record["version"]["provenance"] |= {"code": "0" * 16, "key": "0" * 32}
    case.write_text(json.dumps(record))
    lines: list[str] = []
    res = _select(out, lines)
    assert res["reference_computed"] is True and res["runs_made"] == 1, res
    said = [s for s in lines if "recomputed" in s]
    assert len(said) == 2 and all(f"code version {'0' * 16}" in s for s in said), lines
    _check_provenance(res["provenance"], _study_scenario(), out / "reference")


def test_materials_json_carries_each_materials_stamps(tmp_path):
    run_materials_study(
        TINY,
        tmp_path,
        materials=["Al"],
        selections=[(1, 1)],
        modes=[7],
        serial=True,
        progress=False,
        echo=lambda s: None,
    )
    summary = json.loads((tmp_path / "materials.json").read_text())
    sc = material_scenario(_study_scenario(), "b2", "Al", SEED_MATERIALS["Al"])
    assert set(summary["provenance"]) == {"Al"}
    _check_provenance(summary["provenance"]["Al"], sc, tmp_path / "Al" / "reference")
    assert stamped(tmp_path / "materials.json") and stamped(tmp_path / "materials.csv")
