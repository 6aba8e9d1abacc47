"""Studies and inputs that fail in one line (issue 48, the "poor" items): a full disk during
`flexmvm select`, Ctrl-C on it, an impact faster than the model holds, time tables whose
times are wrong, a --scheduler that nothing answers. Each ends in one stderr line naming
the key (or file) and the value as written: exit status 2 (130 for Ctrl-C), no traceback,
no Dask log lines."""

from __future__ import annotations

import copy
import errno
import importlib
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from test_cli_failures import TINY, _in_process, _one_line
from test_fault_injection import _alive, _children
from test_loads_scenario import _data as _loads_data

from flexmvm.errors import OutputError
from flexmvm.scenarios import ScenarioError, load_scenario, scenario_from_dict

SELECT_FAST = ["--body", "b2", "--t-end", "3e-6", "--layers", "1", "--laps", "1", "--modes", "7"]


# ------------------------------------------------------------------------------------------
# item 4: time tables
def _loads_error(path: tuple, value) -> str:
    data = copy.deepcopy(_loads_data())
    target = data
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(data, "driven_rod")
    return str(info.value)


@pytest.mark.parametrize(
    ("path", "value", "expected"),
    [
        # times wrong: the times key named, the times as written (was: force_n / torque_nm
        # named and "np.float64(5e-06) then np.float64(5e-06)")
        (
            ("loads", 0, "times_s"),
            [5e-6, 5e-6],
            "loads[0].times_s: times must increase strictly, got 5e-06 then 5e-06",
        ),
        (
            ("loads", 0, "times_s"),
            [1e-5, 5e-6],
            "loads[0].times_s: times must increase strictly, got 1e-05 then 5e-06",
        ),
        (
            ("loads", 0, "times_s"),
            [0.0, float("nan")],
            "loads[0].times_s: expected finite times [s], got nan",
        ),
        # values wrong: the values key named, the value as written
        (
            ("loads", 0, "torque_nm"),
            [0.0, float("inf")],
            "loads[0].torque_nm: expected finite values, got inf",
        ),
    ],
)
def test_time_table_errors_name_the_key_and_show_values_as_written(path, value, expected):
    line = _loads_error(path, value)
    assert expected in line and "np." not in line and "\n" not in line, line


def test_table_rows_show_times_as_written():
    """A table of numpy rows (a script's) said np.float64(...) in TimeHistory.table's line."""
    import numpy as np

    from flexmvm.errors import InputError
    from flexmvm.loads.history import TimeHistory

    with pytest.raises(InputError) as info:
        TimeHistory.table(np.array([0.0, 5e-6, 5e-6]), np.zeros(3), 1, "force")
    assert "got 5e-06 then 5e-06" in str(info.value) and "np." not in str(info.value)


# ------------------------------------------------------------------------------------------
# item 3: the impact speed against the bar wave speed
def _tiny_at(tmp_path: Path, speed: str) -> Path:
    text = TINY.read_text(encoding="utf-8")
    old = "velocity_mps = [0.21, 0.0, 0.0]"
    assert old in text
    path = tmp_path / "case.toml"
    path.write_text(text.replace(old, f"velocity_mps = [{speed}, 0.0, 0.0]"), encoding="utf-8")
    return path


def test_an_impact_faster_than_a_tenth_of_the_wave_speed_is_refused(tmp_path, capsys):
    """1e6 m/s was accepted and gave NaN at step 1. Brass b1 onto aluminium b2: the smaller
    bar wave speed is brass's, c = sqrt(E/rho) = sqrt(96.5e9 / 8390) = 3391 m/s (printed to
    4 digits; aluminium's is 5189 m/s); the bound is 0.1 c = 339.1 m/s."""
    code, _, err = _in_process(
        ["run", _tiny_at(tmp_path, "1e6"), "--t-end", "3e-6", "--out", tmp_path / "o"], capsys
    )
    line = _one_line(err, 2, code, "bodies[0].placement.velocity_mps", "[1e+06, 0, 0]")
    assert "c = sqrt(E/rho) = 3391 m/s" in line and "'b1'" in line, line
    assert not (tmp_path / "o").exists()


def test_the_wave_speed_bound_is_a_tenth_of_c(tmp_path):
    """Just below 0.1 c (330 m/s, 0.097 c) loads; just above (350 m/s, 0.103 c) does not:
    the bound sits where the docstring puts it, to 3 % of c."""
    load_scenario(_tiny_at(tmp_path, "330.0"))
    with pytest.raises(ScenarioError, match=re.escape("expected at most 0.1 c = 339.1 m/s")):
        load_scenario(_tiny_at(tmp_path, "350.0"))


# ------------------------------------------------------------------------------------------
# item 5: a bad --scheduler address before the reference
def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_scheduler_nothing_answers_fails_before_the_reference(tmp_path, capsys):
    """A port nothing listens on: one line in a few seconds (was: after the full-FE
    reference, then Dask's 30 s of connect retries); no reference made. 10 s bounds the
    5 s connect timeout on a loaded machine (a refused port answers in milliseconds)."""
    address = f"tcp://127.0.0.1:{_free_port()}"
    out = tmp_path / "study"
    start = time.monotonic()
    code, _, err = _in_process(
        ["select", TINY, *SELECT_FAST, "--scheduler", address, "--out", out], capsys
    )
    took = time.monotonic() - start
    _one_line(err, 2, code, address, "cannot connect")
    assert took < 10.0, took
    assert not (out / "reference").exists()


