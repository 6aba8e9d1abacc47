"""The "Where the time goes" block of docs/performance.md, written from one run of step_cost.py.

step_cost.py --write-docs calls :func:`write_page` with the run's result dict (the one it
stores as benchmarks/results/step_cost_<version>.json): the block between this module's two
marker lines is replaced whole (speed_page.write_block, the writer of the Current figures
block), the rest of the page is kept as it is. The block states the machine as the Current
figures do (speed_page.machine_line), the date, and the figures as the run measured them; it
names no code version (the json holds the commit).
"""

from __future__ import annotations

from pathlib import Path

from speed_page import machine_line, wrap, write_block

BEGIN = "<!-- step_cost.py --write-docs: begin (generated: rerun the command, do not edit) -->"
END = "<!-- step_cost.py --write-docs: end -->"

# kernels listed by name on the page (the rest are in the json)
N_KERNELS_SHOWN = 4


def _ms(seconds: float) -> str:
    """A time [s] in ms, 3 significant digits."""
    return f"{seconds * 1e3:.3g} ms"


def _us(steps_s: list[float]) -> str:
    """The step sizes of a run [s] in us ("0.5 us", or "0.25-0.5 us")."""
    us = [f"{1e6 * h:g}" for h in (min(steps_s), max(steps_s))]
    return f"{us[0]} us" if us[0] == us[1] else f"{us[0]}-{us[1]} us"


def _pct(share: float) -> str:
    return f"{100 * share:.0f} %"


def _header(res: dict, command: str) -> list[str]:
    m = res["machine"]
    steps = _us(res["full"]["dt_s"] + res["mvm"]["timed"]["dt_s"])
    text = (
        f"Measured by `{command}` on {m['date_utc']}: {machine_line(m)}. Every number below "
        "is from this one run of the seed case (`scenarios/rod_impact.toml`, contact steps of "
        f"{steps}, the first {res['warm_steps']} steps of each run left out); its record, "
        "with the code version, is `benchmarks/results/step_cost_<version>.json`."
    )
    return wrap(text)


def _full_rows(f: dict, n_solves: int) -> list[tuple[str, str, str]]:
    tf, bs = f["target_factor"], f["back_substitution"]
    dof = " + ".join(f"{d:,}" for d in f["dof"])
    per_rod = ", ".join(f"{name} {n:.2f}" for name, n in f["solves_per_step_by_body"].items())

    def rate(seconds: float) -> str:  # L is read twice per solve (forward and backward)
        return f"{_ms(seconds)} ({2 * tf['values_mb'] / 1e3 / seconds:.3g} GB/s)"

    return [
        (
            f"full FE (coordinates {dof}): one contact step",
            _ms(f["median_step_s"]),
            (
                f"median of {f['n_steps']} steps; both rods' work on a thread each; "
                f"{_ms(f['mean_step_process_cpu_s'])} of CPU time per step (both threads, mean)"
            ),
        ),
        (
            "of it, a back-substitution running on either thread",
            _pct(f["solve_share"]),
            (
                f"{f['solves_per_step']:.2f} back-substitutions per step ({per_rod}), "
                f"{_ms(f['solve_thread_s_per_step'])} of thread time; besides, "
                f"{f['other_solves_per_step']:.2f} small solves with the massless contact nodes' "
                f"stiffness, {_ms(f['other_solve_thread_s_per_step'])}"
            ),
        ),
        (
            "the aluminium rod's factor L",
            f"{tf['values_mb']:.1f} MB",
            (
                f"{tf['nnz'] / 1e6:.2f} M entries of 8 bytes ({tf['total_mb']:.1f} MB with its "
                f"index arrays), {tf['n']:,} rows; read twice per back-substitution"
            ),
        ),
        (
            "one back-substitution with it, one thread",
            rate(bs["one_thread_s"]),
            (
                f"median of {n_solves}, {_ms(bs['one_thread_cpu_s'])} of CPU time; GB/s: twice "
                "the factor over the time"
            ),
        ),
        (
            "the same, its two elimination-tree halves on two threads",
            rate(bs["two_threads_s"]),
            "" if tf["split"] else "the factor is not split in halves: one thread either way",
        ),
        (
            "both rods' back-substitutions, one after the other / at once on two threads",
            f"{_ms(bs['both_rods_serial_s'])} / {_ms(bs['both_rods_parallel_s'])}",
            "what a full-FE step does on two cores",
        ),
    ]


