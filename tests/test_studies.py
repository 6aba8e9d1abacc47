"""Selection and material studies on the tiny scenario tests/data/tiny_impact.toml.

One brute-force sweep (layers 1..2 x laps 1..2 x modes {7, 13}, serial) is shared by the tests;
the others copy its reference (and cases, where a test is about loading them) to avoid
recomputing what does not matter for the test.

Its target is force NCC >= 0.99999 (TARGET), where the answer is not the smallest candidate:
measured over the contact window (2026-11-27), the four 7-mode models score 1 - r = 1.8e-5 to
2.2e-5 and fail, the four 13-mode ones 1.4e-7 to 7.2e-7 and pass, so the smallest passing
model is 1-1 + 13 (16 DOF) while 1-1 + 7 (10 DOF) and 2-1 + 7 (13 DOF) are smaller. At 0.99
every model passes and any selection rule that returns the smallest candidate would pass.
"""

from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from flexmvm.cli.select_cmd import parse_range
from flexmvm.errors import InputError
from flexmvm.metrics.ncc import Target
from flexmvm.scenarios import load_scenario, scenario_from_dict
from flexmvm.studies import selection
from flexmvm.studies.estimate import estimate_selection, median_ncc
from flexmvm.studies.grid import selection_cases
from flexmvm.studies.selection import run_selection_study

TINY = Path(__file__).parent / "data" / "tiny_impact.toml"
GRID = {"layers": [1, 2], "laps": [1, 2], "modes": [7, 13]}
TARGET = Target(0.99999)


