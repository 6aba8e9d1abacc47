"""Where the time of a contact step goes, on the seed case (issue 38), measured in one run.

    python benchmarks/step_cost.py [--write-docs] [--out benchmarks/results]

The seed case (scenarios/rod_impact.toml) with the models of the "Current figures"
(bench_speed.py): both rods full FE, and both rods MVM (b1 3-5 + 80 modes, b2 1-3 + 37).

Full FE: a short run (FULL_T_END_S, contact from t = 0) with a timer around every
back-substitution (fe.solvers.ldl.SupernodalLDL.solve); the steps after WARM_STEPS give the
wall of a contact step and the share of it during which a back-substitution runs on either
thread (the union of the solves' intervals over the steps' wall). Then, on the aluminium
rod's factor as the run made it: its size, and one back-substitution (median of N_SOLVES, a
random right-hand side) on one thread and with its two elimination-tree halves on two; and
both rods' back-substitutions at once on two threads against one after the other (what a
step does on two cores).

All MVM: the same run twice (MVM_T_END_S): once as it is (the wall of a contact step) and
once with a timer around every call of a compiled (numba) kernel from Python (the split:
time inside kernels on the calling thread, the rest of the step there, kernels run on the
other thread in parallel), plus the striker's inertia invariants (stored size, elastic
coordinates, what one G2 contraction reads). Nested kernels are inside their caller's time;
the rest is the Python layer and the numpy/scipy/LAPACK calls it makes.

Prints a table and writes step_cost_<commit>.json; with --write-docs it rewrites the "Where
the time goes" block of docs/performance.md (step_cost_page.py: the machine stated as the
Current figures state it, no code version on the page).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from speed_page import load_average, machine_facts
from step_cost_page import write_page

from flexmvm.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "rod_impact.toml"
FULL_T_END_S = 50e-6  # 100 contact steps of 0.5 us: ~3 s of stepping at ~30 ms a step
MVM_T_END_S = 200e-6  # 400 contact steps: ~1.5 s (the contact lasts ~0.6 ms, 2 L / c of b1)
WARM_STEPS = 20  # steps left out of the figures: factorizations, first contact columns,
# kernels loaded from the disk cache on their first call
N_SOLVES = 30  # back-substitutions timed for each median
STRIKER, TARGET = "b1", "b2"  # the brass striker, the aluminium rod


def _built(model: str, t_end: float, scenario: Path):
    from flexmvm.assembly.build import build_scenario
    from flexmvm.scenarios import load_scenario

    sc = load_scenario(scenario).with_overrides(model=model, t_end_s=t_end, dt_s=None)
    return build_scenario(sc)


def _run(built, clock: _KernelClock | None = None, marks: list | None = None):
    """simulate ``built``: (the end of every accepted step as (wall, the calling thread's CPU
    time, the process's CPU time) [s], the steps' (h [s], contact active), the integrator);
    with a clock, its totals at the end of every step go to ``marks``."""
    from flexmvm.integrate.driver import moreau_jean, simulate

    made, stamps, steps = [], [], []

    def make(system, grid):
        made.append(moreau_jean()(system, grid))
        return made[-1]

    def on_step(step) -> None:
        stamps.append((time.perf_counter(), time.thread_time(), time.process_time()))
        if clock is not None:
            marks.append(clock.snapshot())
        steps.append((step.h_s, bool(np.any(step.result.contact_impulses > 0.0))))

    simulate(built.system, built.states, built.grid, built.probes, integrator=make, on_step=on_step)
    return stamps, steps, made[0]


def _window(stamps: list, steps: list) -> dict:
    """The steps after WARM_STEPS: their count, how many had contact, their sizes, the wall
    from the end of step WARM_STEPS - 1 to the last, the median and mean step [s], and the
    mean CPU time per step of the calling thread and of the process (all threads) [s]."""
    if len(stamps) < WARM_STEPS + 10:
        raise InputError(f"step_cost: {len(stamps)} steps, need at least {WARM_STEPS + 10}")
    walls, thread_cpu, process_cpu = np.diff(np.array(stamps[WARM_STEPS - 1 :]), axis=0).T
    kept = steps[WARM_STEPS:]
    return {
        "n_steps": len(walls),
        "n_contact_steps": sum(c for _, c in kept),
        "dt_s": sorted({h for h, _ in kept}),
        "t0": stamps[WARM_STEPS - 1][0],
        "t1": stamps[-1][0],
        "mean_step_s": float(walls.mean()),
        "median_step_s": float(np.median(walls)),
        "mean_step_thread_cpu_s": float(thread_cpu.mean()),
        "mean_step_process_cpu_s": float(process_cpu.mean()),
    }


class _SolveLog:
    """A timer around every SupernodalLDL.solve (any thread) while active: (start, end,
    thread, id of the factor) of each."""

    def __enter__(self):
        from flexmvm.fe.solvers.ldl import SupernodalLDL

        self.cls, self.orig = SupernodalLDL, SupernodalLDL.solve
        self.calls: list[tuple[float, float, int, int]] = []
        orig, calls = self.orig, self.calls

        def solve(ldl, b):
            t0 = time.perf_counter()
            try:
                return orig(ldl, b)
            finally:
                calls.append((t0, time.perf_counter(), threading.get_ident(), id(ldl)))

        self.cls.solve = solve
        return self

    def __exit__(self, *exc):
        self.cls.solve = self.orig


def _union(intervals: list[tuple[float, float]], t0: float, t1: float) -> float:
    """Length [s] of the union of the intervals, clipped to [t0, t1]."""
    total, end = 0.0, t0
    for a, b in sorted((max(a, t0), min(b, t1)) for a, b in intervals):
        if b > end:
            total += b - max(a, end)
            end = b
    return total


def _median_s(fn, n: int = N_SOLVES, cpu: bool = False) -> float:
    """The median wall of n calls of fn [s] (cpu: of the calling thread's CPU time)."""
    clock = time.thread_time if cpu else time.perf_counter
    for _ in range(3):  # warm: pages of the factor, threads started
        fn()
    times = []
    for _ in range(n):
        t0 = clock()
        fn()
        times.append(clock() - t0)
    return float(np.median(times))


def _factor_bytes(ldl) -> dict:
    """The packed L of a SupernodalLDL: its entries (nnz, 8 bytes each) and every array of
    the factor (with the row indices and offsets of its supernodes) and the pivots."""
    arrays = [a for a in ldl._factor if isinstance(a, np.ndarray)] + [ldl._d, ldl._perm]
    return {
        "n": int(ldl.n),
        "nnz": int(ldl.nnz),
        "values_mb": 8 * ldl.nnz / 1e6,
        "total_mb": sum(a.nbytes for a in arrays) / 1e6,
        "n_supernodes": int(ldl.n_supernodes),
        "split": bool(ldl.split),
    }


def _back_substitutions(target, striker) -> dict:
    """One back-substitution with the target's factor on one thread and on two (its etree
    halves), and both rods' at once on two threads against one after the other [s]."""
    rng = np.random.default_rng(1)
    bt, bs = rng.standard_normal(target.n), rng.standard_normal(striker.n)
    pools = (target.pool, striker.pool)
    try:
        target.pool = striker.pool = None
        one = _median_s(lambda: target.solve(bt))
        one_cpu = _median_s(lambda: target.solve(bt), cpu=True)
        serial = _median_s(lambda: (target.solve(bt), striker.solve(bs)))
        with ThreadPoolExecutor(max_workers=1) as pool:
            both = _median_s(lambda: (pool.submit(striker.solve, bs), target.solve(bt))[0].result())
            target.pool = pool
            two = _median_s(lambda: target.solve(bt))
    finally:
        target.pool, striker.pool = pools
    return {
        "one_thread_s": one,
        "one_thread_cpu_s": one_cpu,
        "two_threads_s": two,
        "both_rods_serial_s": serial,
        "both_rods_parallel_s": both,
    }


def _factors(integ) -> list[object]:
    """Per body of the run, the factor its step solved with (the last one made: one step
    size through the contact). Read from the body solvers' caches
    (integrate.moreau_jean.body_solver), which have no public accessor: this is a measurement, not a
    use."""
    out = []
    for solver in integ.solvers:
        made = [f.solve.__self__ for f in solver._cache.values()]
        out.append(made[-1] if made else None)
    return out


def measure_full(scenario: Path) -> dict:
    """The full-FE figures (module docstring)."""
    built = _built("full", FULL_T_END_S, scenario)
    with _SolveLog() as log:
        stamps, steps, integ = _run(built)
    w = _window(stamps, steps)
    t0, t1 = w["t0"], w["t1"]
    names = [b.name for b in built.system.bodies]
    factors = dict(zip(names, _factors(integ), strict=True))
    if any(not hasattr(factors.get(name), "nnz") for name in (STRIKER, TARGET)):
        raise InputError(
            "step_cost: the rods were not solved by fe.solvers.ldl (FLEXMVM_CHOLESKY?)"
        )
    target, striker = factors[TARGET], factors[STRIKER]
    rods = {id(f) for f in factors.values()}
    # the rods' W; other sparse solves of the step (the massless contact nodes' K_ss,
    # integrate.moreau_jean.massless) are counted apart
    inside = {True: [], False: []}
    for a, b, _, i in log.calls:
        if b > t0 and a < t1:
            inside[i in rods].append((max(a, t0), min(b, t1)))
    started = [i for a, _, _, i in log.calls if t0 <= a < t1]
    n = w["n_steps"]
    return {
        **{k: v for k, v in w.items() if k not in ("t0", "t1")},
        "bodies": names,
        "dof": [6 + b.nq for b in built.system.bodies],
        "solves_per_step_by_body": {
            name: sum(i == id(f) for i in started) / n for name, f in factors.items()
        },
        "solves_per_step": sum(i in rods for i in started) / n,
        "solve_thread_s_per_step": sum(b - a for a, b in inside[True]) / n,
        "solve_share": _union(inside[True], t0, t1) / (t1 - t0),
        "other_solves_per_step": sum(i not in rods for i in started) / n,
        "other_solve_thread_s_per_step": sum(b - a for a, b in inside[False]) / n,
        "threads": len({t for _, _, t, _ in log.calls}),
        "target_factor": _factor_bytes(target),
        "striker_factor": _factor_bytes(striker),
        "back_substitution": _back_substitutions(target, striker),
        "n_factorizations": integ.n_factorizations,
    }


class _KernelClock:
    """A timer around every call of a compiled (numba) kernel from Python, any thread, while
    active: totals (wall [s], calls, CPU time of the thread that ran it [s]) per (kernel, on
    the calling thread or not).
    Calls from one kernel to another are compiled in and are not seen: they count in the
    caller's time."""

    def __enter__(self):
        from numba import _dispatcher
        from numba.core.registry import CPUDispatcher

        self.cls, base = CPUDispatcher, _dispatcher.Dispatcher.__call__
        self.main = threading.get_ident()
        self.totals: dict[tuple[str, bool], list] = {}
        totals, main = self.totals, self.main

        def call(kernel, *args, **kwargs):
            t0, c0 = time.perf_counter(), time.thread_time()
            try:
                return base(kernel, *args, **kwargs)
            finally:
                c1, t1 = time.thread_time(), time.perf_counter()
                key = (kernel.py_func.__qualname__, threading.get_ident() == main)
                acc = totals.get(key)
                if acc is None:
                    acc = totals[key] = [0.0, 0, 0.0]
                acc[0] += t1 - t0
                acc[1] += 1
                acc[2] += c1 - c0

        self.cls.__call__ = call
        return self

    def snapshot(self) -> dict:
        return {k: tuple(v) for k, v in self.totals.items()}

    def __exit__(self, *exc):
        del self.cls.__call__


def timer_overhead_s(n: int = 2000) -> float:
    """What _KernelClock adds to one kernel call [s]: the median call of a kernel that does
    nothing, timed and not, minus each other."""
    import numba

    @numba.njit
    def nothing(x):  # pragma: no cover - compiled
        return x

    def per_call() -> float:
        t0 = time.perf_counter()
        for _ in range(n):
            nothing(1.0)
        return (time.perf_counter() - t0) / n

    nothing(1.0)
    plain = float(np.median([per_call() for _ in range(7)]))
    with _KernelClock():
        timed = float(np.median([per_call() for _ in range(7)]))
    return timed - plain


def _invariants(body) -> dict:
    """Stored size of a body's inertia invariants [MB] (every array once, views of another
    not counted again), its elastic coordinates, and what one G2 contraction reads [MB]: 4.5
    nq^2 numbers in the packed one-pass form (bodies.contraction), else the 9 nq^2 of the
    stacked product."""
    import dataclasses

    import scipy.sparse as sp

    seen, total = set(), 0

    def add(x) -> None:
        nonlocal total
        if isinstance(x, (tuple, list)):
            for y in x:
                add(y)
        elif sp.issparse(x):
            for a in (x.data, getattr(x, "indices", None), getattr(x, "indptr", None)):
                add(a)
        elif isinstance(x, np.ndarray):
            base = x
            while isinstance(base.base, np.ndarray):
                base = base.base
            if id(base) not in seen:
                seen.add(id(base))
                total += base.nbytes

    for f in dataclasses.fields(body.inv):
        add(getattr(body.inv, f.name))
    blocks = 4.5 if body.contracts_in_halves else 9.0
    return {
        "nq": int(body.nq),
        "stored_mb": total / 1e6,
        "g2_read_mb": blocks * body.nq**2 * 8 / 1e6,
        "packed": bool(body.contracts_in_halves),
    }


def measure_mvm(scenario: Path) -> dict:
    """The all-MVM figures (module docstring)."""
    built = _built("mvm", MVM_T_END_S, scenario)
    plain = _window(*_run(built)[:2])
    clock = _KernelClock()
    marks: list = []
    with clock:
        stamps, steps, _ = _run(built, clock, marks)
    w = _window(stamps, steps)
    first, last = marks[WARM_STEPS - 1], marks[-1]
    per_kernel: dict[str, dict] = {}
    kernel_cpu = 0.0
    for key, (s, n, c) in last.items():
        s0, n0, c0 = first.get(key, (0.0, 0, 0.0))
        if key[1]:
            kernel_cpu += (c - c0) / w["n_steps"]
        if n > n0:
            name, on_main = key
            row = per_kernel.setdefault(
                name, {"ms_per_step": 0.0, "calls_per_step": 0.0, "ms_per_step_other_threads": 0.0}
            )
            row["ms_per_step"] += 1e3 * (s - s0) / w["n_steps"]
            row["calls_per_step"] += (n - n0) / w["n_steps"]
            if not on_main:
                row["ms_per_step_other_threads"] += 1e3 * (s - s0) / w["n_steps"]
    other = sum(r["ms_per_step_other_threads"] for r in per_kernel.values())
    total = sum(r["ms_per_step"] for r in per_kernel.values())
    striker = next(b for b in built.system.bodies if b.name == STRIKER)
    return {
        "plain": {k: v for k, v in plain.items() if k not in ("t0", "t1")},
        "timed": {k: v for k, v in w.items() if k not in ("t0", "t1")},
        "dof": [6 + b.nq for b in built.system.bodies],
        "kernel_ms_calling_thread": total - other,
        "kernel_ms_other_threads": other,
        "kernel_cpu_ms_calling_thread": 1e3 * kernel_cpu,
        "kernels_called": len(per_kernel),
        "timer_overhead_s_per_call": timer_overhead_s(),
        "kernel_calls_per_step": sum(r["calls_per_step"] for r in per_kernel.values()),
        "kernels": dict(sorted(per_kernel.items(), key=lambda kv: -kv[1]["ms_per_step"])),
        "striker_invariants": _invariants(striker),
    }


def _commit() -> str:
    out = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"],
        check=False,
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    return out.stdout.strip() or "unknown"


def _print(res: dict) -> None:
    f, m = res["full"], res["mvm"]
    tf, bs = f["target_factor"], f["back_substitution"]
    inv = m["striker_invariants"]
    rows = [
        ("full FE: contact step, median [ms]", 1e3 * f["median_step_s"]),
        ("  share of its wall with a back-substitution running", f["solve_share"]),
        ("  back-substitutions per step (both rods)", f["solves_per_step"]),
        (f"{TARGET}'s factor L, entries x 8 bytes [MB]", tf["values_mb"]),
        ("  with its index arrays [MB]", tf["total_mb"]),
        ("one back-substitution, one thread [ms]", 1e3 * bs["one_thread_s"]),
        ("  its etree halves on two threads [ms]", 1e3 * bs["two_threads_s"]),
        ("both rods' back-substitutions, one after the other [ms]", 1e3 * bs["both_rods_serial_s"]),
        ("  at once on two threads [ms]", 1e3 * bs["both_rods_parallel_s"]),
        ("one back-substitution, one thread, CPU [ms]", 1e3 * bs["one_thread_cpu_s"]),
        ("all MVM: contact step, median [ms]", 1e3 * m["plain"]["median_step_s"]),
        ("  calling thread's CPU per step [ms]", 1e3 * m["timed"]["mean_step_thread_cpu_s"]),
        ("  of it in compiled kernels [ms]", m["kernel_cpu_ms_calling_thread"]),
        ("  with the kernel timers [ms]", 1e3 * m["timed"]["median_step_s"]),
        ("  in compiled kernels, calling thread [ms]", m["kernel_ms_calling_thread"]),
        ("  compiled kernels on the other thread [ms]", m["kernel_ms_other_threads"]),
        ("  kernel calls per step", m["kernel_calls_per_step"]),
        (f"{STRIKER}'s inertia invariants [MB]", inv["stored_mb"]),
        (f"  elastic coordinates of {STRIKER}", inv["nq"]),
        ("  read by one G2 contraction [MB]", inv["g2_read_mb"]),
    ]
    print(f"commit {res['commit']}, {res['machine']['cpu']}")
    for label, value in rows:
        print(f"{label:60s} {value:10.3f}")
    print("all-MVM kernels by time [ms per step, calls per step]:")
    for name, r in list(m["kernels"].items())[:10]:
        print(f"  {name:50s} {r['ms_per_step']:8.3f} {r['calls_per_step']:6.1f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", type=Path, default=SCENARIO, help=argparse.SUPPRESS)
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    ap.add_argument(
        "--write-docs",
        action="store_true",
        help='rewrite the "Where the time goes" block of docs/performance.md from this run',
    )
    args = ap.parse_args()
    res: dict = {"commit": _commit(), "cpu_count": os.cpu_count(), "machine": machine_facts()}
    res["scenario"] = args.scenario.name
    res["warm_steps"] = WARM_STEPS
    res["n_solves"] = N_SOLVES
    res["full"] = measure_full(args.scenario)
    res["mvm"] = measure_mvm(args.scenario)
    res["machine"]["load_avg_end"] = load_average()
    _print(res)
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / f"step_cost_{res['commit']}.json"
    path.write_text(json.dumps(res, indent=1))
    print(f"wrote {path}")
    if args.write_docs:
        if args.scenario != SCENARIO:
            raise SystemExit("step_cost: --write-docs writes the seed case's figures only")
        page = ROOT / "docs" / "performance.md"
        try:
            write_page(page, res, "python benchmarks/step_cost.py --write-docs")
        except InputError as exc:
            raise SystemExit(f"step_cost: {exc}") from None
        print(f"wrote {page}")


if __name__ == "__main__":
    main()
