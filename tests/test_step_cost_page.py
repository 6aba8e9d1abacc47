"""The writer of docs/performance.md's "Where the time goes" block (benchmarks/step_cost_page.py),
on a result dict of step_cost.py made up for the test: the figures are shown as measured, the
derived ones (GB/s, shares, the rest of a step) are those of the dict's own numbers, the machine
is stated as the Current figures state it, no code version reaches the page, and the rest of
the page (the Current figures block included) is kept byte for byte. Checked as exact strings:
the writer formats numbers (3 significant digits), it computes nothing that could round
differently. Cost: about 1 s of CPU for the file (imports; nothing is simulated or timed).
"""

from __future__ import annotations

import copy
import importlib.util
import re
import sys
from pathlib import Path

import pytest

from flexmvm.errors import InputError

ROOT = Path(__file__).resolve().parents[1]


def _load(name: str):
    """A module of benchmarks/ by its path, registered under its name (step_cost_page imports
    speed_page by name, as it does when run from benchmarks/)."""
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    module = sys.modules[name] = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


speed_page = _load("speed_page")
page_writer = _load("step_cost_page")

COMMAND = "python benchmarks/step_cost.py --write-docs"


def _factor(n: int, nnz: int, total_mb: float, split: bool) -> dict:
    return {
        "n": n,
        "nnz": nnz,
        "values_mb": 8 * nnz / 1e6,
        "total_mb": total_mb,
        "n_supernodes": 1900,
        "split": split,
    }


def _kernel(ms: float, calls: float, other: float = 0.0) -> dict:
    return {"ms_per_step": ms, "calls_per_step": calls, "ms_per_step_other_threads": other}


RES = {
    "commit": "abc1234",
    "warm_steps": 20,
    "n_solves": 30,
    "machine": {
        "cpu": "Test CPU 9000, x86_64, 2 cores",
        "memory_gib": 23.44,
        "load_avg_start": 0.42,
        "load_avg_end": 1.96,
        "date_utc": "2026-11-27 10:00 UTC",
        "versions": {"python": "3.12.3", "numpy": "2.1.0", "scipy": "1.14.1", "numba": "0.60.0"},
    },
    "full": {
        "n_steps": 80,
        "dt_s": [5e-7],
        "median_step_s": 0.0281,
        "mean_step_s": 0.0290,
        "mean_step_process_cpu_s": 0.0412,
        "dof": [25773, 25047],
        "solves_per_step": 2.16,
        "solves_per_step_by_body": {"b1": 1.09, "b2": 1.07},
        "solve_thread_s_per_step": 0.0302,
        "solve_share": 0.7134,
        "other_solves_per_step": 4.0,
        "other_solve_thread_s_per_step": 0.000213,
        "target_factor": _factor(25041, 12_600_000, 104.37, True),
        "striker_factor": _factor(25767, 13_000_000, 108.0, True),
        "back_substitution": {
            "one_thread_s": 0.0090,
            "one_thread_cpu_s": 0.0088,
            "two_threads_s": 0.0070,
            "both_rods_serial_s": 0.0185,
            "both_rods_parallel_s": 0.0101,
        },
    },
    "mvm": {
        "plain": {
            "n_steps": 380,
            "dt_s": [5e-7],
            "median_step_s": 0.00305,
            "mean_step_s": 0.0031,
            "mean_step_thread_cpu_s": 0.0029,
        },
        "timed": {
            "n_steps": 380,
            "dt_s": [5e-7],
            "median_step_s": 0.00312,
            "mean_step_s": 0.0032,
            "mean_step_thread_cpu_s": 0.0030,
        },
        "dof": [599, 118],
        "kernel_ms_calling_thread": 1.25,
        "kernel_ms_other_threads": 0.25,
        "kernel_cpu_ms_calling_thread": 1.2,
        "kernels_called": 14,
        "kernel_calls_per_step": 31.4,
        "timer_overhead_s_per_call": 1.7e-6,
        "kernels": {
            "_contract_diagonal": _kernel(0.31, 1.0),
            "penetration_scan": _kernel(0.3, 2.0),
            "_contract_rest": _kernel(0.25, 1.0, 0.25),
            "momentum_terms": _kernel(0.2, 6.0),
            "scan_nodes": _kernel(0.1, 1.0),
        },
        "striker_invariants": {"nq": 593, "stored_mb": 25.46, "g2_read_mb": 12.66, "packed": True},
    },
}


def _row(block: str, label: str) -> str:
    rows = [line for line in block.splitlines() if line.startswith(f"| {label}")]
    assert len(rows) == 1, (label, rows)
    return rows[0]


