"""The "Current figures" block of docs/performance.md, written from one run of bench_speed.py.

bench_speed.py --write-docs calls :func:`write_page` with the run's result dict (the one it
stores as benchmarks/results/speed_<version>.json): the block between the two marker lines
is replaced whole, the page's hand-written text around it is kept as it is. The block states
the machine (CPU model, cores, memory, load average), the date, the ratios of wall times
measured side by side in that run and the absolute times as the run measured them. It names
no code version: the run's json holds the commit (the page must not go stale with the next
commit, and the version is provenance, not something a reader needs to use the numbers).
"""

from __future__ import annotations

import datetime as _dt
import os
import platform
import sys
import textwrap
from importlib import metadata
from pathlib import Path

from flexmvm.errors import InputError
from flexmvm.results.atomic import write_text_atomic

BEGIN = "<!-- bench_speed.py --write-docs: begin (generated: rerun the command, do not edit) -->"
END = "<!-- bench_speed.py --write-docs: end -->"

# a kernel "compile time" below this is the first process's start-up noise: the kernels were
# already on disk (numba cache=True) from an earlier process of the same source tree
_COMPILED_ALREADY_S = 0.5


def machine_facts() -> dict:
    """What the page says of the machine and the software, measured now: CPU model,
    architecture and cores (tools.validation.suite.machine), physical memory [GiB], the
    1-min load average (other jobs on a shared machine), the UTC date and the versions of
    Python, numpy, scipy and numba."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository's tools/
    from tools.validation.suite import machine

    try:
        memory_gib = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") / 2**30
    except (AttributeError, OSError, ValueError):
        memory_gib = None
    versions = {"python": platform.python_version()}
    for name in ("numpy", "scipy", "numba"):
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return {
        "cpu": machine(),
        "memory_gib": memory_gib,
        "load_avg_start": load_average(),
        "date_utc": _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "versions": versions,
    }


def load_average() -> float | None:
    """The 1-min load average (None where the platform has none)."""
    try:
        return os.getloadavg()[0]
    except (AttributeError, OSError):
        return None


def _s(x: float) -> str:
    """A wall time [s] as the table shows it: 3 significant digits, at least 0.1 s."""
    return f"{x:.1f} s" if abs(x) >= 10 else f"{x:.2f} s"


def _ratio(a: float, b: float) -> str:
    return f"{a / b:.3g}"


def _dof(dof: list[int]) -> str:
    return " + ".join(f"{d:,}" for d in dof)


def _table(head: tuple[str, ...], rows: list[tuple[str, ...]]) -> list[str]:
    """A Markdown table's lines."""
    return [
        f"| {' | '.join(head)} |",
        "|" + "---|" * len(head),
        *(f"| {' | '.join(row)} |" for row in rows),
    ]


def _sim_row(label: str, r: dict) -> tuple[str, str, str]:
    detail = (
        f"{r['n_steps']:,} steps, {r['ms_per_step']:.2f} ms per step; coordinates "
        f"{_dof(r['dof'])}; setup {_s(r['build_s'])}"
    )
    return (label, _s(r["wall_s"]), detail)


def machine_line(m: dict) -> str:
    """What a generated block says of the machine, from machine_facts() with the run's
    ``load_avg_end``: "<cpu>, <memory> GiB of memory; 1-min load average <start> at the
    start, <end> at the end; Python <v>, numpy <v>, scipy <v>, numba <v>"."""
    parts = [m["cpu"]]
    if m.get("memory_gib") is not None:
        parts.append(f"{m['memory_gib']:.1f} GiB of memory")
    loads = [m.get("load_avg_start"), m.get("load_avg_end")]
    load = ""
    if None not in loads:
        load = f"; 1-min load average {loads[0]:.1f} at the start, {loads[1]:.1f} at the end"
    v = m["versions"]
    return (
        f"{', '.join(parts)}{load}; Python {v['python']}, numpy {v['numpy']}, scipy "
        f"{v['scipy']}, numba {v['numba']}"
    )


def wrap(text: str) -> list[str]:
    """A generated paragraph's lines, wrapped as the hand-written pages are (a code span may
    break: Markdown reads a space)."""
    return textwrap.wrap(text, 100, break_long_words=False, break_on_hyphens=False)


def _header(res: dict, command: str) -> list[str]:
    m = res["machine"]
    text = (
        f"Measured by `{command}` on {m['date_utc']}: {machine_line(m)}. Every "
        "number below is from this one run; its record, with the code version, is "
        "`benchmarks/results/speed_<version>.json`."
    )
    if res["t_end_s"] < 2e-3:
        window = f"{res['t_end_s'] * 1e3:g} ms"
        text += f" `--quick`: {window} of simulation instead of 2 ms, a look, not the record."
    return wrap(text)


