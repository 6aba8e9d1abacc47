"""Failure paths of the command line (issue 11, items 10-12): every failure is one stderr line
and a non-zero exit status, never a traceback (unless --debug); a failed run leaves its output
directory as it was; comparisons that cannot be made are listed, not dropped."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest
import scipy.sparse as sp

from flexmvm.cli import main as cli_main
from flexmvm.errors import InputError, MeshError, SolverError

ROOT = Path(__file__).resolve().parents[1]
SEED = ROOT / "scenarios" / "rod_impact.toml"
TINY = Path(__file__).parent / "data" / "tiny_impact.toml"
RUN_FAST = ["--t-end", "3e-6", "--no-fields", "--no-progress", "--jobs", "1"]


def _flexmvm(*args, cwd=None, env=None):
    return subprocess.run(
        [sys.executable, "-m", "flexmvm.cli.main", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=600,
        check=False,
        env=None if env is None else {**os.environ, **env},
    )


def _one_line(stderr: str, status: int, returncode: int, *words) -> str:
    assert returncode == status, stderr
    assert "Traceback" not in stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert lines[0].startswith("flexmvm: error:"), lines[0]
    for w in words:
        assert w in lines[0], lines[0]
    return lines[0]


def _in_process(argv, capsys) -> tuple[int, str, str]:
    """main(argv) in this process (monkeypatches apply); (exit status, stdout, stderr)."""
    code = 0
    try:
        cli_main.main([str(a) for a in argv])
    except SystemExit as exc:
        code = exc.code
    out = capsys.readouterr()
    return code, out.out, out.err


def _tree(path: Path) -> dict[str, bytes]:
    """Every file under path (relative name -> content)."""
    return {
        str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()
    }


# ----------------------------------------------------------------------------------------------
# item 10: bad input -> one line, exit status, nothing written
def test_mesh_rod_write_into_a_missing_directory(tmp_path):
    p = _flexmvm(
        "mesh",
        "rod",
        "--length",
        "0.2",
        "--modes",
        "0",
        "--write",
        "missing_dir/rod.vtu",
        cwd=tmp_path,
    )
    _one_line(p.stderr, 2, p.returncode, "--write", "missing_dir")
    assert list(tmp_path.iterdir()) == []


STUDY_FAST = ["--serial", "--no-progress", "--t-end", "3e-6", "--modes", "7"]


@pytest.mark.parametrize("command", [["run"], ["theory"], ["select"], ["study", "materials"]])
def test_out_dir_under_a_file_cannot_be_created(tmp_path, command):
    (tmp_path / "afile").write_text("user data\n")
    extra = {
        "run": RUN_FAST,
        "theory": [],
        "select": ["--body", "b2", *STUDY_FAST],
        "study": STUDY_FAST,
    }[command[0]]
    p = _flexmvm(*command, TINY, "--out", "afile/sub", *extra, cwd=tmp_path)
    _one_line(p.stderr, 2, p.returncode, "--out", "afile/sub", "is a file")
    assert [x.name for x in tmp_path.iterdir()] == ["afile"]
    assert (tmp_path / "afile").read_text() == "user data\n"


def test_out_dir_holding_other_files_is_refused(tmp_path):
    """An existing directory is replaced only if it is an earlier output of the command."""
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep me")
    p = _flexmvm("theory", TINY, "--out", out)
    _one_line(p.stderr, 2, p.returncode, "--out", "not written by flexmvm theory")
    assert _tree(out) == {"notes.txt": b"keep me"}


def _bad_connectivity_scenario(tmp_path: Path, duplicate: bool = False) -> Path:
    """tiny_impact.toml with b2 read from a VTU whose first cell names a node past the end
    (``duplicate``: whose cell 3 is written twice instead, its node sets kept: the file is
    otherwise fine)."""
    from flexmvm.mesh.io import write_mesh
    from flexmvm.mesh.rod import RodSpec, rod_mesh

    rm = rod_mesh(
        RodSpec(radius_m=0.005, length_m=0.05, n_rings=1, first_element_m=0.005, max_element_m=0.02)
    )
    write_mesh(tmp_path / "good.vtu", rm.mesh)
    m = meshio.read(tmp_path / "good.vtu")
    conn = m.cells[0].data.copy()
    if duplicate:
        conn = np.vstack([conn, conn[3:4]])
    else:
        conn[0, 0] = len(m.points) + 5
    meshio.write(
        tmp_path / "bad.vtu",
        meshio.Mesh(
            m.points, [(m.cells[0].type, conn)], point_data=m.point_data if duplicate else {}
        ),
    )
    text = TINY.read_text()
    i = text.index('name = "b2"')
    b2 = text[i:]
    b2 = b2.replace(b2[b2.index("[bodies.rod]") : b2.index("[bodies.model]")], "")
    b2 = b2.replace('material = "aluminium"', 'material = "aluminium"\nmesh_file = "bad.vtu"')
    b2 = b2.replace(
        'kind = "mvm"\nselection = "1-1"\nmodes = 13\nreference = "end_b"', 'kind = "rigid"'
    )
    path = tmp_path / "bad.toml"
    path.write_text(text[:i] + b2)
    return path


def test_out_of_range_mesh_connectivity(tmp_path):
    scenario = _bad_connectivity_scenario(tmp_path)
    before = sorted(x.name for x in tmp_path.iterdir())
    p = _flexmvm("run", scenario, "--out", tmp_path / "out", *RUN_FAST)
    line = _one_line(p.stderr, 2, p.returncode, "bad.vtu", "refer to node")
    assert str(len(meshio.read(tmp_path / "good.vtu").points) + 5) in line
    assert sorted(x.name for x in tmp_path.iterdir()) == before


def test_duplicated_mesh_cell(tmp_path):
    """A mesh body with one hexahedron27 written twice (issue "Nothing lost", item 2: it raised
    the tiny case's peak force by 10.6 % and exited 0): one line naming the file and the cell,
    exit 2, nothing written."""
    scenario = _bad_connectivity_scenario(tmp_path, duplicate=True)
    before = sorted(x.name for x in tmp_path.iterdir())
    p = _flexmvm("run", scenario, "--out", tmp_path / "out", *RUN_FAST)
    _one_line(p.stderr, 2, p.returncode, "bad.vtu", "hexahedron27 element 4 is written 2 times")
    assert sorted(x.name for x in tmp_path.iterdir()) == before


def test_nan_reaching_the_lcp_names_the_time(tmp_path, capsys, monkeypatch):
    """A NaN in the contact LCP: SolverError at its source, the step's time added by the
    driver (after the step was cut down to its smallest size); one line, exit 2, and what was
    computed before it kept in the output directory, marked failed."""
    from flexmvm.integrate.moreau_jean import coulomb, lcp

    def poisoned(D, c, n_eq, *args, **kwargs):
        return lcp.solve_checked(D, np.full_like(c, np.nan), n_eq, *args, **kwargs)

    # both steps (general and non-rotating) solve through coulomb.solve_contact_impulses
    monkeypatch.setattr(coulomb, "solve_checked", poisoned)
    code, _, err = _in_process(["run", TINY, "--out", tmp_path / "out", *RUN_FAST], capsys)
    _one_line(err, 2, code, "at t = ", "non-finite", "LCP", "histories up to t = 0 s")
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "failed" and "non-finite" in summary["failure"]


def test_unexpected_exception_is_one_line_with_exit_1(tmp_path, capsys, monkeypatch):
    import flexmvm.theory.scenario as theory

    def broken(*args, **kwargs):
        raise RuntimeError("b9 is missing\n  second line")

    monkeypatch.setattr(theory, "theory_histories", broken)
    code, _, err = _in_process(["theory", TINY, "--out", tmp_path / "th"], capsys)
    line = _one_line(err, 1, code)
    assert line == "flexmvm: error: theory: RuntimeError: b9 is missing second line"
    assert list(tmp_path.iterdir()) == []


def test_debug_shows_the_traceback(tmp_path, capsys, monkeypatch):
    import flexmvm.theory.scenario as theory

    monkeypatch.setattr(theory, "theory_histories", lambda *a, **k: 1 / 0)
    with pytest.raises(ZeroDivisionError):
        cli_main.main(["--debug", "theory", str(TINY), "--out", str(tmp_path / "th")])
    monkeypatch.setenv(cli_main.DEBUG_ENV, "1")
    with pytest.raises(ZeroDivisionError):
        cli_main.main(["theory", str(TINY), "--out", str(tmp_path / "th")])
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("how", ["--debug", "env"])
def test_debug_traceback_of_a_user_error(tmp_path, how):
    args = ["mesh", "rod", "--modes", "0", "--write", "missing_dir/rod.vtu"]
    if how == "--debug":
        p = _flexmvm("--debug", *args, cwd=tmp_path)
    else:
        p = _flexmvm(*args, cwd=tmp_path, env={cli_main.DEBUG_ENV: "1"})
    assert p.returncode != 0
    assert "Traceback" in p.stderr and "InputError" in p.stderr


def test_command_path_and_one_line():
    cli_main._register()
    assert cli_main.command_path(["--debug", "mesh", "rod", "--write", "x"]) == "mesh rod"
    assert cli_main.command_path(["study", "materials", "a.toml"]) == "study materials"
    assert cli_main.command_path(["run", "mesh"]) == "run"
    assert cli_main.one_line("a\n  b\tc\n") == "a b c"


# ----------------------------------------------------------------------------------------------
# item 10: the numerical sources
def test_lcp_refuses_non_finite_input():
    D = np.eye(2)
    with pytest.raises(SolverError, match="non-finite"):
        from flexmvm.integrate.moreau_jean.lcp import solve_mixed_lcp

        solve_mixed_lcp(D, np.array([-1.0, np.nan]), 0)
    with pytest.raises(SolverError, match="matrix"):
        solve_mixed_lcp(np.array([[1.0, np.inf], [np.inf, 1.0]]), np.array([-1.0, -1.0]), 1)


@pytest.mark.parametrize("sparse", [True, False])
def test_body_solver_refuses_a_non_finite_iteration_matrix(sparse):
    from flexmvm.bodies.body import FlexibleBody
    from flexmvm.integrate.moreau_jean.body_solver import BodySolver

    n = 6
    X = np.random.default_rng(0).normal(size=(n, 3))
    M = sp.csr_matrix(sp.eye(n))
    psi = sp.csr_matrix(sp.eye(3 * n).tocsc()[:, 6:])
    K = sp.eye(3 * n - 6, format="csr") * 1.0
    K = K.tolil()
    K[0, 0] = np.nan
    K = sp.csr_matrix(K) if sparse else K.toarray()
    body = FlexibleBody.build("striker", X, M, psi, K)
    with pytest.raises(SolverError, match="'striker'.*non-finite"):
        BodySolver(body).prepare(1e-6, np.eye(3), np.eye(6))


def test_driver_names_the_body_whose_state_became_non_finite():
    from types import SimpleNamespace

    from flexmvm.integrate.driver import _check_finite

    system = SimpleNamespace(bodies=[SimpleNamespace(name="b1"), SimpleNamespace(name="b2")])
    row = {
        "kin": 1.0,
        "strain": 0.5,
        "force": 0.0,
        "v": np.zeros((2, 6)),
        "q": [np.zeros(3), np.zeros(4)],
    }
    _check_finite(row, system, 1e-6)
    row["q"][1][2] = np.nan
    row["strain"] = np.nan
    with pytest.raises(SolverError, match=r"at t = 2e-06 s: .*non-finite.*'b2'"):
        _check_finite(row, system, 2e-6)


def test_sparse_factor_refuses_non_finite():
    from flexmvm.fe.modes import factor

    a = sp.eye(4, format="csc") * 1.0
    a[1, 1] = np.inf
    with pytest.raises(SolverError, match="non-finite"):
        factor(a)


def test_mesh_connectivity_out_of_range_at_creation():
    from flexmvm.mesh.mesh import CellBlock, CellType, Mesh

    nodes = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    for bad in (-1, 4):
        with pytest.raises(MeshError, match=f"node {bad}"):
            Mesh(nodes, (CellBlock(CellType.TET4, np.array([[0, 1, 2, bad]])),))


def test_read_mesh_refuses_out_of_range_node_sets(tmp_path):
    from flexmvm.mesh.io import read_mesh, write_mesh
    from flexmvm.mesh.rod import RodSpec, rod_mesh

    rm = rod_mesh(
        RodSpec(radius_m=0.005, length_m=0.05, n_rings=1, first_element_m=0.005, max_element_m=0.02)
    )
    write_mesh(tmp_path / "rod.vtu", rm.mesh)
    with pytest.raises(MeshError, match="node set 'tip'"):
        read_mesh(tmp_path / "rod.vtu", node_sets={"tip": [rm.mesh.n_nodes + 1]})


# ----------------------------------------------------------------------------------------------
# item 11: no partial output
def _run_ok(out: Path, capsys) -> dict:
    code, _, err = _in_process(["run", TINY, "--out", out, *RUN_FAST], capsys)
    assert code == 0, err
    return json.loads((out / "summary.json").read_text())


def test_reference_failure_keeps_the_scenarios_run(tmp_path, capsys, monkeypatch):
    """The scenario's run writes its history, then the full-FE reference fails: the scenario's
    run is written all the same (issue 48: a failing reference never hides it), its summary's
    failures names the reference; the one-line error names the reference; no temporary
    directory is left beside DIR."""
    from flexmvm.runs import main_job

    real = main_job._run_and_write

    def ref_fails(sc, label, out_dir, fields, progress):
        if label == "full":
            raise SolverError("contact Newton iteration did not converge")
        return real(sc, label, out_dir, fields, progress)

    out = tmp_path / "new" / "out"
    monkeypatch.setattr(main_job, "_run_and_write", ref_fails)
    code, _, err = _in_process(["run", TINY, "--out", out, *RUN_FAST], capsys)
    _one_line(err, 2, code, "full-FE reference", "did not converge", "written in")
    summary = json.loads((out / "summary.json").read_text())
    assert "reference_full" in [f["item"] for f in summary["failures"]]
    assert [x.name for x in tmp_path.iterdir()] == ["new"]
    assert [x.name for x in out.parent.iterdir()] == ["out"]


def test_reference_failure_in_the_second_process(tmp_path):
    """--jobs 2: the reference fails in its worker process; the scenario's own run (the other
    worker) is waited for and written, the reference named in one line. The job runs in a
    process of its own (the hook patched in before main): in the test worker itself, the
    pool's start and stop twice ended that worker ("worker crashed") in full suite runs; here a
    crash is this test's failure, with its exit status."""
    fast = [a for a in RUN_FAST if a not in ("--jobs", "1")]
    job = tmp_path / "job"
    argv = ["run", str(TINY), "--out", str(job / "out"), *fast, "--jobs", "2"]
    script = (
        f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r})\n"
        "import _main_job_hooks\n"
        "from flexmvm.runs import main_job\n"
        "main_job._run_and_write = _main_job_hooks.reference_fails\n"
        "from flexmvm.cli import main as cli_main\n"
        f"cli_main.main({argv!r})\n"
    )
    p = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=600, check=False
    )
    _one_line(p.stderr, 2, p.returncode, "full-FE reference", "did not converge", "written in")
    summary = json.loads((job / "out" / "summary.json").read_text())
    assert "reference_full" in [f["item"] for f in summary["failures"]]


