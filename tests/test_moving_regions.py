"""Several moving regions in one run (issue 53: "one moving body per scenario" was a
limit): two copies of scenarios/moving_load.toml side by side, the second beam 0.1 m away and
its slider at 40 m/s, both beams mvm-moving; each region switches on its own contact and each
beam's mid-span deflection follows its full-FE run."""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import numpy as np

import flexmvm as fm
from flexmvm.integrate.moving_region import MovingRegions

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


def _two_beams(t_end_s: float) -> fm.Scenario:
    """moving_load.toml and a copy of its beam, slider, supports, drive, load and contact
    (names suffixed 2), the copy 0.1 m along y with its slider at 40 m/s; the point probes
    (given in the beam's frame at y = 0) dropped, the mid-span node-set probes kept."""
    with open(SCENARIOS / "moving_load.toml", "rb") as f:
        d = tomllib.load(f)
    for b in d["bodies"]:
        b["mesh_file"] = str(SCENARIOS / b["mesh_file"])
    d["time"].update(t_end_s=t_end_s)
    beam, slider = copy.deepcopy(d["bodies"][0]), copy.deepcopy(d["bodies"][1])
    beam["name"], slider["name"] = "beam2", "slider2"
    beam["placement"] = {"position_m": [0.0, 0.1, 0.0]}
    slider["placement"]["position_m"] = [0.0, 0.1, 0.010]
    slider["placement"]["velocity_mps"] = [40.0, 0.0, 0.0]
    d["bodies"] += [beam, slider]
    for s in list(d["supports"]):
        d["supports"].append({**s, "body": "beam2"})
    drive = {**d["joints"][0], "name": "drive2", "body": "slider2", "velocity_mps": [40.0, 0, 0]}
    d["joints"].append(drive)
    d["loads"].append({**d["loads"][0], "name": "press2", "body": "slider2"})
    d["contacts"].append({**d["contacts"][0], "slave": "slider2.front", "master": "beam2.top"})
    d["probes"] = [p for p in d["probes"] if "node_set" in p]
    d["probes"].append({**d["probes"][0], "name": "mid_axis2", "body": "beam2"})
    return fm.scenario_from_dict(d)


def test_two_moving_regions_each_follow_their_contact():
    """5 ms (100 steps of 50 us): the first slider travels 0.3 m, the second 0.2 m; each region
    switches (>= 15 and >= 10 times: one window is 12.5 mm; measured 23 and 15) and each beam's
    mid-span deflection is within 1e-3 of its full-FE largest (the bound of the single region's
    test, tests/test_moving_region.py; measured 3.5e-4 and 3.3e-4). Fails before: a second
    moving region was refused."""
    sc = _two_beams(5e-3)
    full = fm.run(sc).result
    mv = fm.run(sc.with_kind("mvm-moving"))
    hook = mv.built.switches
    assert isinstance(hook, MovingRegions)
    assert len(hook.region("beam").switches) >= 15 and len(hook.region("beam2").switches) >= 10
    centres = [np.array(hook.region(n).centres)[:, 1] for n in ("beam", "beam2")]
    assert np.ptp(centres[0]) > 1.4 * np.ptp(centres[1])  # 60 against 40 m/s
    for probe in ("mid_axis", "mid_axis2"):

        def deflection(r, probe=probe):
            z = r.probe_x[:, r.probe_names.index(probe), 2]
            return -(z - z[0])

        w_full, w_mv = deflection(full), deflection(mv.result)
        assert w_full.max() > 0
        assert np.abs(w_mv - w_full).max() <= 1e-3 * w_full.max()
