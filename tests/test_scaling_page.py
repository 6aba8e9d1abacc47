"""docs/performance.md's scaling tables are their stamped records (benchmarks/bench_scaling.py
--json): the body-size table remade from docs/performance/scaling_body.json and the region-size
table (with its full-FE line) from docs/performance/scaling_region.json by the benchmark's own
table writers. Reads JSON and Markdown only (no run)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "performance.md"
BODY = ROOT / "docs" / "performance" / "scaling_body.json"
REGION = ROOT / "docs" / "performance" / "scaling_region.json"


def _tables():
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import bench_scaling
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    body = json.loads(BODY.read_text())
    pairs = [(r["full"], r["mvm-sparse"], r["mesh_dof"]) for r in body["body_size"]]
    region = json.loads(REGION.read_text())
    rows = [(r["nodes"], r["mvm-sparse"], r["mvm"]) for r in region["region_size"]]
    return bench_scaling.body_table(pairs), bench_scaling.region_table(region["region_full"], rows)


def test_the_scaling_tables_are_their_records():
    page = PAGE.read_text()
    for table in _tables():
        assert table in page, table.splitlines()[0]


def test_the_records_are_stamped():
    for record in (BODY, REGION):
        prov = json.loads(record.read_text())["provenance"]
        assert {"key", "code", "libraries", "scripts"} <= set(prov)
        assert {"scikit-fem", "gmsh"} <= set(prov["libraries"])
