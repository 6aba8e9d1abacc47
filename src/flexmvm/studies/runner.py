"""Resumable, parallel runner for the cases of a study (selection and material studies).

A study is a list of :class:`Case` objects (a stable key and JSON parameters) and a case
function ``fn(case) -> mapping``. :func:`run_cases` stores every finished case at once,
atomically, in ``out_dir/cases/<key>.json`` as ``{"key", "params", "result", "result_sha256",
"version"}``; a rerun loads the stored cases and computes only the others, so a killed sweep
resumes where it stopped. A stored case is loaded only if it passes its check: readable, its
``version`` (what the study passes: studies key theirs by runs.provenance.stamp, the
package source, numpy/scipy/numba, the resolved scenario and mesh files, and by their reference
history) the current one, and its result the one whose SHA-256 was written with it; otherwise
it is recomputed and that is announced in one line per reason.
Cases run on Dask distributed: a local process cluster by default, an existing cluster when
a scheduler address is given, or in-process with ``serial=True``.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
import traceback
import uuid
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from tqdm import tqdm

from flexmvm.errors import (
    InputError,
    SolverError,
    StudyInterrupted,
    announce_recompute,
    notes_as_lines,
)
from flexmvm.processes import Terminated
from flexmvm.results.atomic import canonical_json, write_json_atomic, write_text_atomic
from flexmvm.results.output import writing
from flexmvm.studies.case_store import (
    CASES_DIR,
    Case,
    Params,
    announce_stale,
    case_path,
    collect,
    error_path,
    load_stored,
    result_sha256,
)
from flexmvm.studies.dask_client import PRELOAD, check_scheduler, close_quietly, connect
from flexmvm.studies.main_guard import main_guard_advice, unguarded_main_script
from flexmvm.threads import ENV_THREADS

__all__ = [
    "Case",
    "Params",
    "case_path",
    "check_cluster_options",
    "check_study_cluster",
    "cluster_slots",
    "collect",
    "error_path",
    "local_cluster",
    "run_cases",
    "study_cluster",
    "worker_env",
]


def _validate(cases: Sequence[Case]) -> None:
    seen: set[str] = set()
    for case in cases:
        if not isinstance(case, Case):
            raise InputError(f"run_cases: received {type(case).__name__}, expected Case objects")
        if case.key in seen:
            raise InputError(
                f"run_cases: case key {case.key!r} appears twice; expected unique keys"
            )
        seen.add(case.key)


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}".rstrip(": ")


class _Recorder:
    """Driver-side bookkeeping: writes each outcome at once and updates the progress bar
    ``bar`` (a tqdm bar; run_cases's dispatch step sets it when it opens one)."""

    def __init__(
        self, out_dir: Path, results: dict[str, dict], bar: Any, version_of: Callable[[Case], Any]
    ) -> None:
        self.out_dir = out_dir
        self.results = results
        self.bar = bar
        self.version_of = version_of
        self.failed: list[tuple[str, str]] = []

    def success(self, case: Case, result: Any) -> None:
        if not isinstance(result, Mapping):
            err = InputError(
                f"case {case.key}: fn returned {type(result).__name__}, expected a mapping"
            )
            self.failure(case, err, "")
            return
        assert isinstance(case.params, Params)
        try:
            plain = json.loads(canonical_json({"result": dict(result)}))["result"]
            record = {
                "key": case.key,
                "params": case.params.to_dict(),
                "result": plain,
                "result_sha256": result_sha256(plain),
                "version": self.version_of(case),
            }
            text = canonical_json(record)
        except InputError as exc:
            self.failure(case, exc, "")
            return
        path = case_path(self.out_dir, case.key)
        with writing(path):  # a full disk: OutputError naming the file (stops the study)
            write_json_atomic(path, json.loads(text))
        error_path(self.out_dir, case.key).unlink(missing_ok=True)
        self.results[case.key] = json.loads(text)["result"]
        self.bar.update(1)

    def failure(self, case: Case, exc: BaseException, tb_text: str) -> None:
        line = _one_line(exc)
        path = error_path(self.out_dir, case.key)
        with writing(path):
            write_text_atomic(
                path, f"case {case.key} failed: {line}\nparams: {case.params}\n\n{tb_text}"
            )
        self.failed.append((case.key, line))
        self.bar.update(1)


def _run_serial(pending: Sequence[Case], fn: Callable[[Case], Any], rec: _Recorder) -> None:
    for case in pending:
        try:
            result = fn(case)
        except Exception as exc:  # noqa: BLE001 - any case failure is recorded, not fatal
            rec.failure(case, exc, traceback.format_exc())
            continue
        rec.success(case, result)


def _check_picklable(fn: Callable[[Case], Any]) -> None:
    from distributed.protocol import pickle as dask_pickle

    try:
        dask_pickle.dumps(fn)
    except Exception as exc:  # noqa: BLE001 - pickling can raise anything; reported as input
        raise InputError(
            f"run_cases: fn {fn!r} cannot be pickled ({_one_line(exc)}); expected a "
            "module-level function importable by the workers"
        ) from None


def worker_env(n_workers: int) -> dict[str, str]:
    """Environment of a local cluster's worker processes: flexmvm's own thread pools
    (FLEXMVM_THREADS: a run's G2 contraction or back-substitutions in two halves) get the
    cores divided among the workers, at least one (two workers on two cores: one each, so
    the workers do not take each other's core); a value set by the user is kept."""
    if os.environ.get(ENV_THREADS, "").strip():
        return {}
    return {ENV_THREADS: str(max(1, (os.cpu_count() or 1) // max(n_workers, 1)))}


def _local_workers(n_workers: int | None) -> int:
    """The workers of a study's local cluster: ``n_workers``, default one per core."""
    return n_workers or os.cpu_count() or 1


def local_cluster(n_workers: int):
    """A LocalCluster of n_workers single-threaded processes that hands each worker one case
    at a time (worker-saturation 1.0: with the default 1.1 a one-thread worker is sent two
    cases, and with long cases one worker can sit idle while another holds two), no
    dashboard; the workers' thread pools as worker_env, SIGINT ignored in them (the driver
    handles a Ctrl-C and closes the cluster: studies/dask_client.py). InputError, before
    any process is started, when the main script has no main guard (unguarded_main_script)."""
    script = unguarded_main_script()
    if script is not None:
        raise InputError(
            f"a local Dask cluster was asked for from {script}, which has no "
            f"main guard; {main_guard_advice(script)}, or pass serial=True"
        )
    import dask
    from distributed import LocalCluster

    with (
        dask.config.set({"distributed.scheduler.worker-saturation": 1.0}),
        warnings.catch_warnings(),
    ):
        # the scheduler's HTTP routes (health, metrics) move to a free port when 8787 is taken
        # (another cluster on the machine); nothing here uses them, so that is no news
        warnings.filterwarnings("ignore", message="Port 8787 is already in use")
        return LocalCluster(
            n_workers=n_workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            env=worker_env(n_workers),
            preload=[PRELOAD],
        )


def check_cluster_options(scheduler: str | None, n_workers: int | None, serial: bool) -> None:
    """InputError unless at most one of ``serial``, ``scheduler``, ``n_workers`` is given and
    ``n_workers`` (if given) is >= 1."""
    if serial and (scheduler is not None or n_workers is not None):
        raise InputError("serial=True received with scheduler/workers; expected one")
    if scheduler is not None and n_workers is not None:
        raise InputError("--workers applies to a local cluster; expected no --scheduler with it")
    if n_workers is not None and n_workers < 1:
        raise InputError(f"workers: expected a positive integer, got {n_workers}")


def check_study_cluster(scheduler: str | None, n_workers: int | None, serial: bool) -> None:
    """What a study checks before its full-FE reference: :func:`check_cluster_options`, and
    a ``scheduler`` that answers within seconds (dask_client.check_scheduler)."""
    check_cluster_options(scheduler, n_workers, serial)
    check_scheduler(scheduler)


@contextlib.contextmanager
def study_cluster(
    scheduler: str | None, n_workers: int | None, serial: bool
) -> Iterator[str | None]:
    """The scheduler address a whole study gives run_cases: ``scheduler`` itself, None with
    ``serial`` (in-process), else a LocalCluster of ``n_workers`` (default: one per core)
    processes started here and closed at exit. Options as :func:`check_cluster_options`."""
    check_cluster_options(scheduler, n_workers, serial)
    if serial or scheduler is not None:
        yield scheduler
        return
    cluster = local_cluster(_local_workers(n_workers))
    try:
        yield cluster.scheduler_address
    except BaseException:  # a stop (error, Ctrl-C): the cluster closed without Dask's lines
        close_quietly(cluster.close)
        raise
    cluster.close()


def cluster_slots(scheduler: str | None, n_workers: int | None, serial: bool) -> int:
    """How many cases the cluster of a study runs at once: 1 in-process (``serial``), the
    local cluster's single-threaded workers (``n_workers``, default one per core, as
    :func:`study_cluster`), or the threads of the workers connected to the scheduler at
    ``scheduler`` when asked (at least 1). InputError if that scheduler cannot be reached."""
    check_cluster_options(scheduler, n_workers, serial)
    if serial:
        return 1
    if scheduler is None:
        return _local_workers(n_workers)
    client = connect(scheduler)
    try:
        return max(1, sum(client.nthreads().values()))
    finally:
        client.close()


def _run_dask(
    pending: Sequence[Case],
    fn: Callable[[Case], Any],
    rec: _Recorder,
    scheduler: str | None,
    n_workers: int | None,
) -> None:
    from distributed import Client

    _check_picklable(fn)
    cluster = None
    if scheduler is None:
        cluster = local_cluster(_local_workers(n_workers))
        try:
            client = Client(cluster, set_as_default=False)
        except BaseException:
            cluster.close()
            raise
    else:
        client = connect(scheduler)
    try:
        client.run(notes_as_lines)  # a recomputed setup-cache entry: one line on the worker
        _gather(pending, fn, rec, client)
    except BaseException:  # a stop (full disk, Ctrl-C): closed without Dask's lines
        close_quietly(client.close, None if cluster is None else cluster.close)
        raise
    client.close()
    if cluster is not None:
        cluster.close()


def _gather(pending: Sequence[Case], fn: Callable[[Case], Any], rec: _Recorder, client) -> None:
    """Submit ``pending`` to ``client`` and record each outcome as it comes."""
    from distributed import as_completed

    run_id = uuid.uuid4().hex[:12]
    by_key = {}
    futures = []
    for case in pending:
        fut = client.submit(fn, case, key=f"flexmvm-case-{case.key}-{run_id}", pure=False)
        by_key[fut.key] = case
        futures.append(fut)
    for fut in as_completed(futures, loop=client.loop):
        case = by_key[fut.key]
        if fut.status == "error":
            exc = fut.exception()
            tb = fut.traceback()
            rec.failure(case, exc, "".join(traceback.format_exception(type(exc), exc, tb)))
        elif fut.status == "cancelled":
            rec.failure(case, SolverError("cancelled by the Dask scheduler"), "")
        else:
            rec.success(case, fut.result())
        fut.release()


def run_cases(
    cases: Sequence[Case],
    fn: Callable[[Case], Mapping[str, Any]],
    out_dir: str | os.PathLike[str],
    *,
    scheduler: str | None = None,
    n_workers: int | None = None,
    progress: bool = True,
    serial: bool = False,
    failures: dict[str, str] | None = None,
    version: Mapping[str, Any] | Callable[[Case], Mapping[str, Any]] | None = None,
    loaded: set[str] | None = None,
    announce: Callable[[str], Any] = announce_recompute,
) -> dict[str, dict]:
    """Run ``fn`` on every case not already stored in ``out_dir``; return all results.

    Storage (module doc): ``out_dir/cases/<key>.json`` (sorted keys, indent 2), written
    atomically by the driver as soon as the case finishes; on start a case whose file passes
    its check is loaded, the others recomputed, each reason ``announce``d in one line.

    Execution: with ``serial=True`` in this process, no Dask. Otherwise on Dask distributed:
    ``scheduler=None`` starts a ``LocalCluster`` of ``n_workers`` processes (default
    ``os.cpu_count()``), one thread each, closed at the end; ``scheduler="tcp://host:port"``
    connects to an existing cluster, which is left running. Results come back with
    ``distributed.as_completed``.

    ``fn`` must be picklable: a function (or an instance of a class) defined at module level
    in a module that the worker processes can import (installed, or on their ``PYTHONPATH``);
    ``fn(case)`` returns a JSON-serialisable mapping (numpy scalars and arrays are converted,
    NaN/inf are refused). Returned results are the JSON form, identical whether loaded or
    computed, serial or parallel.

    Failures: an exception inside a case (or a non-mapping / non-finite result) is written
    to ``out_dir/cases/<key>.error.txt`` (one line, params, traceback) and the other cases
    go on; a later successful run of that case removes the error file. With ``failures`` (a
    dict) given, the failed cases are put there (key -> one line) and left out of the returned
    results instead of raising; a rerun computes them again (they have no stored file).

    Args:
        cases: the cases, with unique keys.
        fn: the case function, ``fn(case) -> mapping``.
        out_dir: study directory (created if missing).
        scheduler: address of an existing Dask scheduler, or None for a local cluster.
        n_workers: number of local worker processes (local cluster only).
        progress: show a tqdm bar (cases done / total, time left) on stderr.
        serial: run in this process without Dask.
        failures: if given, filled with ``{key: one line}`` of the failed cases, which do not
            raise (see Failures).
        version: what the results depend on beyond the params (JSON; a mapping for every case
            or a function of the case); a stored case of another version is recomputed.
        loaded: if given, filled with the keys of the cases loaded from their files (the
            others were computed now).
        announce: called with the one-line notice of each recomputation of stored cases.

    Returns:
        ``{key: result}`` for every case, loaded and computed (without the failed ones when
        ``failures`` is given).

    Raises:
        InputError: duplicate keys, conflicting options, an unpicklable ``fn``, or a stored
            case file with other params under the same key (refuses to mix studies).
        OutputError: a case file cannot be written (a full disk): one line naming it.
        StudyInterrupted: Ctrl-C (a KeyboardInterrupt): one line, how many cases are
            stored and where; the cluster is closed first, quietly.
        SolverError: after all successful cases are stored, if any case failed and
            ``failures`` is None (one line: how many, the first failure, where the error
            files are).
    """
    _validate(cases)
    check_cluster_options(scheduler, n_workers, serial)
    out = Path(out_dir)
    (out / CASES_DIR).mkdir(parents=True, exist_ok=True)
    version_of = version if callable(version) else (lambda _case: version)
    results, pending = _resume(cases, out, version_of, announce)
    if loaded is not None:
        loaded.update(results)
    rec = _Recorder(out, results, None, version_of)
    _run_pending(cases, pending, fn, rec, progress, serial, scheduler, n_workers)
    return _outcome(cases, results, rec.failed, failures, out)


def _resume(
    cases: Sequence[Case],
    out: Path,
    version_of: Callable[[Case], Any],
    announce: Callable[[str], Any],
) -> tuple[dict[str, dict], list[Case]]:
    """The resume step: the results of the cases stored in ``out`` that pass their check
    (case_store.load_stored), by key, and the cases to run; the reasons for recomputing
    stored ones announced (case_store.announce_stale)."""
    results: dict[str, dict] = {}
    pending: list[Case] = []
    stale: dict[str, list[str]] = {}
    for case in cases:
        stored, why = load_stored(case, out, version_of(case))
        if stored is None:
            pending.append(case)
            if why is not None:
                stale.setdefault(why, []).append(case.key)
        else:
            results[case.key] = stored
    announce_stale(stale, out, announce)
    return results, pending


def _run_pending(
    cases: Sequence[Case],
    pending: Sequence[Case],
    fn: Callable[[Case], Any],
    rec: _Recorder,
    progress: bool,
    serial: bool,
    scheduler: str | None,
    n_workers: int | None,
) -> None:
    """The dispatch step: ``pending`` in this process (``serial``) or on Dask, each outcome
    recorded by ``rec`` as it comes, under a progress bar over all ``cases``. A Ctrl-C
    becomes StudyInterrupted (cases stored, where); the cluster is closed first, quietly."""
    with tqdm(
        total=len(cases),
        initial=len(rec.results),
        unit="case",
        desc="cases",
        disable=not progress,
        file=sys.stderr,
        dynamic_ncols=True,
    ) as bar:
        rec.bar = bar
        try:
            if pending and serial:
                _run_serial(pending, fn, rec)
            elif pending:
                _run_dask(pending, fn, rec, scheduler, n_workers)
        except KeyboardInterrupt as exc:  # Ctrl-C: one line, how many cases are kept
            if isinstance(exc, (Terminated, StudyInterrupted)):
                raise
            raise StudyInterrupted(
                f"interrupted; {len(rec.results)} of {len(cases)} cases stored in "
                f"{rec.out_dir / CASES_DIR}, rerun to resume"
            ) from None


def _outcome(
    cases: Sequence[Case],
    results: dict[str, dict],
    failed: list[tuple[str, str]],
    failures: dict[str, str] | None,
    out: Path,
) -> dict[str, dict]:
    """The report step: the results in the order of ``cases``; the ``failed`` (key, one line)
    put in ``failures`` when given, else SolverError naming the first."""
    if failed and failures is not None:
        failures.update(failed)
        return {case.key: results[case.key] for case in cases if case.key in results}
    if failed:
        key, line = failed[0]
        raise SolverError(
            f"{len(failed)} of {len(cases)} cases failed (first: {key}: {line}); "
            f"see {out / CASES_DIR}/<key>.error.txt"
        )
    return {case.key: results[case.key] for case in cases}