# ------------------------------------------------------------------------------------------
# item 1: a full disk during select
def _no_space(*args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device")


@pytest.mark.parametrize(
    ("module", "name", "file"),
    [
        ("flexmvm.studies.reference_run", "write_history", "reference/history.csv"),
        ("flexmvm.studies.runner", "write_json_atomic", "cases/l1-j1-m7.json"),
        ("flexmvm.studies.selection_files", "write_json_atomic", "selection.json"),
    ],
)
def test_full_disk_in_select_is_one_line_naming_the_file(
    tmp_path, capsys, monkeypatch, module, name, file
):
    """The reference, a case, the report: each write on a full disk is exit 2 and one line
    naming the file (was: exit 1 with a raw OSError)."""
    monkeypatch.setattr(importlib.import_module(module), name, _no_space)
    out = tmp_path / "study"
    code, _, err = _in_process(
        ["select", TINY, *SELECT_FAST, "--serial", "--no-progress", "--out", out], capsys
    )
    _one_line(err, 2, code, str(out / file), "no space left")


def test_full_disk_on_dask_is_one_line_without_dask_noise(tmp_path, capfd, monkeypatch):
    """The same on a local Dask cluster (one worker): one line on the process's stderr
    (file descriptor 2, where the workers and Dask's loggers write), no Dask log line."""
    from flexmvm.studies import runner

    monkeypatch.setattr(runner, "write_json_atomic", _no_space)
    out = tmp_path / "study"
    argv = ["select", TINY, *SELECT_FAST, "--workers", "1", "--no-progress", "--out", out]
    code, _, err = _in_process(argv, capfd)
    _one_line(err, 2, code, str(out / "cases" / "l1-j1-m7.json"), "no space left")


def test_a_full_quota_without_a_file_name_names_the_file_to_be(tmp_path):
    """The last guard of the study commands: an OSError that no writer named (EDQUOT on a
    results.atomic temporary file) names the file it was to become."""
    from flexmvm.cli.study_options import study_output

    tmp = tmp_path / ".ncc.csv.k3j9x0qa.tmp"
    expected = re.escape(f"cannot write {tmp_path / 'ncc.csv'}: ")
    with pytest.raises(OutputError, match=expected), study_output(tmp_path):
        raise OSError(errno.EDQUOT, os.strerror(errno.EDQUOT), str(tmp))


# ------------------------------------------------------------------------------------------
# item 2: Ctrl-C on select
def _descendants(pid: int) -> list[int]:
    out, todo = [], [pid]
    while todo:
        kids = _children(todo.pop())
        out += kids
        todo += kids
    return out


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_ctrl_c_on_select_is_one_line_and_130(tmp_path):
    """Ctrl-C in a terminal (SIGINT to the whole process group) once the first case is
    stored: one line saying how many cases are stored where, exit 130, no traceback (each
    worker printed a 30-line KeyboardInterrupt traceback, the nanny its warnings), no
    process of the study left 10 s after (the nanny's own kill comes after 4 s)."""
    out = tmp_path / "study"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "flexmvm.cli.main",
            "select",
            str(TINY),
            "--body",
            "b2",
            "--t-end",
            "1e-5",
            "--layers",
            "1",
            "--laps",
            "1..2",
            "--modes",
            "7:43:6",
            "--workers",
            "1",
            "--no-progress",
            "--out",
            str(out),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    deadline = time.monotonic() + 300
    while not (out / "cases").is_dir() or not list((out / "cases").glob("*.json")):
        if proc.poll() is not None or time.monotonic() > deadline:
            proc.kill()
            pytest.fail(f"no case stored before the end: {proc.communicate()}")
        time.sleep(0.1)
    kids = _descendants(proc.pid)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    lines = err.strip().splitlines()
    assert proc.returncode == 130, err
    assert "Traceback" not in err and len(lines) == 1, err
    assert re.fullmatch(
        rf"flexmvm: interrupted; \d+ of 14 cases stored in {re.escape(str(out / 'cases'))}, "
        "rerun to resume",
        lines[0],
    ), lines[0]
    deadline = time.monotonic() + 10
    while any(_alive(k) for k in kids) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not [k for k in kids if _alive(k)]


def test_ctrl_c_before_the_cases_is_one_line_and_130(tmp_path, capsys, monkeypatch):
    """Ctrl-C during the full-FE reference (no case yet): one line and 130 (was click's
    blank line, then the run command's message about output directories)."""
    from flexmvm.studies import selection

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(selection, "reference_history", interrupted)
    out = tmp_path / "study"
    code, _, err = _in_process(["select", TINY, *SELECT_FAST, "--serial", "--out", out], capsys)
    assert (
        code == 130
        and err == f"flexmvm: interrupted before the cases ran; rerun to resume in {out}\n"
    ), err
