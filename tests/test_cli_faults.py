"""Smaller faults of the command line ("Nothing lost", item 5): absurd motion input, a full
disk, a time step longer than the run, Ctrl-C during the imports. Each ends in one stderr
line naming what was wrong and a non-zero exit status, never a traceback."""

from __future__ import annotations

import errno
import math
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from flexmvm.cli import main as cli_main
from flexmvm.errors import InputError, SolverError

TINY = Path(__file__).parent / "data" / "tiny_impact.toml"
RUN_FAST = ["--t-end", "3e-6", "--no-progress", "--jobs", "1"]


def _in_process(argv, capsys) -> tuple[int, str]:
    """main(argv) in this process (monkeypatches apply); (exit status, stderr)."""
    code = 0
    try:
        cli_main.main([str(a) for a in argv])
    except SystemExit as exc:
        code = exc.code
    return code, capsys.readouterr().err


def _one_line(err: str) -> str:
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return lines[0]


def _tiny_with(tmp_path: Path, old: str, new: str) -> Path:
    text = TINY.read_text(encoding="utf-8")
    assert old in text
    path = tmp_path / "case.toml"
    path.write_text(text.replace(old, new), encoding="utf-8")
    return path


@pytest.mark.parametrize(
    "old, new, key",
    [
        (
            "velocity_mps = [0.21, 0.0, 0.0]",
            "velocity_mps = [1e200, 0.0, 0.0]",
            "bodies[0].placement.velocity_mps",
        ),
        ("gravity_mps2 = [0.0, 0.0, 0.0]", "gravity_mps2 = [0.0, 0.0, -1e308]", "gravity_mps2"),
    ],
)
def test_absurd_motion_is_an_input_error_naming_the_key(tmp_path, capsys, old, new, key):
    """Velocity 1e200 m/s and gravity 1e308 m/s^2 ended in exit 1, 'ValueError: math domain
    error' (expm_so3 of an overflowed rotation); now exit 2 naming the key and the bound."""
    code, err = _in_process(
        [
            "run",
            _tiny_with(tmp_path, old, new),
            *RUN_FAST,
            "--no-fields",
            "--out",
            tmp_path / "out",
        ],
        capsys,
    )
    line = _one_line(err)
    assert code == 2
    assert key in line and "magnitude must be <=" in line


def test_an_overflowed_rotation_is_a_solver_error():
    """What the schema's bounds cannot foresee: a non-finite rotation vector in the step is a
    SolverError (exit 2 from the command), not a math domain error."""
    from flexmvm.bodies.rotation import expm_so3

    for bad in ([math.inf, 0.0, 0.0], [math.nan, 1.0, 0.0]):
        with pytest.raises(SolverError, match="not finite"):
            expm_so3(bad)


def test_dt_longer_than_the_run_is_reported_as_dt():
    """dt_s > t_end_s was reported as a problem of output_dt_s (compared with dt_s first)."""
    from flexmvm.scenarios import scenario_from_dict

    data = tomllib.loads(TINY.read_text(encoding="utf-8"))
    data["time"].update(t_end_s=1e-6, dt_s=2e-6, dt_max_s=2e-6, output_dt_s=1e-6)
    with pytest.raises(InputError, match=r"time\.dt_s: must be <= t_end_s") as exc:
        scenario_from_dict(data)
    assert "output_dt_s" not in str(exc.value)


@pytest.mark.parametrize(
    "message, err_no",
    [
        ("No space left on device", errno.ENOSPC),
        # h5py's own wording: an OSError without errno
        (
            (
                "Can't synchronously write data (file write failed: time = Fri Nov 27 01:00:00 2026, "
                "filename = 'results.h5', file descriptor = 5, errno = 28, error message = 'No space "
                "left on device', buf = 0x5, total write size = 8192, bytes this sub-write = 8192, "
                "bytes actually written = 18446744073709551615, offset = 0)"
            ),
            None,
        ),
    ],
)
def test_full_disk_is_one_line_naming_the_file(tmp_path, capsys, monkeypatch, message, err_no):
    """A full disk while results.h5 is written: exit non-zero (2, an OutputError), one line
    naming the file and 'no space left'; the output directory is not created."""
    from flexmvm.results import output

    def full_disk(path, *args, **kwargs):
        raise OSError(err_no, message) if err_no is not None else OSError(message)

    monkeypatch.setattr(output, "write_results_h5", full_disk)
    out = tmp_path / "out"
    code, err = _in_process(["run", TINY, *RUN_FAST, "--model", "full", "--out", out], capsys)
    line = _one_line(err)
    assert code == 2
    assert "results.h5" in line and "no space left" in line
    assert not out.exists()


INTERRUPTING_IMPORT = """
import sys

class Interrupt:        # Ctrl-C arrives while {module} is being imported
    def find_spec(self, name, path=None, target=None):
        if name == "{module}":
            raise KeyboardInterrupt
        return None

sys.meta_path.insert(0, Interrupt())
from flexmvm.cli.main import main
main(["mesh", "rod"])
"""


@pytest.mark.parametrize("module", ["click", "numpy", "scipy.sparse"])
def test_interrupt_during_the_imports_is_one_line_and_130(module):
    """Ctrl-C while the command imports click (its first import), numpy or scipy printed a
    51-line traceback; now exit 130 and the one interrupt line. Importing the entry point
    itself imports neither click nor numpy (checked below), so nothing before main() can
    take long enough to be interrupted."""
    proc = subprocess.run(
        [sys.executable, "-c", INTERRUPTING_IMPORT.format(module=module)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert proc.returncode == 130, proc.stderr
    assert _one_line(proc.stderr) == cli_main.INTERRUPTED
    probe = subprocess.run(
        [
            sys.executable,
            "-c",
            ("import sys, flexmvm.cli.main; print(sorted({'click', 'numpy'} & set(sys.modules)))"),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    assert probe.stdout.strip() == "[]"
