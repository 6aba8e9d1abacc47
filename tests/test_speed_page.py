"""The writer of docs/performance.md's "Current figures" block (benchmarks/speed_page.py),
on a result dict of bench_speed.py made up for the test: the ratios are those of the walls
of the same run, the absolute times are shown as measured, the machine is stated, no code
version reaches the page, and the text around the block is kept byte for byte. Checked as
exact strings: the writer formats numbers, it computes nothing that could round differently
(ratios to 3 significant digits, times to 0.01 s below 10 s and 0.1 s above). Cost: 2.4 s
of CPU for the whole file, 5.6-7.4 s of wall at load 20 (mostly imports).
"""

from __future__ import annotations

import copy
import importlib.util
import re
from pathlib import Path

import pytest

from flexmvm.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("speed_page", ROOT / "benchmarks" / "speed_page.py")
speed_page = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(speed_page)

COMMAND = "python benchmarks/bench_speed.py --main-job --write-docs"


def _sim(wall: float, n_steps: int, dof: list[int], build: float) -> dict:
    return {
        "wall_s": wall,
        "n_steps": n_steps,
        "ms_per_step": 1e3 * wall / n_steps,
        "dof": dof,
        "build_s": build,
    }


RES = {
    "commit": "abc1234",
    "t_end_s": 2e-3,
    "machine": {
        "cpu": "Test CPU 9000, x86_64, 2 cores",
        "memory_gib": 23.44,
        "load_avg_start": 0.42,
        "load_avg_end": 1.96,
        "date_utc": "2026-11-27 08:00 UTC",
        "versions": {"python": "3.12.3", "numpy": "2.1.0", "scipy": "1.14.1", "numba": "0.60.0"},
    },
    "kernel_compile_s": 84.0,
    "seed_runs": {
        "all_mvm": _sim(5.83, 1991, [559, 118], 8.2),
        "full": _sim(59.9, 1994, [25773, 25047], 1.84),
        "shipped": _sim(40.2, 1992, [25773, 118], 0.42),
    },
    "all_mvm_command_first_s": 19.7,
    "all_mvm_command_second_s": 11.3,
    "basis_s": 3.47,
    "nq": 118,
    "main_job_s": 101.5,
    "main_job_runs": {"shipped_wall_s": 49.1, "full_wall_s": 80.2},
}


def _row(block: str, label: str) -> str:
    rows = [line for line in block.splitlines() if line.startswith(f"| {label}")]
    assert len(rows) == 1, (label, rows)
    return rows[0]


def test_ratios_are_those_of_the_runs_walls():
    """59.9 / 5.83 = 10.27, 59.9 / 40.2 = 1.490, 40.2 / 5.83 = 6.895, 19.7 / 11.3 = 1.743,
    80.2 / 49.1 = 1.633: shown to 3 significant digits."""
    block = speed_page.render_block(RES, COMMAND)
    assert _row(block, "full FE / both rods MVM").endswith("| 10.3 |")
    assert "over 2 ms" in _row(block, "full FE / both rods MVM")
    assert _row(block, "full FE / the scenario as shipped").endswith("| 1.49 |")
    assert _row(block, "the scenario as shipped / both rods MVM").endswith("| 6.9 |")
    assert _row(block, "the all-MVM command end to end").endswith("| 1.74 |")
    assert _row(block, "inside the main job").endswith("| 1.63 |")


def test_absolute_times_machine_and_no_code_version():
    block = speed_page.render_block(RES, COMMAND)
    assert "| 5.83 s | 1,991 steps, 2.93 ms per step; coordinates 559 + 118; setup 8.20 s |" in (
        _row(block, "both rods MVM")
    )
    assert "| 59.9 s |" in _row(block, "full-FE reference")
    assert "| 101.5 s |" in _row(block, "main job")
    assert "shipped model 49.1 s and the full-FE reference 80.2 s" in _row(block, "main job")
    assert "| 84.0 s | first process" in _row(block, "numba kernels")
    first = " ".join(block.split("\n\n")[0].splitlines()[1:])  # the paragraph, unwrapped
    for fact in (COMMAND, "2026-11-27 08:00 UTC", "Test CPU 9000, x86_64, 2 cores", "23.4 GiB"):
        assert fact in first
    assert "load average 0.4 at the start, 2.0 at the end" in first
    assert "numba 0.60.0" in first
    assert "--quick" not in first
    # the commit is in the json, never on the page (no 7-40 hex-digit word at all)
    assert RES["commit"] not in block
    assert not re.search(r"\b[0-9a-f]{7,40}\b", block)


def test_optional_rows_and_quick_run():
    """Without --main-job its rows are left out; a 0.4 ms run says it is not the record;
    a kernel 'compile time' near zero says the kernels were on disk already."""
    res = copy.deepcopy(RES)
    del res["main_job_s"], res["main_job_runs"]
    res["t_end_s"] = 4e-4
    res["kernel_compile_s"] = -0.003
    block = speed_page.render_block(res, "python benchmarks/bench_speed.py --quick --write-docs")
    assert "main job" not in block
    assert "`--quick`: 0.4 ms of simulation instead of 2 ms" in " ".join(block.splitlines())
    assert "over 0.4 ms" in _row(block, "full FE / both rods MVM")
    assert "none measured" in _row(block, "numba kernels")
    with pytest.raises(KeyError):
        speed_page.render_block({k: v for k, v in RES.items() if k != "basis_s"}, COMMAND)


def test_block_replaced_rest_kept():
    before = "# Performance\n\nprose, kept\n\n"
    after = "\nmore prose\n"
    page = before + f"{speed_page.BEGIN}\nold table\n{speed_page.END}\n" + after
    block = speed_page.render_block(RES, COMMAND)
    new = speed_page.replace_block(page, block)
    assert new == before + block + after
    assert speed_page.replace_block(new, block) == new  # a rerun with the same figures


@pytest.mark.parametrize(
    "page",
    [
        "no markers\n",
        f"{speed_page.BEGIN}\nonly the first\n",
        f"{speed_page.END}\nreversed\n{speed_page.BEGIN}\n",
        f"{speed_page.BEGIN}\n{speed_page.END}\n{speed_page.BEGIN}\n{speed_page.END}\n",
    ],
)
def test_markers_checked(page):
    with pytest.raises(InputError, match="expected one line"):
        speed_page.replace_block(page, "x\n")


def test_the_page_has_its_block(tmp_path):
    """docs/performance.md carries one block, so --write-docs can write it; written into a
    copy, only the block changes."""
    page = (ROOT / "docs" / "performance.md").read_text(encoding="utf-8")
    copy_path = tmp_path / "performance.md"
    copy_path.write_text(page, encoding="utf-8")
    speed_page.write_page(copy_path, RES, COMMAND)
    new = copy_path.read_text(encoding="utf-8")
    head = page.split(speed_page.BEGIN)[0]
    tail = page.split(speed_page.END)[1]
    assert new == head + speed_page.render_block(RES, COMMAND) + tail[1:]


def test_machine_facts():
    m = speed_page.machine_facts()
    assert re.search(r"\b\d+ cores$", m["cpu"])
    assert re.fullmatch(r"\d{4}-\d\d-\d\d \d\d:\d\d UTC", m["date_utc"])
    assert set(m["versions"]) == {"python", "numpy", "scipy", "numba"}
