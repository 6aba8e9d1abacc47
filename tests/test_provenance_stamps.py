"""Stored records that pages and tests read carry the provenance stamp, and reuse refuses a
mismatch (issue 51 item 4): the run key holds scikit-fem and gmsh; benchmarks/seed_plastic.py
--reuse, benchmarks/plastic_restitution.py --from-csv and benchmarks/yield_onset.py's appended
record refuse, in one line, a record made under another code, other libraries or other
scripts. No simulation runs here: the stamps of the tiny scenario and of the scripts only.
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import pytest

import flexmvm as fm
from flexmvm.runs import provenance

ROOT = Path(__file__).resolve().parents[1]
TINY = ROOT / "tests" / "data" / "tiny_impact.toml"
BENCH = ROOT / "benchmarks"


@pytest.fixture(scope="module")
def bench():
    """The benchmark scripts as modules (they import each other by name)."""
    sys.path.insert(0, str(BENCH))
    try:
        import plastic_restitution
        import seed_plastic
        import yield_onset

        yield {"seed": seed_plastic, "restitution": plastic_restitution, "onset": yield_onset}
    finally:
        sys.path.remove(str(BENCH))


def _other_code(monkeypatch):
    """The provenance module as under another package source."""
    monkeypatch.setattr(provenance, "run_code_version", lambda: "c0de" * 4)


def test_key_holds_scikit_fem_and_gmsh(monkeypatch):
    """scikit-fem assembles the matrices and gmsh writes the parts' meshes: both versions are
    in the stamp, and another version of either is another key."""
    sc = fm.load_scenario(TINY)
    s = provenance.stamp(sc)
    assert {"scikit-fem", "gmsh"} <= set(s["libraries"])
    real = provenance.library_versions()
    for lib in ("scikit-fem", "gmsh"):
        monkeypatch.setattr(provenance, "library_versions", lambda lib=lib: real | {lib: "0.0"})
        other = provenance.stamp(sc)
        assert other["key"] != s["key"], lib
        assert f"{lib} 0.0 (now {real[lib]})" in provenance.stamp_mismatch(other, s)
        monkeypatch.undo()


def _seed_record(tmp_path: Path, row_stamp) -> Path:
    rows = [{"run": "plastic", "peak_force_N": 1.0}, {"run": "mvm 7-5:37", "peak_force_N": 2.0}]
    if row_stamp is not None:
        rows[0]["provenance"] = row_stamp
    path = tmp_path / "seed_plastic.json"
    path.write_text(json.dumps({"rows": rows}))
    return path


def test_seed_plastic_reuse_refuses_another_run(bench, tmp_path, monkeypatch):
    """--reuse takes a stored run only under its stamp: the same stamp is reused; a row
    without one, or made under another code, exits with one line naming the run and what
    differs."""
    sc = fm.load_scenario(TINY)
    reused = bench["seed"].reused_rows(
        _seed_record(tmp_path, provenance.stamp(sc)), {"plastic": sc}
    )
    assert [r["run"] for r in reused] == ["plastic"]
    with pytest.raises(SystemExit, match="its plastic run was stored without a code version"):
        bench["seed"].reused_rows(_seed_record(tmp_path, None), {"plastic": sc})
    record = _seed_record(tmp_path, provenance.stamp(sc))
    with pytest.raises(SystemExit, match="another resolved scenario"):
        bench["seed"].reused_rows(record, {"plastic": sc.with_time(t_end_s=3e-6)})
    _other_code(monkeypatch)
    with pytest.raises(SystemExit, match=r"code version \w+ \(now c0dec0de") as err:
        bench["seed"].reused_rows(record, {"plastic": sc})
    assert "\n" not in str(err.value)


def _study(tmp_path: Path, meta: dict) -> Path:
    path = tmp_path / "study.csv"
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["v_over_vy", "e_pl"])
        w.writeheader()
        w.writerow({"v_over_vy": 1.0, "e_pl": 0.9})
    path.with_suffix(".json").write_text(json.dumps({"meta": meta, "rows": []}))
    return path


def test_restitution_from_csv_refuses_another_study(bench, tmp_path, monkeypatch):
    """--from-csv reads a stored study only under the stamp this code would write (this
    script, its setup and speeds, code, libraries): an unstamped one (the study stored before
    stamps) and one made under another code exit with one line."""
    mod = bench["restitution"]
    script = Path(mod.__file__)
    good = provenance.script_stamp(script, {"setup": "study", "speeds": [1.0]})
    assert provenance.script_stamp_mismatch(good, script) is None
    monkeypatch.setattr(mod, "fitted_columns", lambda row, meta: row)  # the laws: not here
    rows, meta = mod.from_csv(_study(tmp_path, {"provenance": good}))
    assert rows == [{"v_over_vy": 1, "e_pl": 0.9}] and meta["provenance"] == good
    with pytest.raises(SystemExit, match="stored without a code version"):
        mod.from_csv(_study(tmp_path, {}))
    _other_code(monkeypatch)
    with pytest.raises(SystemExit, match=r"--from-csv: .* code version \w+ \(now c0de"):
        mod.from_csv(_study(tmp_path, {"provenance": good}))


def test_yield_onset_appends_only_to_rows_of_this_code(bench, tmp_path, monkeypatch):
    """yield_onset.json is one table of one code: rows are appended only to a record whose
    every row carries this code's stamp (the stored record mixed code versions)."""
    mod = bench["onset"]
    record = tmp_path / "yield_onset.json"
    assert mod.stamped_rows(record) == []
    row = {"case": "base", "provenance": mod.row_stamp("base", None)}
    record.write_text(json.dumps([row]))
    assert mod.stamped_rows(record) == [row]
    record.write_text(json.dumps([row, {"case": "h20"}]))
    with pytest.raises(SystemExit, match=r"row 1 \(h20\) was stored without a code version"):
        mod.stamped_rows(record)
    record.write_text(json.dumps([row]))
    _other_code(monkeypatch)
    with pytest.raises(SystemExit, match=r"row 0 \(base\) was run under code version"):
        mod.stamped_rows(record)