def _ratios(res: dict) -> list[str]:
    s = res["seed_runs"]
    walls = {k: s[k]["wall_s"] for k in ("all_mvm", "full", "shipped")}
    window = f"{res['t_end_s'] * 1e3:g} ms"
    cmd = (res["all_mvm_command_first_s"], res["all_mvm_command_second_s"])
    rows = [
        (
            f"full FE / both rods MVM, simulation walls over {window}",
            _ratio(walls["full"], walls["all_mvm"]),
        ),
        (
            "full FE / the scenario as shipped (b1 full FE, b2 MVM)",
            _ratio(walls["full"], walls["shipped"]),
        ),
        ("the scenario as shipped / both rods MVM", _ratio(walls["shipped"], walls["all_mvm"])),
        (
            "the all-MVM command end to end, first run (empty setup cache) / second run",
            _ratio(*cmd),
        ),
    ]
    if "main_job_runs" in res:
        mj = res["main_job_runs"]
        label = "inside the main job, side by side on the two cores: full-FE reference / shipped"
        rows.append((label, _ratio(mj["full_wall_s"], mj["shipped_wall_s"])))
    return [
        "Side by side in this run (each a ratio of two wall times measured in it):",
        "",
        *_table(("ratio", "value"), rows),
    ]


def _times(res: dict) -> list[str]:
    s = res["seed_runs"]
    window = f"{res['t_end_s'] * 1e3:g} ms"
    command = "`flexmvm run scenarios/rod_impact.toml --model mvm --no-fields`, first run"
    rows = [
        _sim_row(f"both rods MVM (the scenario's selections), {window} simulated", s["all_mvm"]),
        _sim_row(f"the scenario as shipped (b1 full FE, b2 MVM), {window}", s["shipped"]),
        _sim_row(f"full-FE reference (both rods full FE), {window}", s["full"]),
        (command, _s(res["all_mvm_command_first_s"]), "end to end, empty setup cache"),
        ("the same, second run", _s(res["all_mvm_command_second_s"]), "setup cached"),
        (
            "one Craig-Bampton basis (b2, 1-3 + 43 modes), built cold",
            _s(res["basis_s"]),
            f"{res['nq']} elastic coordinates, no disk cache",
        ),
    ]
    if "main_job_s" in res:
        detail = "end to end, empty setup cache"
        if "main_job_runs" in res:
            mj = res["main_job_runs"]
            detail += (
                f"; inside it the shipped model {_s(mj['shipped_wall_s'])} and the full-FE "
                f"reference {_s(mj['full_wall_s'])}, side by side"
            )
        label = "main job, `flexmvm run scenarios/rod_impact.toml`"
        rows.append((label, _s(res["main_job_s"]), detail))
    compile_s = res["kernel_compile_s"]
    note = (
        "first process on this source tree minus the second"
        if compile_s >= _COMPILED_ALREADY_S
        else "none measured: an earlier process had compiled them to disk"
    )
    rows.append(("numba kernels, compilation", _s(compile_s), note))
    return [
        "Absolute wall times of this run:",
        "",
        *_table(("quantity", "wall time", "details"), rows),
    ]


def render_block(res: dict, command: str) -> str:
    """The generated block (marker lines included) from bench_speed.py's result dict ``res``
    and the ``command`` that made it. Raises KeyError when ``res`` lacks a figure every run
    measures (seed_runs, the two command runs, basis_s, kernel_compile_s, machine)."""
    lines = [BEGIN, *_header(res, command), "", *_ratios(res), "", *_times(res), END]
    return "\n".join(lines) + "\n"


def replace_block(page: str, block: str, begin: str = BEGIN, end: str = END) -> str:
    """``page`` with the text from its ``begin`` line to its ``end`` line (default: this
    block's markers) replaced by ``block``. Raises InputError unless the page has exactly one
    of each, ``begin`` first."""
    lines = page.splitlines(keepends=True)
    begins = [i for i, line in enumerate(lines) if line.strip() == begin]
    ends = [i for i, line in enumerate(lines) if line.strip() == end]
    if len(begins) != 1 or len(ends) != 1 or begins[0] > ends[0]:
        raise InputError(
            f"expected one line {begin!r} and, after it, one line {end!r}; found "
            f"{len(begins)} and {len(ends)}"
        )
    return "".join(lines[: begins[0]]) + block + "".join(lines[ends[0] + 1 :])


def write_block(path: Path, block: str, begin: str = BEGIN, end: str = END) -> None:
    """Replace the marked block of the page ``path`` by ``block`` (replace_block); the rest
    of the page is kept byte for byte. Raises InputError as replace_block, naming the page."""
    page = path.read_text(encoding="utf-8")
    try:
        text = replace_block(page, block, begin, end)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    write_text_atomic(path, text)


def write_page(path: Path, res: dict, command: str) -> None:
    """Rewrite the generated block of ``path`` (docs/performance.md) from ``res``; the rest of
    the page is kept byte for byte. Raises InputError as replace_block."""
    write_block(path, render_block(res, command))
