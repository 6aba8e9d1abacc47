"""Faults injected as a demanding user meets them, on the tiny case (issue "Nothing lost"):
a folder of a user's files given as --out, the run killed (SIGTERM, SIGKILL) or one of its
workers killed. Each holds: the user's files survive, exit status non-zero with one line, no
worker outlives its parent, no staging folder is left (or the next run removes it and says so).
Corrupt cache entries: tests/test_setup_cache.py (NaN and edited entries evicted, named,
rebuilt); cut or edited stored histories: tests/test_study_stored.py, tests/test_validation_cache.py."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from test_cli_failures import RUN_FAST, TINY, _in_process, _one_line, _tree

from flexmvm.errors import InputError
from flexmvm.results.outdir import MARKER, claim_study_dir, staged_dir


def _refused(code: int, err: str, *words: str) -> None:
    """One stderr line, exit 2, naming every word (test_cli_failures._one_line)."""
    _one_line(err, 2, code, *words)


# ------------------------------------------------------------------------------------------
# a folder of a user's files
def _users_folder(path: Path) -> dict[str, bytes]:
    path.mkdir()
    (path / "summary.json").write_text('{"mine": true}\n')
    (path / "thesis.tex").write_text("\\documentclass{article}\n")
    (path / "figs").mkdir()
    (path / "figs" / "f1.pdf").write_bytes(b"%PDF-1.4 user figure")
    return _tree(path)


def test_run_refuses_a_users_folder_that_holds_a_summary_json(tmp_path, capsys):
    """Before: a folder with any summary.json counted as an earlier output and was replaced
    whole (thesis.tex and figs/ deleted, exit 0)."""
    out = tmp_path / "thesis"
    before = _users_folder(out)
    code, _, err = _in_process(["run", TINY, "--out", out, *RUN_FAST], capsys)
    _refused(code, err, str(out), "no flexmvm manifest", "summary.json")
    assert _tree(out) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["thesis"]


def test_theory_refuses_a_users_folder_that_holds_a_history_csv(tmp_path, capsys):
    out = tmp_path / "data"
    out.mkdir()
    (out / "history.csv").write_text("t,f\n0,0\n")
    (out / "measured.csv").write_text("t,f\n0,1\n")
    before = _tree(out)
    code, _, err = _in_process(["theory", TINY, "--out", out], capsys)
    _refused(code, err, "no flexmvm manifest")
    assert _tree(out) == before


def test_run_keeps_a_note_added_to_its_earlier_output(tmp_path, capsys):
    """An earlier run's folder is replaced when unchanged; with a user's NOTES.txt added (or a
    file of the run edited) it is refused, naming the file, and nothing is lost."""
    out = tmp_path / "out"
    code, _, err = _in_process(["run", TINY, "--out", out, *RUN_FAST], capsys)
    assert code == 0, err
    manifest = json.loads((out / MARKER).read_text())
    assert manifest["command"] == "flexmvm run"
    assert set(manifest["files"]) == set(_tree(out)) - {MARKER}
    first = _tree(out)
    code, _, err = _in_process(["run", TINY, "--out", out, *RUN_FAST], capsys)
    assert code == 0, err  # an unchanged earlier output is replaced
    assert set(_tree(out)) == set(first)
    (out / "NOTES.txt").write_text("run 1: looks right\n")
    before = _tree(out)
    code, _, err = _in_process(["run", TINY, "--out", out, *RUN_FAST], capsys)
    _refused(code, err, "did not write", "NOTES.txt")
    assert _tree(out) == before
    (out / "NOTES.txt").unlink()
    (out / "summary.json").write_text('{"edited": "by hand"}\n')
    before = _tree(out)
    code, _, err = _in_process(["run", TINY, "--out", out, *RUN_FAST], capsys)
    _refused(code, err, "changed since", "summary.json")
    assert _tree(out) == before


def test_staged_dir_refuses_another_command_and_a_markerless_folder(tmp_path):
    out = tmp_path / "out"
    with staged_dir(out, "flexmvm test") as tmp:
        (tmp / "a.txt").write_text("1")
        (tmp / "sub").mkdir()
        (tmp / "sub" / "b.txt").write_text("2")
    with (
        pytest.raises(InputError, match="output of 'flexmvm test', not of flexmvm other"),
        staged_dir(out, "flexmvm other"),
    ):
        pass
    (out / MARKER).unlink()
    with pytest.raises(InputError, match="no flexmvm manifest"), staged_dir(out, "flexmvm test"):
        pass
    assert _tree(out) == {"a.txt": b"1", "sub/b.txt": b"2"}


def test_study_folder_is_claimed_only_when_new_empty_or_its_own(tmp_path):
    """`flexmvm select --out` wrote into any folder, overwriting same-named files among a
    user's own; now the folder must be new, empty, an earlier study of the same command (its
    marker), or hold only the study's own names (a study written before the marker)."""
    users = tmp_path / "users"
    users.mkdir()
    (users / "ncc.csv").write_text("mine\n")
    (users / "paper.tex").write_text("x\n")
    with pytest.raises(InputError, match="not written by flexmvm select.*paper.tex"):
        claim_study_dir(users, "flexmvm select", own={"ncc.csv", "cases"})
    assert sorted(p.name for p in users.iterdir()) == ["ncc.csv", "paper.tex"]
    study = claim_study_dir(tmp_path / "study", "flexmvm select", own={"ncc.csv"})
    (study / "ncc.csv").write_text("study\n")
    (study / "NOTES.txt").write_text("a user's note beside the study\n")
    assert claim_study_dir(study, "flexmvm select", own={"ncc.csv"}) == study  # resumes
    with pytest.raises(InputError, match="output of 'flexmvm select'"):
        claim_study_dir(study, "flexmvm study materials")
    legacy = tmp_path / "legacy"
    (legacy / "cases").mkdir(parents=True)
    (legacy / "ncc.csv").write_text("old study\n")
    claim_study_dir(legacy, "flexmvm select", own={"ncc.csv", "cases"})
    assert (legacy / MARKER).is_file()


