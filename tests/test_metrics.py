"""Checks of the history metrics (flexmvm.metrics.ncc): NCC (seed section 3.1) and the peak,
impulse and contact-duration errors reported beside it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexmvm.errors import InputError
from flexmvm.metrics import (
    Comparison,
    Target,
    compare_force,
    contact_intervals,
    contact_window,
    impulse,
    ncc,
    peak,
)


def _pulse(t: np.ndarray, t0: float = 0.1, t1: float = 0.3, amp: float = 600.0) -> np.ndarray:
    """Half-sine contact force amp sin(pi (t - t0)/(t1 - t0)) on [t0, t1], 0 elsewhere."""
    inside = (t >= t0) & (t <= t1)
    return np.where(inside, amp * np.sin(np.pi * (t - t0) / (t1 - t0)), 0.0)


@pytest.fixture
def histories():
    rng = np.random.default_rng(7)
    t = np.linspace(0.0, 1.0, 401)
    y_ref = np.sin(7 * t) + 0.3 * np.cos(23 * t)
    y = y_ref + 0.2 * rng.standard_normal(t.size)
    return t, y_ref, y


def test_ncc_equals_numpy_corrcoef_on_common_grid(histories):
    """On one common grid no resampling happens: NCC = numpy.corrcoef(x, y)[0, 1] to 1e-12."""
    t, y_ref, y = histories
    r = ncc(t, y_ref, t, y)
    assert r == pytest.approx(np.corrcoef(y_ref, y)[0, 1], abs=1e-12)
    assert r < 0.99


def test_ncc_identity_offset_scale_and_negation(histories):
    """r(x, x) = 1; r is invariant to offset and positive scale; r(x, -x) = -1 (to 1e-12)."""
    t, y_ref, y = histories
    assert ncc(t, y_ref, t, y_ref) == pytest.approx(1.0, abs=1e-12)
    base = ncc(t, y_ref, t, y)
    assert ncc(t, y_ref, t, 3.5 * y - 12.0) == pytest.approx(base, abs=1e-12)
    assert ncc(t, 0.2 * y_ref + 4.0, t, y) == pytest.approx(base, abs=1e-12)
    assert ncc(t, y_ref, t, -y_ref) == pytest.approx(-1.0, abs=1e-12)
    assert ncc(t, y_ref, t, -y) == pytest.approx(-base, abs=1e-12)


def test_ncc_resamples_candidate_on_reference_grid():
    """Two different grids of the smooth f(t) = sin(2 pi t) e^{-t}: the candidate (uneven grid)
    is linearly interpolated onto the reference's samples; r > 0.9999. Only the common window
    [0.2, 1.5] counts: a wild candidate outside it does not change r. The result equals the
    Pearson r of the reference against numpy.interp of the candidate, to 1e-12."""
    t_ref = np.linspace(0.0, 1.5, 301)
    rng = np.random.default_rng(3)
    t = np.sort(np.concatenate(([0.2, 1.5, 2.0], rng.uniform(0.2, 2.0, 700))))

    def f(x):
        return np.sin(2 * np.pi * x) * np.exp(-x)

    y = np.where(t > 1.5, 1e3 * rng.standard_normal(t.size), f(t))
    r = ncc(t_ref, f(t_ref), t, y)
    assert r > 0.9999
    keep = t_ref >= 0.2
    expected = np.corrcoef(f(t_ref[keep]), np.interp(t_ref[keep], t, y))[0, 1]
    assert r == pytest.approx(expected, abs=1e-12)
    assert ncc(t_ref, f(t_ref), t, y, t_window=(0.5, 1.0)) > 0.9999


def test_ncc_errors(histories):
    """No overlap, < 3 samples, NaN, a constant history: InputError with a one-line message."""
    t, y_ref, y = histories
    bad = [
        (t, y_ref, t + 2.0, y),  # no overlap
        (t[:2], y_ref[:2], t, y),  # < 3 samples
        (t, np.where(t > 0.5, np.nan, y_ref), t, y),  # NaN
        (t, y_ref, t, np.full_like(t, 2.0)),  # constant candidate
        (t, np.zeros_like(t), t, y),  # constant reference
        (t[::-1], y_ref, t, y),  # decreasing time
        (t, y_ref[:-1], t, y),  # length mismatch
    ]
    for args in bad:
        with pytest.raises(InputError) as err:
            ncc(*args)
        assert "\n" not in str(err.value)
    with pytest.raises(InputError, match="constant"):
        ncc(t, y_ref, t, np.full_like(t, 2.0))
    with pytest.raises(InputError, match="overlap"):
        ncc(t, y_ref, t, y, t_window=(3.0, 4.0))


def test_scaled_force_scores_one_but_errors_show():
    """A force 10 % too low everywhere: NCC = 1.0 (r ignores scale) but peak_err = -0.1 and
    impulse_err = -0.1 (to 1e-12); with a zero threshold the contact duration is the same."""
    t = np.linspace(0.0, 0.5, 2001)
    f_ref = _pulse(t)
    c = compare_force(t, f_ref, t, 0.9 * f_ref, threshold_fraction=0.0)
    assert c.ncc == pytest.approx(1.0, abs=1e-12)
    assert c.peak_err == pytest.approx(-0.1, abs=1e-12)
    assert c.impulse_err == pytest.approx(-0.1, abs=1e-12)
    assert c.duration_err == pytest.approx(0.0, abs=1e-12)
    assert not Target.parse("ncc>=0.99,peak<=0.05").met_by(c)
    assert Target.parse("ncc>=0.99").met_by(c)


def test_contact_intervals_peak_impulse():
    """Two half-sine pulses on [0.1, 0.3] and [0.5, 0.6]: intervals above a threshold of 1e-6 N
    are these (crossings interpolated linearly; the grid holds the ends; to 1e-9 s);
    above F_th = amp/2 a half-sine of length D is above for 2D/3. Peak (0.2, 600) and
    impulse 2 amp D/pi summed over the pulses (trapezoid, 1e-5 relative on 20001 samples)."""
    t = np.linspace(0.0, 1.0, 20001)
    f = _pulse(t) + _pulse(t, 0.5, 0.6, 300.0)
    iv = contact_intervals(t, f, 1e-6)
    assert len(iv) == 2
    assert np.allclose(iv, [(0.1, 0.3), (0.5, 0.6)], atol=1e-9)
    iv_half = contact_intervals(t, f, 300.0)
    assert len(iv_half) == 1
    ((a, b),) = iv_half
    assert b - a == pytest.approx(2 * 0.2 / 3, abs=1e-4)
    assert peak(t, f) == pytest.approx((0.2, 600.0), abs=1e-9)
    assert impulse(t, f) == pytest.approx(2 * (600 * 0.2 + 300 * 0.1) / math.pi, rel=1e-5)
    assert contact_intervals(t, f + 1.0, 0.5) == [(0.0, 1.0)]
    assert contact_intervals(t, f, 1e4) == []


def test_duration_error_from_contact_intervals():
    """Candidate pulse lasting 0.22 s instead of 0.2 s (same amplitude): duration_err = +0.1
    within the grid resolution (2 samples / 0.2 s), peak_err = 0, NCC < 1. With two contacts
    (0.2 s + 0.1 s, the second lasting 0.14 s in the candidate) the duration is the total time in
    contact: duration_err = 0.04/0.3."""
    t = np.linspace(0.0, 0.5, 5001)
    c = compare_force(t, _pulse(t), t, _pulse(t, 0.1, 0.32), threshold_fraction=0.0)
    assert isinstance(c, Comparison)
    assert c.duration_err == pytest.approx(0.1, abs=2 * (t[1] - t[0]) / 0.2)
    assert c.peak_err == pytest.approx(0.0, abs=1e-6)
    assert c.impulse_err == pytest.approx(0.1, abs=1e-4)
    assert 0.9 < c.ncc < 0.999
    assert ncc(t, _pulse(t), t, _pulse(t)) == pytest.approx(1.0, abs=1e-12)
    two = compare_force(
        t,
        _pulse(t) + _pulse(t, 0.35, 0.45),
        t,
        _pulse(t) + _pulse(t, 0.35, 0.49),
        threshold_fraction=0.0,
    )
    assert two.duration_err == pytest.approx(0.04 / 0.3, abs=2 * (t[1] - t[0]) / 0.3)
    with pytest.raises(InputError, match="threshold_fraction"):
        compare_force(t, _pulse(t), t, _pulse(t), threshold_fraction=1.5)
    with pytest.raises(InputError, match="peak"):
        compare_force(t, -_pulse(t) - 1.0, t, _pulse(t))


def test_target_parse_and_met_by():
    """Target.parse reads 'ncc>=X,peak<=X,impulse<=X,duration<=X' (ncc defaults to 0.99);
    met_by requires ncc >= ncc_min and |error| <= each given bound."""
    tgt = Target.parse("ncc>=0.995, peak<=0.02,impulse<=0.05")
    assert tgt == Target(ncc_min=0.995, peak_err_max=0.02, impulse_err_max=0.05)
    assert Target.parse("duration<=0.1") == Target(duration_err_max=0.1)
    good = Comparison(ncc=0.996, peak_err=-0.019, impulse_err=0.04, duration_err=0.5)
    assert tgt.met_by(good)
    assert not tgt.met_by(Comparison(0.994, 0.0, 0.0, 0.0))
    assert not tgt.met_by(Comparison(0.999, -0.021, 0.0, 0.0))
    assert not tgt.met_by(Comparison(0.999, 0.0, 0.051, 0.0))
    assert not Target(duration_err_max=0.1).met_by(good)


@pytest.mark.parametrize(
    "text",
    [
        "ncc>=abc",
        "stiffness<=0.1",
        "peak>=0.02",
        "ncc<=0.9",
        "peak<=0.02,peak<=0.03",
        "",
        "ncc>=1.5",
        "peak<=-0.1",
        "peak<=nan",
        "ncc=0.99",
        "peak<=0.02,,",
    ],
)
def test_target_parse_errors(text):
    """Unknown keys, wrong operators, repeats, bad or out-of-range numbers: one-line InputError."""
    with pytest.raises(InputError) as err:
        Target.parse(text)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("window", [1.0, 2.0, 3.0])
def test_force_ncc_is_taken_over_the_contact(window):
    """Reference: a half-sine pulse over [0, 0.66]; candidate: the same pulse 5 % longer, so
    its contact ends at 0.693. Zero force before and after the contact is shared by both and
    raises Pearson r over the whole window: measured ncc_whole 0.9919 (window 1), 0.9946 (2),
    0.9952 (3), against 0.98590 over the contact window [0, 0.693] (first to last contact of
    either history; contact: F above 1 % of the reference peak, as for the duration), which
    does not depend on the window (to round-off, 1e-12)."""
    t = np.linspace(0.0, window, int(2000 * window) + 1)
    ref, cand = _pulse(t, 0.0, 0.66, 1.0), _pulse(t, 0.0, 0.693, 1.0)
    c = compare_force(t, ref, t, cand)
    inside = (t >= 0.01 / np.pi * 0.66) & (t <= 0.693 * (1 - 0.01 / np.pi))  # F > 1 % of peak
    assert c.ncc == pytest.approx(np.corrcoef(ref[inside], cand[inside])[0, 1], abs=1e-12)
    assert c.ncc == pytest.approx(0.98590, abs=5e-5)
    assert c.ncc_whole == pytest.approx(np.corrcoef(ref, cand)[0, 1], abs=1e-12)
    assert c.ncc_whole > c.ncc + 5e-3


def test_contact_window_spans_either_history():
    """A candidate whose contact starts late: the window starts at the reference's contact
    and ends at the candidate's, and a history pair without contact is an InputError."""
    t = np.linspace(0.0, 2.0, 4001)
    ref, cand = _pulse(t, 0.0, 0.5, 1.0), _pulse(t, 0.2, 0.7, 1.0)
    c = compare_force(t, ref, t, cand)
    inside = (t >= 0.01 / np.pi * 0.5) & (t <= 0.7 - 0.01 / np.pi * 0.5)  # F > 1 % of peak
    assert c.ncc == pytest.approx(np.corrcoef(ref[inside], cand[inside])[0, 1], abs=1e-12)
    with pytest.raises(InputError, match="no contact"):
        contact_window(t, [])
