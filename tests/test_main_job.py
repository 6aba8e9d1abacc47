"""The main job runs the scenario and its full-FE reference side by side (two processes) or one
after the other: the same summary and the same files either way."""

from __future__ import annotations

import json
from pathlib import Path

from flexmvm.runs.main_job import run_main_job

TINY = Path(__file__).parent / "data" / "tiny_impact.toml"


def test_two_processes_equal_one(tmp_path):
    """Each run is deterministic and single-threaded, so the comparison against the reference
    and every reported number agree exactly (the wall times aside)."""
    out = {}
    for jobs in (1, 2):
        run_main_job(
            TINY,
            tmp_path / f"jobs{jobs}",
            t_end=10e-6,
            fields=False,
            progress=False,
            echo=lambda *_: None,
            jobs=jobs,
        )
        out[jobs] = json.loads((tmp_path / f"jobs{jobs}" / "summary.json").read_text())
        assert (tmp_path / f"jobs{jobs}" / "full" / "history.csv").exists()
    for s in out.values():
        s.pop("wall_time_s")
        s.pop("speedup_vs_full")
        s["reference_full"].pop("wall_time_s")
    assert out[1] == out[2]
