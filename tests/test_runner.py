"""The resumable case runner: same table serial and on Dask, resume, corruption, failures."""

from __future__ import annotations

import hashlib
import json
import os
import pickle

import numpy as np
import pytest
from _study_cases import CountingCase, chain_eigenvalues, computed_keys, computing_pids

from flexmvm.errors import InputError, SolverError, StaleDataWarning
from flexmvm.results.atomic import atomic_path, canonical_json, write_json_atomic
from flexmvm.studies.runner import (
    Case,
    case_path,
    cluster_slots,
    collect,
    error_path,
    run_cases,
)


def make_cases(n_cases: int = 8) -> list[Case]:
    return [
        Case(f"c{i:02d}-n{4 + i}", {"n": 4 + i, "seed": 100 + i, "scale": 1.0 + 0.5 * i})
        for i in range(n_cases)
    ]


def table(out_dir) -> list[dict]:
    return collect(out_dir)


def test_case_is_hashable_picklable_and_frozen():
    a = Case("l2-j3-m13", {"layers": 2, "laps": 3, "modes": 13, "tags": ("x", "y")})
    b = Case("l2-j3-m13", {"modes": 13, "laps": 3, "layers": 2, "tags": ["x", "y"]})
    assert a == b and hash(a) == hash(b) and len({a, b}) == 1
    assert pickle.loads(pickle.dumps(a)) == a
    assert a.params["tags"] == ["x", "y"]
    a.params["tags"].append("z")  # a copy: the case itself cannot change
    assert a.params["tags"] == ["x", "y"]
    assert Case("k", {"x": 1}) != Case("k", {"x": 1.0})
    with pytest.raises(InputError, match="file-name-safe"):
        Case("../evil", {})
    with pytest.raises(InputError, match="non-finite"):
        Case("k", {"x": float("nan")})


def test_serial_stores_every_case_and_returns_json_form(tmp_path):
    cases = make_cases(4)
    results = run_cases(cases, chain_eigenvalues, tmp_path, serial=True, progress=True)
    assert list(results) == [c.key for c in cases]
    for case in cases:
        record = json.loads(case_path(tmp_path, case.key).read_text())
        assert record == {
            "key": case.key,
            "params": case.params.to_dict(),
            "result": results[case.key],
            "result_sha256": hashlib.sha256(canonical_json(results[case.key]).encode()).hexdigest(),
            "version": None,
        }
        expected = chain_eigenvalues(case)
        np.testing.assert_allclose(results[case.key]["lowest"], expected["lowest"], rtol=0)
    rows = collect(tmp_path)
    assert [r["key"] for r in rows] == sorted(c.key for c in cases)


def test_local_cluster_matches_serial_and_resumes(tmp_path):
    """A real 2-process LocalCluster gives the serial table; stored cases are not recomputed."""
    cases = make_cases(8)
    run_cases(cases, chain_eigenvalues, tmp_path / "serial", serial=True, progress=False)

    log = tmp_path / "log"
    log.mkdir()
    par = tmp_path / "parallel"
    run_cases(cases[:3], CountingCase(log), par, serial=True, progress=False)
    results = run_cases(cases, CountingCase(log), par, n_workers=2, progress=True)

    assert computed_keys(log) == sorted(c.key for c in cases)  # each case computed once
    assert os.getpid() not in computing_pids(log, [c.key for c in cases[3:]])  # on workers
    assert table(par) == table(tmp_path / "serial")
    assert results == {r["key"]: r["result"] for r in table(par)}


def test_existing_scheduler_failure_recorded_and_cluster_left_running(tmp_path):
    from distributed import Client, LocalCluster

    cases = make_cases(4)
    bad = Case("bad", {"n": 3, "seed": 0, "fail": True})
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        with pytest.raises(SolverError, match=r"^1 of 5 cases failed \(first: bad: ValueError"):
            run_cases(
                [cases[0], bad, *cases[1:]],
                chain_eigenvalues,
                tmp_path,
                scheduler=cluster.scheduler_address,
                progress=False,
            )
        with Client(cluster.scheduler_address, set_as_default=False) as client:
            assert client.submit(sum, [1, 2]).result() == 3
    text = error_path(tmp_path, "bad").read_text()
    assert text.splitlines()[0] == "case bad failed: ValueError: deliberate failure in case bad"
    assert "Traceback" in text and "chain_eigenvalues" in text
    assert [r["key"] for r in collect(tmp_path)] == sorted(c.key for c in cases)