def test_theory_failure_mid_write_leaves_nothing(tmp_path, capsys, monkeypatch):
    from flexmvm.results import history

    real = history.write_history

    def write_then_fail(path, *args, **kwargs):
        real(path, *args, **kwargs)
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(history, "write_history", write_then_fail)
    code, _, err = _in_process(["theory", TINY, "--out", tmp_path / "th"], capsys)
    _one_line(err, 1, code, "theory: OSError", "No space left")
    assert list(tmp_path.iterdir()) == []


def test_staged_dir_replaces_an_earlier_output_as_a_whole(tmp_path):
    from flexmvm.results.outdir import MARKER, staged_dir

    out = tmp_path / "out"
    with staged_dir(out, "flexmvm test") as tmp:
        (tmp / "a.txt").write_text("1")
        (tmp / "stale.txt").write_text("old")
        assert not out.exists()
    files = lambda: {k: v for k, v in _tree(out).items() if k != MARKER}
    assert files() == {"a.txt": b"1", "stale.txt": b"old"}
    assert set(json.loads((out / MARKER).read_text())["files"]) == {"a.txt", "stale.txt"}
    with staged_dir(out, "flexmvm test") as tmp:
        (tmp / "a.txt").write_text("2")
        assert (out / "a.txt").read_text() == "1"
    assert files() == {"a.txt": b"2"}
    with pytest.raises(InputError, match="not of flexmvm other"), staged_dir(out, "flexmvm other"):
        pass
    with pytest.raises(RuntimeError), staged_dir(out, "flexmvm test") as tmp:
        (tmp / "a.txt").write_text("3")
        raise RuntimeError("boom")
    assert files() == {"a.txt": b"2"}
    assert [x.name for x in tmp_path.iterdir()] == ["out"]


