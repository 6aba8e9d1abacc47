"""Output folders that keep what they hold, failures that keep their results (issue 48).

A user's file written into --out during a run is kept; a mount point is written in place; a
hand-edited manifest entry is not trusted; two runs into one folder cannot both succeed; a
stale staging folder is recognised when its pid was reused; a failed run keeps its result
(non-finite summary values, a degenerate facet, a failing full-FE reference); the validation
tool does not overwrite a user's D.md. Each check is exact (files, bytes, one-line messages): there is
no tolerance to choose.
"""

from __future__ import annotations

import errno
import json
import math
import os
import subprocess
from pathlib import Path

import pytest
from test_cli_failures import RUN_FAST, TINY, _in_process, _one_line, _tree

from flexmvm.errors import InputError, SolverError
from flexmvm.results.outdir import MARKER, PARTIAL_MARKER, remove_stale_partials, staged_dir

CMD = "flexmvm test"


def _write_output(out: Path, files: dict[str, str]) -> None:
    with staged_dir(out, CMD) as tmp:
        for name, text in files.items():
            (tmp / name).write_text(text)


def test_a_users_file_written_during_the_run_is_kept(tmp_path):
    """NOTES.txt written into DIR while the rerun goes: DIR is left as it is (the note and the
    earlier output), the new output kept beside it; both named in one line."""
    out = tmp_path / "out"
    _write_output(out, {"a.txt": "first\n"})
    with pytest.raises(InputError) as info, staged_dir(out, CMD) as tmp:
        (tmp / "a.txt").write_text("second\n")
        (out / "NOTES.txt").write_text("mine\n")
    msg = str(info.value)
    kept = out.with_name(f"out.new-{os.getpid()}")
    assert "NOTES.txt" in msg and str(kept) in msg and "\n" not in msg
    assert (out / "NOTES.txt").read_text() == "mine\n"
    assert (out / "a.txt").read_text() == "first\n"
    assert (kept / "a.txt").read_text() == "second\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", kept.name]


def test_a_hand_edited_link_entry_is_not_trusted(tmp_path):
    """A manifest entry edited to "link" (once a skipped hash check) does not let a changed
    file be deleted; a real symbolic link is recorded with its target and checked."""
    out = tmp_path / "out"
    with staged_dir(out, CMD) as tmp:
        (tmp / "a.txt").write_text("flexmvm's\n")
        (tmp / "to_a").symlink_to("a.txt")
    manifest = json.loads((out / MARKER).read_text())
    assert manifest["files"]["to_a"] == "link:a.txt"
    _write_output(out, {"a.txt": "flexmvm's\n"})  # an unchanged output (link included) goes
    manifest = json.loads((out / MARKER).read_text())
    manifest["files"]["a.txt"] = "link"
    (out / MARKER).write_text(json.dumps(manifest))
    (out / "a.txt").write_text("the user's own data\n")
    with pytest.raises(InputError, match=r"changed since .* \(a\.txt\)"):
        _write_output(out, {"a.txt": "new\n"})
    assert (out / "a.txt").read_text() == "the user's own data\n"


