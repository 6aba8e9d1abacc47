"""docs/moving_region.md's cam-follower table is its stamped record,
docs/moving_region/cam_follower_bench.json (benchmarks/bench_showcases.py --json): every figure of
the table remade from the record at the precision the page prints. Reads JSON and Markdown only."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "moving_region.md"
RECORD = ROOT / "docs" / "moving_region" / "cam_follower_bench.json"


def _row():
    (row,) = json.loads(RECORD.read_text())["rows"]
    return row


def expected_lines(row) -> list[str]:
    """The table's rows as the page prints them, from the record's row."""
    f, r = row["full"], row["reduced"]
    mb = lambda x: f"{x:,.0f}"
    return [
        (
            f"| coordinates of the run (the cam's 6 included) | {f['dof']:,} | {r['dof']:,} "
            "(the first window) |"
        ),
        (
            f"| simulation CPU (wall) | {f['sim_cpu_s']:.1f} s ({f['sim_wall_s']:.1f} s) | "
            f"{r['sim_cpu_s']:.1f} s ({r['sim_wall_s']:.1f} s): {row['cpu_ratio']:.1f} x less "
            f"({row['wall_ratio']:.1f} x) |"
        ),
        f"| set-up CPU (the setup cache warm) | {f['setup_cpu_s']:.1f} s | {r['setup_cpu_s']:.1f} s |",
        (
            f"| resident peak, simulation / set-up | {mb(f['sim_peak_mb'])} / {mb(f['setup_peak_mb'])} "
            f"MB | {mb(r['sim_peak_mb'])} / {mb(r['setup_peak_mb'])} MB |"
        ),
        (
            f"| contact force peak | {row['peak_full_n']:.2f} N | {row['peak_reduced_n']:.2f} N "
            f"({row['peak_diff_pct']:+.4f} %) |"
        ),
        f"| contact force NCC against full FE | - | {row['ncc']:.6f} |",
    ]


def test_the_cam_table_is_its_record():
    text = PAGE.read_text()
    for line in expected_lines(_row()):
        assert line in text, line


def test_the_set_up_sentence_is_its_record():
    """Simulation and set-up CPU together, reduced against full FE, as the text gives them."""
    row = _row()
    f, r = row["full"], row["reduced"]
    cpu_f, cpu_r = f["sim_cpu_s"] + f["setup_cpu_s"], r["sim_cpu_s"] + r["setup_cpu_s"]
    sentence = f"takes {cpu_r:.1f} s of CPU against full FE's {cpu_f:.1f} s ({cpu_f / cpu_r:.1f} x)"
    assert sentence in " ".join(PAGE.read_text().split())


def test_the_record_is_stamped():
    """A script stamp (flexmvm.runs.provenance.script_stamp) with the package's code version and
    the libraries that build the matrices and meshes."""
    prov = json.loads(RECORD.read_text())["provenance"]
    assert {"key", "code", "libraries", "scripts"} <= set(prov)
    assert {"scikit-fem", "gmsh"} <= set(prov["libraries"])
