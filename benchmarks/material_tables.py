"""Markdown tables of a material study directory, as docs/seed_reproduction.md shows them.

    python benchmarks/material_tables.py OUT_DIR     # OUT_DIR of `flexmvm study materials`

Reads materials.csv, materials.json and <material>/reference/reference.json; prints the
references against the 1D theory, the force NCC per material, selection and mode count, the
mean NCC per material and whether the seed's ordering W > Cu > Al > PA6 holds.
"""

import csv
import json
import sys
from pathlib import Path

from flexmvm.results.summary_keys import with_current_keys

d = Path(sys.argv[1])
res = json.loads((d / "materials.json").read_text())
with open(d / "materials.csv", newline="") as fh:
    rows = list(csv.DictReader(fh))
mats = [m for m in ("W", "Cu", "Al", "PA6") if m in res["materials"]]
modes, sels = res["modes"], res["selections"]
print(f"kind {res['kind']}, selections {sels}, modes {modes}, failures {len(res['failures'])}")
for f in res["failures"]:
    print("  FAIL", f["case"], f["reason"][:150])
print("\n| b2 | reference peak | theory | contact | theory duration | energy | reference wall |")
print("|---|---|---|---|---|---|---|")
for m in mats:
    s = with_current_keys(
        json.loads((d / m / "reference" / "reference.json").read_text())["summary"]
    )
    per = res["materials"][m]
    iv = s["contact_intervals_s"]
    ivs = ", ".join(f"{a * 1e6:.0f}..{b * 1e6:.0f}" for a, b in iv)
    tp, td = per.get("theory_peak_force_N"), per.get("theory_contact_duration_s")
    print(
        f"| {m} | {s['max_contact_force_interval_mean_N']:.1f} N | {tp:.1f} N ({(s['max_contact_force_interval_mean_N'] / tp - 1) * 100:+.1f} %) | {ivs} us | {td * 1e6:.0f} us | {s['energy_rel_change'] * 100:+.2f} % | {s['wall_time_s']:.0f} s |"
    )
print(
    "\n| material | selection | "
    + " | ".join(map(str, modes))
    + f" | peak error at {modes[-1]} | mean wall per run |"
)
print("|---|---|" + "---|" * (len(modes) + 2))
for m in mats:
    for sel in sels:
        rs = {int(r["modes"]): r for r in rows if r["material"] == m and r["selection"] == sel}
        cells = [
            f"{float(rs[n]['ncc_force']):.4f}" if rs.get(n) and rs[n]["ncc_force"] else "failed"
            for n in modes
        ]
        last = rs.get(modes[-1])
        pe = f"{float(last['peak_err']) * 100:+.1f} %" if last and last["peak_err"] else "-"
        w = [float(r["wall_time_s"]) for r in rs.values() if r["wall_time_s"]]
        print(f"| {m} | {sel} | " + " | ".join(cells) + f" | {pe} | {sum(w) / len(w):.1f} s |")
print(
    "\nmean NCC: "
    + ", ".join(
        f"{m} {res['materials'][m]['mean_ncc_force']:.4f} ({res['materials'][m]['n_cases']} runs)"
        if res["materials"][m]["mean_ncc_force"] is not None
        else f"{m} none"
        for m in mats
    )
)
print(
    "seed ordering holds:",
    res["seed_ordering_holds"],
    "observed:",
    " > ".join(res["observed_order"]),
)
print(
    "theory radius mm:",
    {m: round(res["materials"][m]["theory_contact_radius_m"] * 1e3, 3) for m in mats},
    "selection radius:",
    res["selection_radius_m"],
)
w = [float(r["wall_time_s"]) for r in rows if r["wall_time_s"]]
print(f"runs {len(rows)}, sum wall {sum(w):.0f} s")