def _mvm_rows(m: dict) -> list[tuple[str, str, str]]:
    dof = " + ".join(f"{d:,}" for d in m["dof"])
    inv = m["striker_invariants"]
    step_ms = 1e3 * m["timed"]["median_step_s"]
    mean_ms = 1e3 * m["timed"]["mean_step_s"]
    kernel_ms = m["kernel_ms_calling_thread"]
    # CPU time of the calling thread: what the split is when other jobs share the cores
    cpu_ms = 1e3 * m["timed"]["mean_step_thread_cpu_s"]
    kernel_cpu_ms = m["kernel_cpu_ms_calling_thread"]
    overhead_ms = 1e3 * m["timer_overhead_s_per_call"] * m["kernel_calls_per_step"]
    shown = list(m["kernels"].items())[:N_KERNELS_SHOWN]
    top = ", ".join(f"`{name}` {r['ms_per_step']:.2f} ms" for name, r in shown)
    others = [
        f"`{name}` {r['ms_per_step_other_threads']:.2f} ms"
        for name, r in m["kernels"].items()
        if r["ms_per_step_other_threads"] > 0.0
    ]
    return [
        (
            f"all MVM (coordinates {dof}): one contact step",
            _ms(m["plain"]["median_step_s"]),
            (
                f"median of {m['plain']['n_steps']} steps, "
                f"{_ms(m['plain']['mean_step_thread_cpu_s'])} of the calling thread's CPU time "
                f"(mean); {step_ms:.3g} ms with a timer around every compiled kernel call (the "
                "run the next three rows split)"
            ),
        ),
        (
            "of it, in compiled (numba) kernels on the calling thread",
            f"{kernel_ms:.3g} ms ({_pct(kernel_ms / mean_ms)})",
            (
                f"CPU time: {kernel_cpu_ms:.3g} of the thread's {cpu_ms:.3g} ms "
                f"({_pct(kernel_cpu_ms / cpu_ms)}); {m['kernel_calls_per_step']:.0f} calls of "
                f"{m['kernels_called']} kernels per step (mean over the steps); the longest: {top}"
            ),
        ),
        (
            "the rest: the Python layer and the numpy/scipy/LAPACK calls it makes",
            f"{mean_ms - kernel_ms:.3g} ms ({_pct(1 - kernel_ms / mean_ms)})",
            (
                f"CPU time: {cpu_ms - kernel_cpu_ms:.3g} ms ({_pct(1 - kernel_cpu_ms / cpu_ms)}); "
                "the step's mean wall minus the kernels'; of it, the timers' own "
                f"{1e6 * m['timer_overhead_s_per_call']:.2g} us per call, "
                f"{overhead_ms:.2g} ms per step"
            ),
        ),
        (
            "compiled kernels on the second thread, beside the calling one",
            f"{m['kernel_ms_other_threads']:.3g} ms",
            ", ".join(others) or "none",
        ),
        (
            "the striker's inertia invariants",
            f"{inv['stored_mb']:.1f} MB",
            (
                f"{inv['nq']} elastic coordinates; "
                f"one G2 contraction per step reads {inv['g2_read_mb']:.1f} MB of them"
            ),
        ),
    ]


def render_block(res: dict, command: str) -> str:
    """The generated block (marker lines included) from step_cost.py's result dict ``res``
    and the ``command`` that made it. Raises KeyError when ``res`` lacks a figure every run
    measures."""
    rows = _full_rows(res["full"], res["n_solves"]) + _mvm_rows(res["mvm"])
    table = [
        "| quantity | value | details |",
        "|---|---|---|",
        *(f"| {' | '.join(row)} |" for row in rows),
    ]
    return "\n".join([BEGIN, *_header(res, command), "", *table, END]) + "\n"


def write_page(path: Path, res: dict, command: str) -> None:
    """Rewrite the "Where the time goes" block of ``path`` (docs/performance.md) from
    ``res``; the rest of the page is kept byte for byte. Raises InputError (flexmvm.errors)
    unless the page holds the block's marker lines once each, in order."""
    write_block(path, render_block(res, command), BEGIN, END)