def test_interrupted_serial_sweep_resumes_to_the_uninterrupted_table(tmp_path):
    cases = make_cases(6)
    run_cases(cases, chain_eigenvalues, tmp_path / "ref", serial=True, progress=False)
    log = tmp_path / "log"
    log.mkdir()
    out = tmp_path / "run"
    with pytest.raises(KeyboardInterrupt):
        run_cases(cases, CountingCase(log, interrupt_after=4), out, serial=True, progress=False)
    assert len(collect(out)) == 4
    first = computed_keys(log)
    run_cases(cases, CountingCase(log), out, serial=True, progress=False)
    assert computed_keys(log) == sorted(c.key for c in cases)  # no case computed twice
    assert sorted(set(computed_keys(log)) - set(first)) == sorted(c.key for c in cases[4:])
    assert table(out) == table(tmp_path / "ref")


def test_corrupt_case_file_is_recomputed(tmp_path):
    cases = make_cases(3)
    reference = run_cases(cases, chain_eigenvalues, tmp_path, serial=True, progress=False)
    path = case_path(tmp_path, cases[1].key)
    path.write_text(path.read_text()[:40])  # a truncated file, as a non-atomic writer leaves
    log = tmp_path / "log"
    log.mkdir()
    with pytest.warns(StaleDataWarning, match="unreadable or incomplete case file: recomputed"):
        again = run_cases(cases, CountingCase(log), tmp_path, serial=True, progress=False)
    assert computed_keys(log) == [cases[1].key]
    assert again == reference
    assert json.loads(path.read_text())["result"] == reference[cases[1].key]


def test_corrupt_case_is_counted_as_computed_not_loaded(tmp_path):
    """The keys run_cases reports loaded are those read from their files: a corrupt file's
    case is recomputed, so it is not among them (a study counted it as loaded)."""
    cases = make_cases(3)
    run_cases(cases, chain_eigenvalues, tmp_path, serial=True, progress=False)
    path = case_path(tmp_path, cases[0].key)
    path.write_text(path.read_text()[:40])
    loaded: set[str] = set()
    notes: list[str] = []
    run_cases(
        cases,
        chain_eigenvalues,
        tmp_path,
        serial=True,
        progress=False,
        loaded=loaded,
        announce=notes.append,
    )
    assert loaded == {cases[1].key, cases[2].key}
    assert notes == [f"{path}: unreadable or incomplete case file: recomputed"]


def test_case_of_another_version_is_recomputed_and_named(tmp_path):
    """A case stored under another version (a code change: studies pass the provenance
    stamp) is recomputed, not mixed with the new rows, in one line naming its file and what
    changed; under the same version it is loaded."""
    from pathlib import Path

    from flexmvm.runs.provenance import stamp
    from flexmvm.scenarios import load_scenario

    sc = load_scenario(Path(__file__).parent / "data" / "tiny_impact.toml")
    old = stamp(sc) | {"code": "0" * 16, "key": "0" * 32}
    cases = make_cases(3)
    run_cases(
        cases, chain_eigenvalues, tmp_path, serial=True, progress=False, version={"provenance": old}
    )
    log = tmp_path / "log"
    log.mkdir()
    notes: list[str] = []
    loaded: set[str] = set()
    run_cases(
        cases,
        CountingCase(log),
        tmp_path,
        serial=True,
        progress=False,
        version={"provenance": stamp(sc)},
        loaded=loaded,
        announce=notes.append,
    )
    assert computed_keys(log) == sorted(c.key for c in cases) and loaded == set()
    assert len(notes) == 1
    assert notes[0].startswith(
        f"{case_path(tmp_path, cases[0].key)} and 2 other case(s): "
        f"run under code version {'0' * 16} (now "
    )
    assert notes[0].endswith(": recomputed")
    run_cases(
        cases,
        CountingCase(log),
        tmp_path,
        serial=True,
        progress=False,
        version={"provenance": stamp(sc)},
        loaded=loaded,
        announce=notes.append,
    )
    assert len(computed_keys(log)) == 3 and loaded == {c.key for c in cases} and len(notes) == 1


def test_edited_result_is_recomputed(tmp_path):
    """A stored result edited after it was written (valid JSON, params unchanged) fails its
    SHA-256 and is recomputed, said in one line."""
    cases = make_cases(2)
    reference = run_cases(cases, chain_eigenvalues, tmp_path, serial=True, progress=False)
    path = case_path(tmp_path, cases[1].key)
    record = json.loads(path.read_text())
    record["result"]["trace"] += 1.0
    path.write_text(json.dumps(record))
    notes: list[str] = []
    again = run_cases(
        cases, chain_eigenvalues, tmp_path, serial=True, progress=False, announce=notes.append
    )
    assert again == reference
    assert notes == [
        (f"{path}: result differs from the SHA-256 written with it (edited or damaged): recomputed")
    ]


