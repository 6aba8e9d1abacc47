"""Probe velocities beyond x (issue 52): every component and the norm in a history CSV, and
comparisons of any component (an impact along z has its curves there). On the tiny case."""

from __future__ import annotations

import csv
import dataclasses
from pathlib import Path

import numpy as np
import pytest

import flexmvm as fm
from flexmvm.results.history import read_history
from flexmvm.results.writers import write_history_csv

TINY = Path(__file__).parent / "data" / "tiny_impact.toml"


@pytest.fixture(scope="module")
def res():
    return fm.run(fm.load_scenario(TINY)).result


def test_history_csv_every_component_and_the_norm(res, tmp_path):
    """probe_axis=None: vx, vy, vz and |v| of each probe, read back bit for bit (repr);
    read_history still finds the x columns."""
    path = tmp_path / "h.csv"
    write_history_csv(path, res, probe_axis=None)
    with open(path) as fh:
        rows = list(csv.reader(fh))
    expected = ["t_s", "contact_force_N"]
    for p in res.probe_names:
        expected += [f"{p}_vx_mps", f"{p}_vy_mps", f"{p}_vz_mps", f"{p}_v_mps"]
    assert rows[0] == expected
    data = np.array(rows[1:], dtype=float)
    for i in range(len(res.probe_names)):
        np.testing.assert_array_equal(data[:, 2 + 4 * i : 5 + 4 * i], res.probe_v[:, i])
        np.testing.assert_array_equal(data[:, 5 + 4 * i], np.linalg.norm(res.probe_v[:, i], axis=1))
    _, _, vx = read_history(path)
    np.testing.assert_array_equal(vx[res.probe_names[0]], res.probe_v[:, 0, 0])


def test_compare_takes_the_component(res):
    """The run turned so that x becomes z: its z NCCs are the x NCCs of the run as it was, to
    the bit; "norm" compares speeds; a tuple holds x only; a bad axis is one line."""
    turn = lambda r: dataclasses.replace(r, probe_v=r.probe_v[:, :, ::-1].copy())
    late = dataclasses.replace(res, probe_v=np.roll(res.probe_v, 1, axis=0))
    cx = fm.compare(late, res, axis="x")
    assert cx.ncc_probes and all(v < 1.0 for v in cx.ncc_probes.values())
    assert fm.compare(turn(late), turn(res), axis=2).ncc_probes == cx.ncc_probes
    assert fm.compare(turn(late), turn(res), axis="x").ncc_probes != cx.ncc_probes
    for i, p in enumerate(res.probe_names):
        np.testing.assert_array_equal(
            res.curves("norm")[2][p], np.linalg.norm(res.probe_v[:, i], axis=1)
        )
    assert fm.compare(res, res, axis="norm").ncc_probes == dict.fromkeys(res.probe_names, 1.0)
    with pytest.raises(fm.InputError, match="tuple holds one velocity component"):
        fm.compare(res.curves(), res, axis="z")
    with pytest.raises(fm.InputError, match="axis: expected"):
        res.curves("w")