def test_full_fe_rows():
    """GB/s = 2 x 100.8 MB / 9.0 ms = 22.4 (one thread), / 7.0 ms = 28.8 (two threads)."""
    block = page_writer.render_block(RES, COMMAND)
    step = _row(block, "full FE (coordinates 25,773 + 25,047): one contact step")
    assert "| 28.1 ms | median of 80 steps;" in step
    assert "41.2 ms of CPU time per step (both threads, mean)" in step
    share = _row(block, "of it, a back-substitution running")
    assert (
        "| 71 % | 2.16 back-substitutions per step (b1 1.09, b2 1.07), 30.2 ms of thread" in share
    )
    assert "besides, 4.00 small solves with the massless contact nodes' stiffness, 0.213 ms |" in (
        share
    )
    factor = _row(block, "the aluminium rod's factor L")
    assert "| 100.8 MB | 12.60 M entries of 8 bytes (104.4 MB with its index arrays)" in factor
    assert "25,041 rows" in factor
    assert "| 9 ms (22.4 GB/s) | median of 30, 8.8 ms of CPU time;" in _row(
        block, "one back-substitution"
    )
    halves = _row(block, "the same, its two elimination-tree halves")
    assert halves.endswith("| 7 ms (28.8 GB/s) |  |")
    assert "| 18.5 ms / 10.1 ms |" in _row(block, "both rods' back-substitutions")


def test_all_mvm_rows():
    """1.25 ms of kernels in a 3.2 ms mean step: 39 %, the rest 1.95 ms (61 %); CPU time of
    the calling thread 1.2 of 3.0 ms: 40 %, the rest 1.8 ms (60 %); the timers' 1.7 us x
    31.4 calls = 0.053 ms per step."""
    block = page_writer.render_block(RES, COMMAND)
    step = _row(block, "all MVM (coordinates 599 + 118): one contact step")
    assert (
        "| 3.05 ms | median of 380 steps, 2.9 ms of the calling thread's CPU time (mean);" in step
    )
    assert "3.12 ms with a timer" in step
    kernels = _row(block, "of it, in compiled (numba) kernels on the calling thread")
    assert "| 1.25 ms (39 %) | CPU time: 1.2 of the thread's 3 ms (40 %); 31 calls of 14" in kernels
    # the four longest by name, in the dict's order (step_cost.py sorts them)
    assert "`_contract_diagonal` 0.31 ms, `penetration_scan` 0.30 ms, `_contract_rest` 0.25 ms" in (
        kernels
    )
    assert "`momentum_terms` 0.20 ms |" in kernels
    assert "scan_nodes" not in kernels
    rest = _row(block, "the rest: the Python layer")
    assert "| 1.95 ms (61 %) | CPU time: 1.8 ms (60 %);" in rest
    assert "the timers' own 1.7 us per call, 0.053 ms per step" in rest
    assert _row(block, "compiled kernels on the second thread").endswith(
        "| 0.25 ms | `_contract_rest` 0.25 ms |"
    )
    inv = _row(block, "the striker's inertia invariants")
    assert "| 25.5 MB | 593 elastic coordinates; one G2 contraction per step reads 12.7 MB" in inv


def test_header_machine_and_no_code_version():
    block = page_writer.render_block(RES, COMMAND)
    first = " ".join(block.split("\n\n")[0].splitlines()[1:])  # the paragraph, unwrapped
    assert first.startswith(f"Measured by `{COMMAND}` on 2026-11-27 10:00 UTC: ")
    # the machine as the Current figures block states it
    assert speed_page.machine_line(RES["machine"]) in first
    assert "23.4 GiB of memory; 1-min load average 0.4 at the start, 2.0 at the end" in first
    assert "contact steps of 0.5 us, the first 20 steps of each run left out" in first
    assert RES["commit"] not in block
    assert not re.search(r"\b[0-9a-f]{7,40}\b", block)


def test_unsplit_factor_and_missing_figure():
    res = copy.deepcopy(RES)
    res["full"]["target_factor"]["split"] = False
    block = page_writer.render_block(res, COMMAND)
    assert "not split in halves" in _row(block, "the same, its two elimination-tree halves")
    del res["mvm"]["striker_invariants"]
    with pytest.raises(KeyError):
        page_writer.render_block(res, COMMAND)


def test_the_page_has_both_blocks(tmp_path):
    """docs/performance.md carries this block and the Current figures block; written into a
    copy, only this block changes, and the Current figures writer still finds its own."""
    page = (ROOT / "docs" / "performance.md").read_text(encoding="utf-8")
    path = tmp_path / "performance.md"
    path.write_text(page, encoding="utf-8")
    page_writer.write_page(path, RES, COMMAND)
    new = path.read_text(encoding="utf-8")
    head = page.split(page_writer.BEGIN)[0]
    tail = page.split(page_writer.END)[1]
    assert new == head + page_writer.render_block(RES, COMMAND) + tail[1:]
    assert speed_page.BEGIN in head and speed_page.END in head  # the other block, untouched
    speed_block = f"{speed_page.BEGIN}\nx\n{speed_page.END}\n"
    again = speed_page.replace_block(new, speed_block)
    assert page_writer.render_block(RES, COMMAND) in again


def test_markers_checked(tmp_path):
    path = tmp_path / "performance.md"
    path.write_text(f"{speed_page.BEGIN}\nonly the other block\n{speed_page.END}\n")
    with pytest.raises(InputError, match="expected one line .*step_cost.py"):
        page_writer.write_page(path, RES, COMMAND)