def test_staged_dir_through_a_symlink_keeps_the_link(tmp_path):
    from flexmvm.results.outdir import staged_dir

    (tmp_path / "scratch").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "scratch")
    for text in ("1", "2"):
        with staged_dir(tmp_path / "link", "flexmvm test") as tmp:
            (tmp / "a.txt").write_text(text)
    assert (tmp_path / "link").is_symlink()
    assert (tmp_path / "scratch" / "a.txt").read_text() == "2"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["link", "scratch"]


def test_interrupt_is_one_line_exit_130_and_leaves_nothing(tmp_path, capsys, monkeypatch):
    import flexmvm.theory.scenario as theory

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(theory, "theory_histories", interrupted)
    code, _, err = _in_process(["theory", TINY, "--out", tmp_path / "th"], capsys)
    assert code == 130 and "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("flexmvm: interrupted"), err
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------------------------
# item 12: comparisons that cannot be made are listed
def test_comparisons_that_cannot_be_made_are_listed(tmp_path, capsys, monkeypatch):
    import flexmvm.theory.scenario as theory

    def not_two_rods(sc, dt=None):
        raise InputError("the 1D theory needs two coaxial rods")

    monkeypatch.setattr(theory, "theory_histories", not_two_rods)
    out = tmp_path / "out"
    code, stdout, err = _in_process(["run", TINY, "--out", out, *RUN_FAST], capsys)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    items = {f["item"]: f["reason"] for f in summary["failures"]}
    assert "two coaxial rods" in items["comparison_vs_theory"]
    assert "comparison_vs_theory" not in summary and "comparison_vs_full" in summary
    assert "not compared" in stdout and "two coaxial rods" in stdout


def test_stale_data_note_is_one_line(capsys):
    """A recomputation of stored data (StaleDataWarning) reaches a CLI user as one stderr line,
    ``flexmvm: note: <message>``, not Python's two-line warning with a source line (the CLI
    and the main job's worker processes install this display: errors.notes_as_lines)."""
    import warnings

    from flexmvm.errors import StaleDataWarning, notes_as_lines

    with warnings.catch_warnings():
        warnings.simplefilter("always")
        notes_as_lines()
        notes_as_lines()  # once is enough: a second call adds nothing
        warnings.warn(
            "setup cache fe-0.npz: holds NaN or inf in M_data: evicted and rebuilt",
            StaleDataWarning,
            stacklevel=1,
        )
    assert capsys.readouterr().err == (
        "flexmvm: note: setup cache fe-0.npz: holds NaN or inf in M_data: evicted and rebuilt\n"
    )