def _table(out: Path, drop=("wall_time_s",)) -> list[dict]:
    with open(out / "ncc.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    return [{k: v for k, v in r.items() if k not in drop} for r in rows]


def _same_table(a: list[dict], b: list[dict], rtol: float = 1e-9) -> None:
    assert [list(r) for r in a] == [list(r) for r in b]
    assert len(a) == len(b) == 8
    for ra, rb in zip(a, b):
        for k in ra:
            if k in ("layers", "laps", "nodes", "modes", "dof") or "" in (ra[k], rb[k]):
                assert ra[k] == rb[k], k  # counts, and fields empty for the body (plastic)
            else:
                assert float(ra[k]) == pytest.approx(float(rb[k]), rel=rtol, abs=1e-12), k


def _copy_reference(src: Path, dst: Path, cases: bool = False) -> None:
    shutil.copytree(src / "reference", dst / "reference")
    if cases:
        shutil.copytree(src / "cases", dst / "cases")


@pytest.fixture(scope="module")
def brute(tmp_path_factory) -> tuple[Path, dict]:
    out = tmp_path_factory.mktemp("brute")
    res = run_selection_study(
        TINY, "b2", out, **GRID, target=TARGET, serial=True, progress=False, echo=lambda s: None
    )
    return out, res


def test_brute_force_writes_table_json_and_figures(brute):
    out, res = brute
    header = (out / "ncc.csv").read_text().splitlines()[0]
    assert header == (
        "layers,laps,nodes,modes,dof,ncc_force,ncc_b2_impact_end,ncc_b2_free_end,"
        "peak_err,impulse_err,duration_err,guard_outside_fraction,energy_gain_rel_max,"
        "plastic_cells_outside,"
        "wall_time_s"
    )
    rows = _table(out, drop=())
    # every run records its validity guard: the share of the contact impulse on surface
    # nodes the basis holds stiff, a fraction in [0, 1]
    assert all(0.0 <= float(r["guard_outside_fraction"]) <= 1.0 for r in rows)
    assert [(int(r["layers"]), int(r["laps"]), int(r["modes"])) for r in rows] == [
        (i, j, m) for i in (1, 2) for j in (1, 2) for m in (7, 13)
    ]
    for r in rows:  # dof = 3 x nodes + modes (elastic coordinates, seed count)
        assert int(r["dof"]) == 3 * int(r["nodes"]) + int(r["modes"])
        # measured 1 - r <= 2.2e-5 (module doc): a broken reduction or coupling reads far below
        assert 0.9999 < float(r["ncc_force"]) <= 1.0
    assert {r["nodes"] for r in rows if r["layers"] == "1" and r["laps"] == "1"} == {"1"}
    assert res["runs"] == res["runs_made"] == 8 and res["runs_loaded"] == 0
    assert res["reference_computed"] is True
    # the smallest model reaching TARGET (module doc): not the smallest candidate
    assert (res["layers"], res["laps"], res["modes"], res["dof"]) == (1, 1, 13, 16)
    assert min(int(r["dof"]) for r in rows) == 10
    assert all(float(r["ncc_force"]) < TARGET.ncc_min for r in rows if int(r["dof"]) < 16)
    assert res["dof_total"] == res["dof"] + 6
    for fig in ("fig7_ncc_map.png", "fig8_ncc_modes.png"):
        assert (out / fig).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_dask_local_cluster_gives_the_serial_table(brute, tmp_path):
    out, _ = brute
    _copy_reference(out, tmp_path)
    res = run_selection_study(
        TINY,
        "b2",
        tmp_path,
        **GRID,
        target=Target(0.99),
        n_workers=2,
        progress=False,
        echo=lambda s: None,
    )
    assert res["runs_made"] == 8 and res["reference_computed"] is False
    _same_table(_table(out), _table(tmp_path))


def test_interrupted_sweep_resumes_only_missing_cases(brute, tmp_path):
    out, _ = brute
    _copy_reference(out, tmp_path, cases=True)
    cases_dir = tmp_path / "cases"
    missing = ["l1-j2-m13", "l2-j1-m7", "l2-j2-m13"]
    for key in missing:
        (cases_dir / f"{key}.json").unlink()
    kept = {p.name: p.stat().st_mtime_ns for p in cases_dir.glob("*.json")}
    assert len(kept) == 5
    res = run_selection_study(
        TINY,
        "b2",
        tmp_path,
        **GRID,
        target=Target(0.99),
        serial=True,
        progress=False,
        echo=lambda s: None,
    )
    assert (res["runs_made"], res["runs_loaded"], res["runs"]) == (3, 5, 8)
    assert {
        p.name: p.stat().st_mtime_ns for p in cases_dir.glob("*.json") if p.name in kept
    } == kept
    assert sorted(p.stem for p in cases_dir.glob("*.json") if p.name not in kept) == sorted(missing)
    _same_table(_table(out), _table(tmp_path))


def test_search_finds_the_brute_force_answer_with_fewer_runs(brute, tmp_path, monkeypatch):
    out, _ = brute
    level = median_ncc([{"ncc_force": float(r["ncc_force"])} for r in _table(out)])
    target = Target(level)
    passing = [r for r in _table(out) if float(r["ncc_force"]) >= level]
    assert 0 < len(passing) < 8  # the target splits the grid
    # brute force at this target from the stored cases (nothing recomputed)
    bdir = tmp_path / "brute"
    _copy_reference(out, bdir, cases=True)
    b = run_selection_study(
        TINY, "b2", bdir, **GRID, target=target, serial=True, progress=False, echo=lambda s: None
    )
    assert b["runs_made"] == 0 and b["runs"] == 8 and b["passed"]
    sdir = tmp_path / "search"
    _copy_reference(out, sdir)
    opened = []
    real = selection.smallest_passing

    def spy(*args, max_open=None, **kw):
        opened.append(max_open)
        return real(*args, max_open=max_open, **kw)

    monkeypatch.setattr(selection, "smallest_passing", spy)
    s = run_selection_study(
        TINY,
        "b2",
        sdir,
        **GRID,
        target=target,
        search=True,
        serial=True,
        progress=False,
        echo=lambda s: None,
    )
    # in-process: one case at a time, so SEARCH_OPEN_PER_SLOT families open
    assert opened == [selection.SEARCH_OPEN_PER_SLOT]
    assert s["passed"] and s["search"] is True
    for key in ("layers", "laps", "modes", "dof", "ncc_force"):
        assert s[key] == b[key], key
    assert s["runs"] == s["runs_made"] <= b["runs"]
    assert len(_table(sdir)) == s["runs"]


def test_a_priori_estimate_against_brute_force(brute):
    out, _ = brute
    sc = load_scenario(TINY)
    est = estimate_selection(sc, "b2", Target(0.99), modes=GRID["modes"])
    assert est["theory_law"] == "hertz"
    assert 0 < est["theory_contact_radius_m"] < 0.5e-3
    assert est["layers"] == 1 and est["modes"] in GRID["modes"]
    assert est["dof"] == 3 * est["nodes"] + est["modes"]
    rows = {(int(r["layers"]), int(r["laps"]), int(r["modes"])): r for r in _table(out)}
    level = median_ncc([{"ncc_force": float(r["ncc_force"])} for r in rows.values()])
    est_ncc = float(rows[(est["layers"], est["laps"], est["modes"])]["ncc_force"])
    # the estimate is sufficient at the median-NCC target and no larger than the brute-force
    # winner at that target (tiny case: both are 1-1 with 13 modes, 16 DOF)
    assert est_ncc >= level
    winner = min((int(r["dof"]), k) for k, r in rows.items() if float(r["ncc_force"]) >= level)
    assert est["dof"] <= winner[0]


def test_selection_cases_keys_and_limits():
    sc = load_scenario(TINY)
    cases = selection_cases(sc, "b2", [1, 2], [1], [7, 13])
    assert [c.key for c in cases] == ["l1-j1-m7", "l1-j1-m13", "l2-j1-m7", "l2-j1-m13"]
    assert cases[0].params["scenario"]["name"] == "tiny_impact"
    with pytest.raises(InputError, match="maximum 5 laps"):
        selection_cases(sc, "b2", [1], [6], [7])
    with pytest.raises(InputError, match="no body 'b7'"):
        selection_cases(sc, "b7", [1], [1], [7])
    # a massless retained node adds static columns: a case's DOF would not be 3 x nodes + modes
    data = sc.model_dump(mode="json")
    data["contacts"][0].update(law="position", redistribute_mass=True)
    with pytest.raises(InputError, match=r"contacts\[0\] redistributes the mass of 'b2'"):
        selection_cases(scenario_from_dict(data), "b2", [1], [1], [7])


def test_parse_range():
    assert parse_range("1..4") == [1, 2, 3, 4]
    assert parse_range("7:43:6") == [7, 13, 19, 25, 31, 37, 43]
    assert parse_range("7:13:6") == [7, 13]
    assert parse_range("3") == [3]
    for bad in ("4..1", "1..x", "0..2", "7:43:0", "a", "1-4", ""):
        with pytest.raises(InputError):
            parse_range(bad)


@pytest.mark.parametrize(
    "args, message",
    [
        (["--layers", "1..x"], "--layers '1..x'"),
        (["--laps", "1..6"], "maximum 5 laps"),
        (["--body", "b9"], "no body 'b9'"),
    ],
)
def test_cli_one_line_errors(tmp_path, args, message):
    argv = ["select", str(TINY), "--out", str(tmp_path / "out")]
    argv += args if "--body" in args else ["--body", "b2", *args]
    p = subprocess.run(
        [sys.executable, "-m", "flexmvm.cli.main", *argv],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("flexmvm: error: ") and message in lines[0]
    assert not (tmp_path / "out").exists()


def test_materials_study_two_materials(tmp_path):
    from flexmvm.runs.guard import ENERGY_GAIN_WARN, WARN_FRACTION
    from flexmvm.studies.materials import run_materials_study

    res = run_materials_study(
        TINY,
        tmp_path,
        materials=["W", "Al"],
        selections=[(1, 1)],
        modes=[7],
        serial=True,
        progress=False,
        echo=lambda s: None,
    )
    with open(tmp_path / "materials.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [(r["material"], r["selection"], r["modes"]) for r in rows] == [
        ("W", "1-1", "7"),
        ("Al", "1-1", "7"),
    ]
    assert float(rows[0]["E_pa"]) == 344.70e9 and float(rows[1]["rho_kg_m3"]) == 2700.0
    w, al = (res["materials"][m]["mean_ncc_force"] for m in ("W", "Al"))
    assert w == pytest.approx(float(rows[0]["ncc_force"]))
    # the seed's ordering, as physics: at equal selection the reduction error is in b2's
    # contact compliance, whose share of the Hertz compliance is 0.23 for W, 0.58 for Al
    # (docs/studies.md): measured 1 - r = 6.4e-6 (W) against 1.8e-5 (Al), ratio 0.35 (the
    # shares' ratio 0.40); required below 0.6
    assert 1.0 - w < 0.6 * (1.0 - al)
    assert res["seed_ordering_holds"] is True
    # the validity verdict per run, and the means over the models valid for every material
    outside = {b["case"] for b in res["guard_outside_validity"]}
    bad = [
        float(r["guard_outside_fraction"]) > WARN_FRACTION
        or float(r["energy_gain_rel_max"]) > ENERGY_GAIN_WARN
        for r in rows
    ]
    for r, m, b in zip(rows, ("W", "Al"), bad):
        assert (f"{m}-l1-j1-m7" in outside) is b
        valid = res["materials"][m]["mean_ncc_force_valid"]
        assert valid == (None if any(bad) else pytest.approx(float(r["ncc_force"])))
    assert res["valid_models"] == ([] if any(bad) else ["1-1 + 7"])
    assert (tmp_path / "fig9_materials.png").is_file()
    assert (tmp_path / "W" / "reference" / "history.csv").is_file()
    # the 1D wave-Hertz contact radius and duration are reported beside each material, and
    # the radius of the outermost retained node of each selection (1-1: the axis node)
    for m in ("W", "Al"):
        assert res["materials"][m]["theory_contact_radius_m"] > 0
        assert res["materials"][m]["theory_contact_duration_s"] > 0
    assert res["selection_radius_m"] == {"1-1": 0.0}
    # the default kind is Craig-Bampton, and its cases keep the keys and params stored before
    # the kind existed (no "kind" param), so existing study directories resume
    assert res["kind"] == "mvm" and {r["kind"] for r in rows} == {"mvm"}
    stored = json.loads((tmp_path / "cases" / "W-l1-j1-m7.json").read_text())
    assert "kind" not in stored["params"]


def test_materials_study_of_the_seed_eq4_kind(tmp_path, monkeypatch):
    """kind = mvm-seed: every run builds the seed's eq. (4) basis (SEED_BLOCK) for the
    material's b2, never Craig-Bampton; the kind is in the cases, materials.csv/json and the
    library result; a rerun of the directory with another kind is refused (stored params
    differ) rather than mixing kinds."""
    import flexmvm as fm
    from flexmvm.assembly.build_cache import SetupCache
    from flexmvm.reduction.basis import BasisKind

    built = []

    def recording(setup, *args):
        built.append((args[1].name, args[2]))
        return basis(setup, *args)

    basis = SetupCache.basis
    monkeypatch.setattr(SetupCache, "basis", recording)
    study = fm.material_study(
        TINY,
        materials=["Al"],
        selections="1-1",
        modes=[7],
        serial=True,
        kind="mvm-seed",
        out_dir=tmp_path,
    )
    assert ("Al", BasisKind.SEED_BLOCK) in built
    assert all(k is not BasisKind.CRAIG_BAMPTON for _, k in built)
    assert study.summary["kind"] == "mvm-seed" and [r["kind"] for r in study.rows] == ["mvm-seed"]
    assert 0.0 < study.rows[0]["ncc_force"] <= 1.0
    stored = json.loads((tmp_path / "cases" / "Al-l1-j1-m7.json").read_text())
    assert stored["params"]["kind"] == "mvm-seed"
    with pytest.raises(InputError, match="stored params"):
        fm.material_study(
            TINY, materials=["Al"], selections="1-1", modes=[7], serial=True, out_dir=tmp_path
        )
    with pytest.raises(InputError, match="expected one of mvm, mvm-seed, mvm-seed-fixed"):
        fm.material_study(
            TINY, materials=["Al"], serial=True, kind="modal", out_dir=tmp_path / "modal"
        )
    assert not (tmp_path / "modal").exists()


def test_materials_cli_bad_kind_is_one_line(tmp_path):
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "flexmvm.cli.main",
            "study",
            "materials",
            str(TINY),
            "--kind",
            "modal",
            "--out",
            str(tmp_path / "out"),
        ],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("flexmvm: error: ") and "--kind" in lines[0]
    assert "mvm-seed-fixed" in lines[0] and not (tmp_path / "out").exists()


@pytest.mark.skipif(
    not os.environ.get("FLEXMVM_SLOW"),
    reason="4-material study: not needed in tests (set FLEXMVM_SLOW=1)",
)
def test_materials_study_all_four(tmp_path):
    from flexmvm.studies.materials import run_materials_study

    res = run_materials_study(
        TINY,
        tmp_path,
        selections=[(1, 1), (2, 2)],
        modes=[7, 13],
        n_workers=2,
        progress=False,
        echo=lambda s: None,
    )
    assert set(res["materials"]) == {"W", "Cu", "Al", "PA6"}
    assert isinstance(res["seed_ordering_holds"], bool)


# ----------------------------------------------------------------------------------------------
# study overrides (no time integration)
def test_parse_model_and_study_scenario():
    from flexmvm.scenarios import ModelKind
    from flexmvm.studies.grid import parse_model, study_scenario

    assert parse_model("scenario") is None
    assert parse_model("full").kind is ModelKind.FULL
    m = parse_model("mvm:3-5:40")
    assert (m.kind, m.selection_ij, m.modes) == (ModelKind.MVM, (3, 5), 40)
    for bad in ("mvm:3-5", "mvm:x-5:4", "rigid", "mvm:3-5:-1", ""):
        with pytest.raises(InputError):
            parse_model(bad)
    sc = load_scenario(TINY)
    out = study_scenario(sc, "b2", t_end_s=2e-5, dt_s=0.5e-6, other="mvm:1-1:7")
    b1, b2 = out.body("b1").model, out.body("b2").model
    assert (b1.kind, b1.selection_ij, b1.modes) == (ModelKind.MVM, (1, 1), 7)
    assert b2 == sc.body("b2").model  # the study body is untouched
    assert (out.time.t_end_s, out.time.dt_s) == (2e-5, 0.5e-6)
    assert study_scenario(sc, "b2") is sc
    with pytest.raises(InputError):
        study_scenario(sc, "nobody")


def test_mode_floor_cuts_the_larger_craig_bampton_basis():
    """A 7-mode basis cut from the 13-mode one spans the same space as a 7-mode solve: the
    same fixed-interface frequencies (eigsh tolerance: 1e-8 relative) and, column by column,
    the same constraint modes (exact: same factor and right-hand sides)."""
    import numpy as np

    from flexmvm.assembly.build_cache import default_setup
    from flexmvm.reduction.basis import BasisKind

    cfg = load_scenario(TINY).body("b2")
    spec, mat = cfg.rod.spec(), cfg.material_obj()
    from flexmvm.mesh.rod import rod_mesh

    sel = tuple(int(n) for n in rod_mesh(spec).selection(1, 1))
    fresh = default_setup().basis(spec, mat, BasisKind.CRAIG_BAMPTON, sel, 7, "end_b")
    cut = (
        default_setup()
        .with_mode_floor(13)
        .basis(spec, mat, BasisKind.CRAIG_BAMPTON, sel, 7, "end_b")
    )
    assert cut.n_modes == 7 and cut.psi.shape == fresh.psi.shape
    np.testing.assert_allclose(cut.mode_freqs_hz, fresh.mode_freqs_hz, rtol=1e-8)
    nb = 3 * len(sel)
    np.testing.assert_allclose(cut.psi[:, :nb], fresh.psi[:, :nb], rtol=0, atol=1e-12)


def test_selection_study_of_the_seed_eq4_kind(tmp_path):
    """kind = mvm-seed sweeps the seed's eq. (4) models: the cases carry the kind (the
    Craig-Bampton cases do not, so studies stored before keep their keys), each run is that
    model (its DOF count is 3 x nodes + modes like Craig-Bampton's), and every NCC is a real
    comparison (0 < NCC <= 1). A kind without a node selection is refused."""
    import flexmvm as fm
    from flexmvm.studies.grid import selection_cases

    sc = load_scenario(TINY)
    assert all("kind" not in c.params for c in selection_cases(sc, "b2", [1], [1], [7]))
    assert {
        c.params["kind"] for c in selection_cases(sc, "b2", [1], [1], [7], kind="mvm-seed")
    } == {"mvm-seed"}
    study = fm.select(
        sc, "b2", layers=[1], laps=[1, 2], modes=[7], serial=True, kind="mvm-seed", out_dir=tmp_path
    )
    assert study.summary["kind"] == "mvm-seed" and len(study.rows) == 2
    for r in study.rows:
        assert 0.0 < r["ncc_force"] <= 1.0 and r["dof"] == 3 * r["nodes"] + r["modes"]
    stored = json.loads(next((tmp_path / "cases").glob("*.json")).read_text())
    assert stored["params"]["kind"] == "mvm-seed"
    with pytest.raises(InputError, match="expected one of mvm, mvm-seed, mvm-seed-fixed"):
        fm.select(sc, "b2", layers=[1], laps=[1], modes=[7], serial=True, kind="modal")


def test_score_refuses_a_run_outside_its_models_validity():
    """A run whose validity guard puts more than WARN_FRACTION of the contact impulse on nodes
    the basis holds stiff, or whose energy rose by more than ENERGY_GAIN_WARN, scores as
    failed whatever its NCC (a study must not pick it); at or below the thresholds, and
    without the records (unguarded, or rows stored before the checks existed), the NCC
    decides."""
    from flexmvm.metrics.ncc import Target
    from flexmvm.runs.guard import ENERGY_GAIN_WARN, WARN_FRACTION
    from flexmvm.studies.selection import FAIL_SCORE, score

    target = Target.parse("ncc>=0.99")
    row = {"ncc_force": 0.995, "peak_err": 0.01, "impulse_err": 0.0, "duration_err": 0.0}
    assert score(row, target) == 0.995
    assert score(row | {"guard_outside_fraction": None}, target) == 0.995
    assert score(row | {"guard_outside_fraction": WARN_FRACTION}, target) == 0.995
    assert score(row | {"guard_outside_fraction": 2 * WARN_FRACTION}, target) == FAIL_SCORE
    assert score(row | {"guard_outside_fraction": 1.0}, target) == FAIL_SCORE
    # an energy rise above ENERGY_GAIN_WARN (chatter) fails it too
    assert score(row | {"energy_gain_rel_max": ENERGY_GAIN_WARN}, target) == 0.995
    assert score(row | {"energy_gain_rel_max": 0.03}, target) == FAIL_SCORE