def test_select_cli_refuses_a_users_folder(tmp_path):
    out = tmp_path / "paper"
    out.mkdir()
    (out / "selection.json").write_text("{}\n")
    (out / "draft.md").write_text("draft\n")
    before = _tree(out)
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "flexmvm.cli.main",
            "select",
            str(TINY),
            "--body",
            "b2",
            "--out",
            str(out),
            "--serial",
            "--no-progress",
            "--t-end",
            "3e-6",
            "--modes",
            "7",
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    _refused(p.returncode, p.stderr, "draft.md")
    assert _tree(out) == before


# ------------------------------------------------------------------------------------------
# the run killed, a worker killed
def _children(pid: int) -> list[int]:
    """Pids of the live processes whose parent is ``pid`` (Linux /proc)."""
    kids = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            stat = (d / "stat").read_text()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2 :].split()
        if int(fields[1]) == pid and fields[0] != "Z":
            kids.append(int(d.name))
    return kids


def _alive(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rindex(")") + 2 :].split()[0] != "Z"


def _start_run(out: Path) -> tuple[subprocess.Popen, list[int]]:
    """`flexmvm run --jobs 2` on the tiny case (long enough to be caught running); returns the
    process and its two pool workers once both have started."""
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "flexmvm.cli.main",
            "run",
            str(TINY),
            "--out",
            str(out),
            "--t-end",
            "3e-4",
            "--no-fields",
            "--no-progress",
            "--jobs",
            "2",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        workers = [
            k
            for k in _children(proc.pid)
            if "resource_tracker" not in Path(f"/proc/{k}/cmdline").read_text()
        ]
        if len(workers) >= 2 and (out.parent / f"{out.name}.partial-{proc.pid}").is_dir():
            time.sleep(3.0)  # inside the runs, past the imports
            return proc, _children(proc.pid)
        if proc.poll() is not None:
            pytest.fail(f"the run ended before it could be killed: {proc.communicate()}")
        time.sleep(0.2)
    proc.kill()
    pytest.fail("the run's workers did not start within 120 s")


def _wait_gone(pids: list[int], seconds: float) -> list[int]:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        alive = [p for p in pids if _alive(p)]
        if not alive:
            return []
        time.sleep(0.1)
    return [p for p in pids if _alive(p)]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_sigterm_stops_the_workers_and_leaves_nothing(tmp_path):
    """SIGTERM to the run alone (a scheduler's stop): exit 143 with one line, its workers and
    resource tracker gone within 5 s (they were left running for the whole run before), no
    staging folder, no output folder."""
    out = tmp_path / "out"
    proc, kids = _start_run(out)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert "Traceback" not in err and "terminated" in err.strip().splitlines()[-1]
    assert _wait_gone(kids, 5.0) == []
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_sigkill_takes_the_workers_and_the_next_run_removes_the_staging_folder(tmp_path, capsys):
    """SIGKILL cannot be cleaned up after: the workers die with the parent (within 5 s), the
    staging folder stays, and the next run into the same --out removes it and says so."""
    out = tmp_path / "out"
    proc, kids = _start_run(out)
    os.kill(proc.pid, signal.SIGKILL)
    proc.communicate(timeout=60)
    assert _wait_gone(kids, 5.0) == []
    stale = tmp_path / f"out.partial-{proc.pid}"
    assert stale.is_dir()
    code, stdout, err = _in_process(["run", TINY, "--out", out, *RUN_FAST], capsys)
    assert code == 0, err
    assert f"removed {stale}" in stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_killed_worker_fails_the_run_in_one_line(tmp_path):
    """One of the two workers killed (the OOM killer's way): the run stops with one line and a
    non-zero exit, the other worker is stopped, nothing is left behind."""
    out = tmp_path / "out"
    proc, kids = _start_run(out)
    workers = [k for k in kids if "resource_tracker" not in Path(f"/proc/{k}/cmdline").read_text()]
    os.kill(workers[0], signal.SIGKILL)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode != 0
    lines = err.strip().splitlines()
    assert "Traceback" not in err and len(lines) == 1 and lines[0].startswith("flexmvm: error:"), (
        err
    )
    assert _wait_gone(kids, 5.0) == []
    assert list(tmp_path.iterdir()) == []
