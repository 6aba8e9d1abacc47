"""Two output rates (issue 52): histories at every output, fields (q, q_dot and what the
ParaView series makes of them) at their own rate, kept in memory only there; results.h5's
fields chunked, compressed and float32 unless asked otherwise. On the tiny seed case (31
outputs, 1 us apart)."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

import flexmvm as fm
from flexmvm.integrate.run_result import FieldPrecision
from flexmvm.results.field_rows import DEFAULT_FIELD_FRAMES, default_field_rows

TINY = Path(__file__).parent / "data" / "tiny_impact.toml"
FIELD_DT = 5e-6  # every 5th output of the tiny case (output_dt_s = 1 us)


@pytest.fixture(scope="module")
def runs():
    """The tiny case with fields at every output, and with fields every 5 us (about 5 s)."""
    sc = fm.load_scenario(TINY)
    return fm.run(sc), fm.run(sc.with_time(field_output_dt_s=FIELD_DT))


def test_fields_kept_at_their_rate_and_histories_bit_for_bit(runs):
    """Every 5th output keeps q and q_dot (t = 0, 5, ..., 30 us), exactly the q of the run
    that kept them all; every history is the same to the bit (the rate changes no step)."""
    every, sparse = runs
    a, b = every.result, sparse.result
    assert a.field_index is None and len(a.q[0]) == len(a.t) == 31
    np.testing.assert_array_equal(b.field_index, np.arange(0, 31, 5))
    np.testing.assert_allclose(b.field_t, np.arange(7) * FIELD_DT, rtol=1e-12)
    for k in range(len(a.body_names)):
        assert b.q[k].shape == (7, a.q[k].shape[1])
        np.testing.assert_array_equal(b.q[k], a.q[k][b.field_index])
        np.testing.assert_array_equal(b.q_dot[k], a.q_dot[k][b.field_index])
    for key in (
        "t",
        "contact_force",
        "probe_x",
        "probe_v",
        "kinetic",
        "strain",
        "potential",
        "momentum",
        "angular_momentum",
        "frame_r",
        "frame_A",
        "frame_v",
        "joint_force",
    ):
        np.testing.assert_array_equal(getattr(b, key), getattr(a, key), err_msg=key)
    q, _ = sparse.elastic("b1")
    assert len(q) == 7


def test_default_field_rows_spread_and_dense_in_contact():
    """1,001 outputs over 2 ms, contact in the first 0.6 ms: about DEFAULT_FIELD_FRAMES rows,
    first and last included, at least half of them in contact; a short run keeps them all."""
    t = np.arange(1001) * 2e-6
    rows = default_field_rows(t, [(0.0, 6e-4)])
    assert DEFAULT_FIELD_FRAMES - 2 <= len(rows) <= DEFAULT_FIELD_FRAMES + 2
    assert rows[0] == 0 and rows[-1] == 1000 and np.all(np.diff(rows) > 0)
    assert np.sum(t[rows] <= 6e-4) >= len(rows) // 2
    np.testing.assert_array_equal(default_field_rows(t[:20], [(0.0, 6e-4)]), np.arange(20))


def test_results_h5_fields_compressed_float32(runs, tmp_path):
    """The scenario's default writes q and q_dot float32, chunked by row, shuffle + gzip;
    histories float64. Tolerance: float32 rounding, 2^-24 of each value."""
    every, _ = runs
    res = every.result
    assert res.field_precision is FieldPrecision.FLOAT32  # the scenario's default
    fm.write_run(tmp_path, every)
    with h5py.File(tmp_path / "results.h5", "r") as f:
        assert f["contact_force"].dtype == np.float64
        np.testing.assert_array_equal(f["contact_force"][()], res.contact_force)
        q = f["bodies/b1/q"]
        assert q.dtype == np.float32 and q.compression == "gzip" and q.shuffle
        assert q.chunks == (1, q.shape[1])
        rows = f["bodies/b1/time_index"][()]
        np.testing.assert_allclose(q[()], res.q[0][rows], rtol=2.0**-24, atol=0)


def test_field_keys_in_the_scenario(tmp_path):
    """field_output_dt_s below output_dt_s is refused in one line; a scenario without the
    keys dumps as before they existed (cache keys unchanged); field_precision float64."""
    sc = fm.load_scenario(TINY)
    assert not {"field_output_dt_s", "field_precision"} & set(sc.model_dump()["time"])
    with pytest.raises(fm.ScenarioError, match="field_output_dt_s"):
        sc.with_time(field_output_dt_s=0.5e-6)
    text = TINY.read_text().replace("theta = 0.55", 'theta = 0.55\nfield_precision = "float64"')
    (tmp_path / "s.toml").write_text(text)
    sc64 = fm.load_scenario(tmp_path / "s.toml")
    assert sc64.time.field_precision is FieldPrecision.FLOAT64
    assert sc64.model_dump(mode="json")["time"]["field_precision"] == "float64"


def test_a_rigid_body_s_fields_are_written(tmp_path):
    """A run with a rigid body (no elastic coordinates) and a field rate writes results.h5:
    the rigid body's q is (k, 0) beside the block's (k, 11742). Before: 'cannot reshape array
    of size 0 into shape (0)', the run's folder not written (the sphere on a plate, on
    sphere_block.toml's ball)."""
    path = Path(__file__).parents[1] / "scenarios" / "sphere_block.toml"
    sc = fm.load_scenario(path).with_time(t_end_s=4e-6)
    data = sc.model_dump(mode="json")
    data["time"]["field_output_dt_s"] = 2e-6
    run = fm.run(fm.scenario_from_dict(data, base_dir=path.parent))
    fm.write_run(tmp_path, run)
    with h5py.File(tmp_path / "results.h5") as f:
        q_ball, q_block = f["bodies/ball/q"], f["bodies/block/q"]
        assert q_ball.shape[1] == 0 and q_block.shape[1] == run.built.system.bodies[1].nq
        assert q_ball.shape[0] == q_block.shape[0] >= 2