def test_two_writers_of_one_folder_the_second_is_refused(tmp_path):
    """While one process writes DIR, a second is refused in one line naming DIR and the
    first one's pid; the first then finishes normally."""
    out = tmp_path / "out"
    with staged_dir(out, CMD) as tmp:
        (tmp / "a.txt").write_text("first\n")
        with pytest.raises(InputError) as info, staged_dir(out, CMD):
            pass
    assert f"pid {os.getpid()}" in str(info.value) and str(out) in str(info.value)
    assert (out / "a.txt").read_text() == "first\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_a_run_in_another_process_holds_the_folder(tmp_path):
    """Another process writing DIR (a real second process, holding the lock) makes this one
    refuse, naming its pid; a lock left by a killed process whose pid was reused (here: this
    test's parent, recorded with another start time) is taken over."""
    import sys

    out = tmp_path / "out"
    script = (
        "import sys, time\n"
        "from flexmvm.results.outdir import staged_dir\n"
        f"with staged_dir({str(out)!r}, {CMD!r}) as tmp:\n"
        "    print('in', flush=True)\n"
        "    sys.stdin.readline()\n"
    )
    other = subprocess.Popen(
        [sys.executable, "-c", script], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    try:
        assert other.stdout.readline() == "in\n"
        with pytest.raises(InputError, match=rf"being written by .*pid {other.pid}\b"):
            _write_output(out, {"a.txt": "second\n"})
    finally:
        other.communicate("\n", timeout=60)
    assert other.returncode == 0 and not (out / "a.txt").exists()
    lock = tmp_path / ".out.flexmvm-lock"
    lock.write_text(json.dumps({"command": CMD, "pid": os.getppid(), "start": "1"}))
    _write_output(out, {"a.txt": "third\n"})
    assert (out / "a.txt").read_text() == "third\n" and not lock.exists()


def test_a_stale_partial_whose_pid_was_reused_is_removed(tmp_path):
    """A staging folder of a killed run whose pid now belongs to another live process (here:
    this test's parent, with another start time) is stale and removed; one of a process that
    really runs (same pid and start time) is kept."""
    from flexmvm.results.outlock import this_process

    out = tmp_path / "out"
    reused = tmp_path / f"out.partial-{os.getppid()}"
    reused.mkdir()
    (reused / PARTIAL_MARKER).write_text(json.dumps({"pid": os.getppid(), "start": "1"}))
    child = subprocess.Popen(["sleep", "30"])
    try:
        live = tmp_path / f"out.partial-{child.pid}"
        live.mkdir()
        info = {**this_process(CMD), "pid": child.pid}
        info["start"] = Path(f"/proc/{child.pid}/stat").read_text().rsplit(")", 1)[1].split()[19]
        (live / PARTIAL_MARKER).write_text(json.dumps(info))
        assert remove_stale_partials(out) == [reused]
        assert live.is_dir()
    finally:
        child.kill()
        child.wait()


def _mounted_tmpfs(path: Path) -> bool:
    path.mkdir()
    p = subprocess.run(
        ["mount", "-t", "tmpfs", "tmpfs", str(path)], capture_output=True, check=False
    )
    return p.returncode == 0


def test_an_out_folder_on_a_mount_point_is_written_in_place(tmp_path):
    """A tmpfs mounted at DIR (a container volume): the run stages inside DIR and moves its
    files in; a rerun replaces them; the mount point stays."""
    out = tmp_path / "out"
    if not _mounted_tmpfs(out):
        pytest.skip("mount -t tmpfs not permitted here (the EBUSY test covers the move)")
    try:
        _write_output(out, {"a.txt": "first\n", "b.txt": "b\n"})
        assert os.path.ismount(out) and _tree(out).keys() == {"a.txt", "b.txt", MARKER}
        _write_output(out, {"a.txt": "second\n"})
        assert os.path.ismount(out)
        assert sorted(p.name for p in out.iterdir()) == [MARKER, "a.txt"]
        assert (out / "a.txt").read_text() == "second\n"
        assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
    finally:
        subprocess.run(["umount", str(out)], check=False)


def test_a_folder_that_cannot_be_renamed_gets_its_files_moved_in(tmp_path, monkeypatch):
    """os.replace of DIR itself fails with EBUSY (a bind mount os.path.ismount does not see):
    the staged files are moved into DIR instead of the run being lost."""
    out = tmp_path / "out"
    _write_output(out, {"a.txt": "first\n", "old.txt": "old\n"})
    real = os.replace

    def busy(src, dst, *args, **kwargs):
        if Path(src) == out:
            raise OSError(errno.EBUSY, "Device or resource busy", str(src))
        return real(src, dst, *args, **kwargs)

    monkeypatch.setattr(os, "replace", busy)
    _write_output(out, {"a.txt": "second\n"})
    assert sorted(p.name for p in out.iterdir()) == [MARKER, "a.txt"]
    assert (out / "a.txt").read_text() == "second\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_non_finite_summary_values_are_written_as_null(tmp_path, capsys, monkeypatch):
    """A NaN in the summary (momentum_residual_rel) no longer loses the run: summary.json is
    written with null there and the field listed in non_finite_fields."""
    from flexmvm.runs import run as run_mod

    real = run_mod.summarize

    def with_nan(res, built):
        return {**real(res, built), "momentum_residual_rel": math.nan}

    monkeypatch.setattr(run_mod, "summarize", with_nan)
    out = tmp_path / "out"
    code, _, err = _in_process(["run", TINY, "--out", out, *RUN_FAST], capsys)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["momentum_residual_rel"] is None
    assert summary["reference_full"]["momentum_residual_rel"] is None  # the reference's too
    assert summary["non_finite_fields"] == [
        "momentum_residual_rel",
        "reference_full.momentum_residual_rel",
    ]


def test_a_degenerate_facet_after_a_step_is_a_step_failure(tmp_path, capsys, monkeypatch):
    """The surface measure after an accepted step meets a degenerate deformed facet: the run
    stops there (time, step, bodies named) and keeps what it computed, marked failed."""
    from flexmvm.contact import pairs

    real = pairs.PointToSurfaceContact.penetration
    calls = [0]

    def degenerate_later(self, bodies, states, deep=False, floors=None):
        calls[0] += 1
        if calls[0] > 4:
            who = getattr(self, "_who", self.name)  # the pair and its bodies
            raise SolverError(f"{who}: " + pairs._failure(pairs.DEGENERATE_QUAD, 3))
        return real(self, bodies, states, deep, floors)

    monkeypatch.setattr(pairs.PointToSurfaceContact, "penetration", degenerate_later)
    out = tmp_path / "out"
    code, _, err = _in_process(["run", TINY, "--out", out, *RUN_FAST], capsys)
    _one_line(err, 2, code, "at t = ", "(step 4)", "quad facet 3 degenerate", "'b2' on 'b1'")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and "degenerate" in summary["failure"]


def test_a_failing_reference_does_not_hide_the_scenarios_run(tmp_path, capsys, monkeypatch):
    """The full-FE reference fails: the scenario's own run is still written (its summary's
    failures names the reference), and the one-line error names the reference."""
    from flexmvm.runs import main_job

    real = main_job._run_and_write

    def ref_fails(sc, label, out_dir, fields, progress):
        if label == "full":
            raise SolverError("contact Newton iteration did not converge")
        return real(sc, label, out_dir, fields, progress)

    monkeypatch.setattr(main_job, "_run_and_write", ref_fails)
    out = tmp_path / "out"
    code, _, err = _in_process(["run", TINY, "--out", out, *RUN_FAST], capsys)
    _one_line(err, 2, code, "full-FE reference", "did not converge", f"written in {out}")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] != "failed"
    assert "reference_full" in [f["item"] for f in summary["failures"]]
    assert "history.csv" in _tree(out)


def test_validate_refuses_a_users_report_page_beside_out(tmp_path, capsys, monkeypatch):
    """python -m tools.validation --out D with a user's D.md: refused in one line before any
    case runs, D.md unchanged; a page the tool wrote (the generated header) is accepted."""
    from tools.validation import command, report, suite

    def validate(argv):
        code = 0
        try:
            command.main([str(a) for a in argv])
        except SystemExit as exc:
            code = exc.code
        out = capsys.readouterr()
        return code, out.out, out.err

    ran = []
    monkeypatch.setattr(suite, "run_validation", lambda *a, **k: ran.append(a))
    (tmp_path / "D.md").write_text("# my notes\n")
    code, _, err = validate(["--out", tmp_path / "D"])
    _one_line(err, 2, code, "D.md", "did not write")
    assert ran == [] and (tmp_path / "D.md").read_text() == "# my notes\n"
    opening = report._template("header").template.split("$")[0]
    (tmp_path / "D.md").write_text(opening + "2026-01-01 ...\n")
    code, _, err = validate(["--out", tmp_path / "D"])
    assert code == 0 and len(ran) == 1, err