def test_stored_case_with_other_params_refused(tmp_path):
    cases = make_cases(2)
    run_cases(cases, chain_eigenvalues, tmp_path, serial=True, progress=False)
    before = case_path(tmp_path, cases[0].key).read_text()
    other = Case(cases[0].key, {**cases[0].params.to_dict(), "seed": 999})
    with pytest.raises(InputError, match="differ from case params") as info:
        run_cases([other, cases[1]], chain_eigenvalues, tmp_path, serial=True, progress=False)
    assert "\n" not in str(info.value)
    assert case_path(tmp_path, cases[0].key).read_text() == before


def test_failing_case_serial_recorded_others_stored_then_cleared(tmp_path):
    cases = make_cases(3)
    bad = Case("bad", {"n": 3, "seed": 0, "fail": True})
    with pytest.raises(SolverError) as info:
        run_cases([bad, *cases], chain_eigenvalues, tmp_path, serial=True, progress=False)
    message = str(info.value)
    assert "\n" not in message and message.startswith("1 of 4 cases failed")
    assert error_path(tmp_path, "bad").exists() and not case_path(tmp_path, "bad").exists()
    assert [r["key"] for r in collect(tmp_path)] == sorted(c.key for c in cases)
    log = tmp_path / "log"
    log.mkdir()
    with pytest.raises(SolverError):  # rerun: only the failed case is tried again
        run_cases([bad, *cases], CountingCase(log), tmp_path, serial=True, progress=False)
    assert computed_keys(log) == ["bad"]


def test_non_finite_result_is_a_case_failure(tmp_path):
    with pytest.raises(SolverError, match="non-finite number at result.x"):
        run_cases([Case("a", {})], _nan_case, tmp_path, serial=True, progress=False)
    assert "non-finite" in error_path(tmp_path, "a").read_text()
    assert collect(tmp_path) == []


def _nan_case(case: Case) -> dict:
    return {"x": float("inf")}


def test_invalid_arguments(tmp_path):
    with pytest.raises(InputError, match="appears twice"):
        run_cases([Case("a", {}), Case("a", {"x": 1})], chain_eigenvalues, tmp_path, serial=True)
    with pytest.raises(InputError, match="serial=True"):
        run_cases([Case("a", {})], chain_eigenvalues, tmp_path, serial=True, n_workers=2)
    with pytest.raises(InputError, match="does not exist"):
        collect(tmp_path / "nowhere")


def test_atomic_write_failure_leaves_old_file(tmp_path):
    path = tmp_path / "x.json"
    write_json_atomic(path, {"b": 1, "a": [1.5, 2]})
    assert path.read_text() == '{\n  "a": [\n    1.5,\n    2\n  ],\n  "b": 1\n}\n'
    with pytest.raises(InputError, match=r"non-finite number at a\[1\]"):
        write_json_atomic(path, {"a": np.array([1.0, np.nan])})
    assert json.loads(path.read_text()) == {"a": [1.5, 2], "b": 1}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.json"]
    with pytest.raises(RuntimeError, match="mid-write"), atomic_path(path) as tmp:
        tmp.write_text("partial")
        raise RuntimeError("mid-write")
    assert json.loads(path.read_text()) == {"a": [1.5, 2], "b": 1}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.json"]


def test_local_cluster_sends_one_case_per_single_threaded_worker():
    """With Dask's default worker-saturation (1.1) a one-thread worker is sent two cases, and
    with long cases one worker can idle while another holds two (seen in the material study)."""
    from flexmvm.studies.runner import local_cluster

    cluster = local_cluster(1)
    try:
        assert cluster.scheduler.WORKER_SATURATION == 1.0
    finally:
        cluster.close()


def test_workers_share_the_cores(monkeypatch):
    """A local cluster's workers get FLEXMVM_THREADS = cores // workers (at least 1), so two
    workers on two cores do not split their G2 contractions onto each other's core; a value
    the user set is kept (no override). Checked in a real worker process."""
    from distributed import Client

    from flexmvm.studies.runner import local_cluster, worker_env
    from flexmvm.threads import ENV_THREADS

    monkeypatch.delenv(ENV_THREADS, raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 8)
    assert worker_env(2) == {ENV_THREADS: "4"}
    assert worker_env(16) == {ENV_THREADS: "1"}
    monkeypatch.setenv(ENV_THREADS, "3")
    assert worker_env(2) == {}
    monkeypatch.delenv(ENV_THREADS)
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    cluster = local_cluster(2)
    try:
        with Client(cluster) as client:
            seen = client.run(lambda: os.environ.get("FLEXMVM_THREADS"))
        assert sorted(seen.values()) == ["1", "1"]
    finally:
        cluster.close()


