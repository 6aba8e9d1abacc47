"""docs/performance.md's big-part table is its stamped record, docs/performance/big_part.json
(benchmarks/bench_big_part.py --json): every figure of the table remade from the record at the
precision the page prints. Reads JSON and Markdown only."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "performance.md"
RECORD = ROOT / "docs" / "performance" / "big_part.json"
LABELS = ("reduced warm", "reduced cold", "region 1.25 mm warm", "region 1.25 mm cold")


def expected_table() -> list[str]:
    d = json.loads(RECORD.read_text())
    full = d["full"]
    cases = {c["label"]: c for c in d["cases"]}
    cs = [cases[k] for k in LABELS]

    def row(name: str, first: str, cells) -> str:
        return f"| {name} | {first} | " + " | ".join(cells) + " |"

    gb = lambda mb: f"{mb / 1e3:.1f} GB"
    peak = full["peak_force_n"]
    return [
        row("coordinates", f"{full['dof']:,}", (f"{c['dof']:,}" for c in cs)),
        row(
            "simulation CPU (100 steps)",
            f"{full['sim_cpu_s']:.1f} s",
            (f"{c['sim_cpu_s']:.1f} s: {c['vs_full']['sim_cpu_ratio']:.2g} x less" for c in cs),
        ),
        row(
            "set-up CPU", f"{full['build_cpu_s']:.1f} s", (f"{c['build_cpu_s']:.1f} s" for c in cs)
        ),
        row(
            "peak memory",
            gb(full["peak_rss_mb"]),
            (f"{gb(c['peak_rss_mb'])} ({c['vs_full']['peak_rss_fraction']:.2f})" for c in cs),
        ),
        row(
            "peak force",
            f"{peak:.2f} N",
            (f"{100 * c['vs_full']['peak_error']:+.2f} %" for c in cs),
        ),
        row("force NCC against full FE", "-", (f"{c['vs_full']['force_ncc']:.5f}" for c in cs)),
    ]


def test_the_big_part_table_is_its_record():
    text = PAGE.read_text()
    block = text[text.index("<!-- big_part.json: begin") : text.index("<!-- big_part.json: end")]
    for line in expected_table():
        assert line in block, line


def test_the_record_is_stamped_and_whole():
    """A script stamp, every case run (none failed), each 100 steps as full FE's."""
    d = json.loads(RECORD.read_text())
    assert {"key", "code", "libraries", "scripts"} <= set(d["provenance"])
    order = ["reduced cold", "reduced warm", "region 1.25 mm cold", "region 1.25 mm warm"]
    assert [c["label"] for c in d["cases"]] == order
    assert all("error" not in c and c["steps"] == d["full"]["steps"] == 100 for c in d["cases"])


def test_the_big_regions_sentence_is_its_record():
    """The sentence after the table: the big region's cold set-up (CPU minutes, peak) and the
    cost guard's estimate of it, as the record has them."""
    d = json.loads(RECORD.read_text())
    cold = {c["label"]: c for c in d["cases"]}["region 1.25 mm cold"]
    text = " ".join(PAGE.read_text().split())
    minutes = f"{cold['build_cpu_s'] / 60:.0f} minutes of CPU"
    peak = f"{cold['peak_rss_mb'] / 1e3:.1f} GB at the peak"
    estimate = f"the cost guard's estimate, {d['estimate']['peak_bytes'] / 1e9:.1f} GB"
    for phrase in (minutes, peak, estimate):
        assert phrase in text, phrase
