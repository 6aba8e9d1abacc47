"""A study's stored data is checked before it is reused (issue "Nothing lost", item 4;
"Numbers a user can trust", item 4): a reference history cut short, a corrupt case file and
cases stored under another code version are recomputed, each said in one line, and counted
as made, not loaded. tests/data/tiny_impact.toml (30 us window), one selection x two mode
counts, serial."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from flexmvm.metrics.ncc import Target
from flexmvm.runs import provenance
from flexmvm.studies.selection import run_selection_study

TINY = Path(__file__).parent / "data" / "tiny_impact.toml"
GRID = {"layers": [1], "laps": [1], "modes": [7, 13]}


def _study(out: Path, lines: list[str]) -> dict:
    return run_selection_study(
        TINY, "b2", out, **GRID, target=Target(0.99), serial=True, progress=False, echo=lines.append
    )


def _ncc(out: Path) -> list[str]:
    return [r.split(",")[5] for r in (out / "ncc.csv").read_text().splitlines()[1:]]


@pytest.fixture(scope="module")
def first(tmp_path_factory) -> tuple[Path, dict, list[str]]:
    out = tmp_path_factory.mktemp("study")
    res = _study(out, [])
    return out, res, _ncc(out)


def test_cut_reference_is_recomputed_and_said(first, tmp_path):
    """The reference history cut to its first 7 samples (before: loaded, and the whole table
    scored on 6 us of the 30 us window, exit 0) fails its check (samples and window in
    reference.json) and is recomputed, in one line; the table is the first run's."""
    import shutil

    src, _, ncc = first
    shutil.copytree(src, tmp_path, dirs_exist_ok=True)
    hist = tmp_path / "reference" / "history.csv"
    rows = hist.read_text().splitlines(keepends=True)
    hist.write_text("".join(rows[:8]))
    lines: list[str] = []
    res = _study(tmp_path, lines)
    note = [s for s in lines if s.startswith("reference history.csv")]
    assert len(note) == 1 and re.fullmatch(
        rf"reference history.csv: 7 of {len(rows) - 1} samples, last at [0-9.]+ us "
        r"\(expected window 0..30 us\): recomputed",
        note[0],
    ), lines
    assert res["reference_computed"] is True
    assert _ncc(tmp_path) == ncc


def test_corrupt_case_is_counted_as_made(first, tmp_path):
    """A case file cut short is recomputed and counted made, not loaded (before: "0 made, 2
    loaded"), said in one line naming the file."""
    import shutil

    src, _, ncc = first
    shutil.copytree(src, tmp_path, dirs_exist_ok=True)
    case = tmp_path / "cases" / "l1-j1-m13.json"
    case.write_text(case.read_text()[:50])
    lines: list[str] = []
    res = _study(tmp_path, lines)
    assert (res["runs_made"], res["runs_loaded"]) == (1, 1)
    assert f"{case}: unreadable or incomplete case file: recomputed" in lines
    assert _ncc(tmp_path) == ncc


def test_cases_of_another_code_version_are_recomputed_and_named(first, tmp_path, monkeypatch):
    """After a (simulated) code change the stored reference and cases, keyed by the package
    source as the validation cases are, are recomputed, never mixed with new rows; each
    recomputation names the file and the code versions; an edited result is recomputed too."""
    import shutil

    src, _, ncc = first
    shutil.copytree(src, tmp_path, dirs_exist_ok=True)
    old = provenance.run_code_version()
    monkeypatch.setattr(provenance, "run_code_version", lambda: "c0de" * 4)
    lines: list[str] = []
    res = _study(tmp_path, lines)
    assert (res["runs_made"], res["runs_loaded"], res["reference_computed"]) == (2, 0, True)
    why = f"run under code version {old} (now {'c0de' * 4})"
    assert f"reference history.csv: {why}: recomputed" in lines
    case = tmp_path / "cases" / "l1-j1-m7.json"
    assert any(s.startswith(str(case)) and why in s for s in lines), lines
    assert _ncc(tmp_path) == ncc
    record = json.loads(case.read_text())
    record["result"]["ncc_force"] = 0.5
    case.write_text(json.dumps(record))
    lines.clear()
    res = _study(tmp_path, lines)
    assert (res["runs_made"], res["runs_loaded"], res["reference_computed"]) == (1, 1, False)
    assert any(s.startswith(str(case)) and "SHA-256" in s for s in lines), lines
    assert _ncc(tmp_path) == ncc


def test_material_reference_cut_short_is_recomputed(tmp_path):
    """The material study: a material's reference history cut short, with its reference case
    stored intact, is announced and recomputed, and the material's run is compared with the
    whole reference again (the same row as before the cut)."""
    import csv

    from flexmvm.errors import StaleDataWarning
    from flexmvm.studies.materials import run_materials_study

    def study() -> list[dict]:
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
        with open(tmp_path / "materials.csv", newline="") as fh:
            return [{k: v for k, v in r.items() if k != "wall_time_s"} for r in csv.DictReader(fh)]

    rows = study()
    hist = tmp_path / "Al" / "reference" / "history.csv"
    whole = hist.read_text()
    hist.write_text("".join(whole.splitlines(keepends=True)[:8]))
    with pytest.warns(
        StaleDataWarning,
        match=r"Al/reference history.csv: 7 of \d+ samples, "
        r"last at .* \(expected window 0..30 us\): "
        "recomputed",
    ):
        again = study()
    assert again == rows and hist.read_text() == whole