def test_cluster_slots_counts_the_cases_run_at_once():
    """In-process 1, a local cluster its workers (default one per core), a running scheduler
    the threads of its workers; option errors as check_cluster_options."""
    from distributed import LocalCluster

    assert cluster_slots(None, None, True) == 1
    assert cluster_slots(None, 3, False) == 3
    assert cluster_slots(None, None, False) == (os.cpu_count() or 1)
    with LocalCluster(
        n_workers=2, threads_per_worker=2, processes=False, dashboard_address=None
    ) as cluster:
        assert cluster_slots(cluster.scheduler_address, None, False) == 4
    with pytest.raises(InputError, match="expected one"):
        cluster_slots("tcp://127.0.0.1:1", None, True)
    with pytest.raises(InputError, match="positive integer"):
        cluster_slots(None, 0, False)


def test_case_compared_with_another_reference_is_recomputed(tmp_path):
    """A study's version holds the SHA-256 of the reference history its cases are compared
    with: after the reference was recomputed to other bits, the cases are recomputed (not
    refused as another study, not kept against the old reference), said in one line."""
    cases = make_cases(2)
    run_cases(
        cases,
        chain_eigenvalues,
        tmp_path,
        serial=True,
        progress=False,
        version={"reference_sha256": "a" * 64},
    )
    notes: list[str] = []
    loaded: set[str] = set()
    run_cases(
        cases,
        chain_eigenvalues,
        tmp_path,
        serial=True,
        progress=False,
        version={"reference_sha256": "b" * 64},
        loaded=loaded,
        announce=notes.append,
    )
    assert loaded == set()
    first = case_path(tmp_path, cases[0].key)
    why = "compared with another reference history"
    assert notes == [f"{first} and 1 other case(s): {why}: recomputed"]


def _as_main(monkeypatch, tmp_path, source: str | None):
    """Make a module with file tmp_path/script.py holding ``source`` (None: no file, as in
    an interactive session) the __main__ module."""
    import sys
    import types

    main = types.ModuleType("__main__")
    if source is not None:
        path = tmp_path / "script.py"
        path.write_text(source, encoding="utf-8")
        main.__file__ = str(path)
    monkeypatch.setitem(sys.modules, "__main__", main)
    return main


@pytest.mark.parametrize(
    "source, unguarded",
    [
        ("import flexmvm\nflexmvm.select('x.toml', 'b2')\n", True),
        ("import flexmvm\nif __name__ == '__main__':\n    flexmvm.select('x.toml', 'b2')\n", False),
        ("def main():\n    pass\nif '__main__' == __name__:\n    main()\n", False),
        ("if __name__ != '__main__':\n    pass\n", True),
        (None, False),
    ],
)
def test_unguarded_main_script_is_recognised(monkeypatch, tmp_path, source, unguarded):
    """A script whose top level has no `if __name__ == "__main__":` block is named (spawned
    workers would re-run it); a guarded one, or no script at all, is not."""
    from flexmvm.studies.main_guard import unguarded_main_script

    _as_main(monkeypatch, tmp_path, source)
    found = unguarded_main_script()
    assert (found == str(tmp_path / "script.py")) if unguarded else found is None


def test_unguarded_script_studies_run_in_process(monkeypatch, tmp_path):
    """From an unguarded script: no workers asked -> in-process with one warning line that
    names the guard to add; workers asked -> a one-line InputError, before any process."""
    from flexmvm.studies.main_guard import InProcessStudyWarning, in_process_by_default
    from flexmvm.studies.runner import local_cluster

    _as_main(monkeypatch, tmp_path, "import flexmvm\n")
    with pytest.warns(InProcessStudyWarning, match='if __name__ == "__main__":') as seen:
        assert in_process_by_default(None, None, False)
    assert "\n" not in str(seen[0].message)
    assert not in_process_by_default(None, 2, False)
    assert not in_process_by_default("tcp://127.0.0.1:1", None, False)
    with pytest.raises(InputError, match="no main guard") as exc:
        local_cluster(2)
    assert "\n" not in str(exc.value)
    _as_main(monkeypatch, tmp_path, None)
    assert not in_process_by_default(None, None, False)
