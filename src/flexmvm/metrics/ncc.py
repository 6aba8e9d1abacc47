"""Comparison of time histories: NCC (seed section 3.1) and the errors it cannot see.

The normalized cross-correlation of the seed (Wang, Hong, Liu 2014, section 3.1) is Pearson's r

    r = sum (x_i - mean x)(y_i - mean y) / sqrt(sum (x_i - mean x)^2 * sum (y_i - mean y)^2)

between a reference x and a candidate y on a common time grid. Here the common grid is the
reference's own samples inside the common time window, and the candidate is resampled onto it by
linear interpolation (``numpy.interp``). r ignores offset and scale (a force 10 % too low scores
1.0), so :func:`compare_force` also reports the peak, impulse and contact-duration errors.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError


def _history(name: str, t: object, y: object) -> tuple[np.ndarray, np.ndarray]:
    """Validate a history: 1D float arrays of equal length >= 3, finite, t strictly increasing."""
    t_arr = np.asarray(t, dtype=float)
    y_arr = np.asarray(y, dtype=float)
    if t_arr.ndim != 1 or y_arr.shape != t_arr.shape:
        raise InputError(
            f"{name}: expected 1D t and y of equal length, got shapes "
            f"{t_arr.shape} and {y_arr.shape}"
        )
    if t_arr.size < 3:
        raise InputError(f"{name}: expected at least 3 samples, got {t_arr.size}")
    if not (np.all(np.isfinite(t_arr)) and np.all(np.isfinite(y_arr))):
        raise InputError(f"{name}: expected finite values, got NaN or inf")
    if np.any(np.diff(t_arr) <= 0):
        raise InputError(f"{name}: expected strictly increasing times")
    return t_arr, y_arr


def _window(
    t_ref: np.ndarray, t: np.ndarray, t_window: tuple[float, float] | None
) -> tuple[float, float]:
    """Common time window of two histories, optionally narrowed to t_window = (start, end) [s]."""
    lo, hi = max(t_ref[0], t[0]), min(t_ref[-1], t[-1])
    if t_window is not None:
        try:
            w_lo, w_hi = (float(v) for v in t_window)
        except (TypeError, ValueError):
            raise InputError(f"t_window: expected (start, end) in s, got {t_window!r}") from None
        if not (math.isfinite(w_lo) and math.isfinite(w_hi) and w_lo < w_hi):
            raise InputError(f"t_window: expected finite start < end, got {t_window!r}")
        lo, hi = max(lo, w_lo), min(hi, w_hi)
    if not lo < hi:
        raise InputError(
            f"histories do not overlap: reference [{t_ref[0]:g}, {t_ref[-1]:g}] s, candidate "
            f"[{t[0]:g}, {t[-1]:g}] s, window {t_window!r}"
        )
    return float(lo), float(hi)


def _on_common_grid(
    t_ref: object, y_ref: object, t: object, y: object, t_window: tuple[float, float] | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reference samples in the common window and the candidate linearly interpolated there."""
    tr, yr = _history("reference", t_ref, y_ref)
    tc, yc = _history("candidate", t, y)
    lo, hi = _window(tr, tc, t_window)
    keep = (tr >= lo) & (tr <= hi)
    if np.count_nonzero(keep) < 3:
        raise InputError(
            f"common window [{lo:g}, {hi:g}] s holds {np.count_nonzero(keep)} reference samples; "
            "expected at least 3"
        )
    return tr[keep], yr[keep], np.interp(tr[keep], tc, yc)


def pearson(x: np.ndarray, y: np.ndarray) -> float:
    """Pearson r of two equal-length samples (the seed's formula). InputError if either is
    constant: r is then undefined (zero variance)."""
    dx = x - x.mean()
    dy = y - y.mean()
    sxx, syy = float(dx @ dx), float(dy @ dy)
    for name, s, v in (("reference", sxx, x), ("candidate", syy, y)):
        scale = float(np.max(np.abs(v))) if v.size else 0.0
        if s <= (1e-14 * scale) ** 2 * v.size:
            raise InputError(
                f"{name} history is constant over the window; NCC (Pearson r) is undefined"
            )
    return float(np.clip((dx @ dy) / math.sqrt(sxx * syy), -1.0, 1.0))


def ncc(
    t_ref: object,
    y_ref: object,
    t: object,
    y: object,
    *,
    t_window: tuple[float, float] | None = None,
) -> float:
    """NCC (seed section 3.1): Pearson r of the candidate (t, y), linearly interpolated onto the
    reference's samples t_ref inside the common time window (optionally narrowed to t_window).

    Arrays are 1D, shape (n_ref,) and (n,); times [s] strictly increasing. Returns r in [-1, 1].
    Raises InputError when the histories do not overlap, have < 3 samples (in the window), contain
    NaN/inf, or either is constant (r undefined).
    """
    _, yr, yc = _on_common_grid(t_ref, y_ref, t, y, t_window)
    return pearson(yr, yc)


def contact_intervals(t: object, force: object, threshold: float) -> list[tuple[float, float]]:
    """Time intervals [s] where force > threshold [N], the crossings located by linear
    interpolation between samples; an interval open at either end of the history is closed there.
    """
    ta, fa = _history("force history", t, force)
    if (
        isinstance(threshold, bool)
        or not isinstance(threshold, (int, float))
        or not math.isfinite(threshold)
    ):
        raise InputError(f"threshold: expected a finite force in N, got {threshold!r}")
    above = fa > threshold
    out: list[tuple[float, float]] = []
    start: float | None = float(ta[0]) if above[0] else None
    for i in np.flatnonzero(above[1:] != above[:-1]):
        f0, f1 = fa[i], fa[i + 1]
        tc = float(ta[i] + (threshold - f0) / (f1 - f0) * (ta[i + 1] - ta[i]))
        if above[i + 1]:
            start = tc
        else:  # a fall follows a rise or the start: start is set
            out.append((float(start), tc))  # type: ignore[arg-type]
            start = None
    if start is not None:
        out.append((start, float(ta[-1])))
    return out


def peak(t: object, y: object) -> tuple[float, float]:
    """(time [s], value) of the largest sample of y (use -y for a minimum)."""
    ta, ya = _history("history", t, y)
    i = int(np.argmax(ya))
    return float(ta[i]), float(ya[i])


def impulse(t: object, force: object) -> float:
    """Impulse int F dt [N s] by the trapezoid rule."""
    ta, fa = _history("force history", t, force)
    return float(np.trapezoid(fa, ta))


@dataclass(frozen=True)
class Comparison:
    """Candidate versus reference force history. ncc: Pearson r over the contact window (from
    the first to the last contact of either history), the value targets and studies use;
    ncc_whole: Pearson r over the whole common window, which the zero force before and after
    the contact inflates (tests/test_seed_mesh.py gives the seed-mesh case's r over the contact,
    over 0.5 ms and over 2 ms). The errors are relative and signed,
    (candidate - reference)/reference, of the peak force, the impulse and the total contact
    duration."""

    ncc: float
    peak_err: float
    impulse_err: float
    duration_err: float
    ncc_whole: float | None = None


def _rel(name: str, cand: float, ref: float) -> float:
    if ref == 0.0:
        raise InputError(f"reference {name} is 0; a relative {name} error is undefined")
    return (cand - ref) / ref


def compare_force(
    t_ref: object, f_ref: object, t: object, f: object, threshold_fraction: float = 0.01
) -> Comparison:
    """Compare a candidate contact-force history with a reference over their common window.

    NCC as :func:`ncc` over the contact window (``ncc``) and over the whole common window
    (``ncc_whole``); peak, impulse (trapezoid) and duration of both histories restricted to the
    common window (the candidate on the reference's samples there). Contact: F >
    threshold_fraction * reference peak (same threshold for both); duration = total length of
    the contact intervals; contact window = the reference samples from the first contact to
    the last of either history (contact_window). Raises InputError on bad histories,
    threshold_fraction outside [0, 1), a reference with non-positive peak, zero impulse or no
    contact, or a contact window of fewer than 3 samples.
    """
    if (
        isinstance(threshold_fraction, bool)
        or not isinstance(threshold_fraction, (int, float))
        or not 0.0 <= threshold_fraction < 1.0
    ):
        raise InputError(
            f"threshold_fraction: expected a number in [0, 1), got {threshold_fraction!r}"
        )
    tr, fr, fc = _on_common_grid(t_ref, f_ref, t, f, None)
    p_ref, p_cand = float(np.max(fr)), float(np.max(fc))
    if p_ref <= 0.0:
        raise InputError(f"reference peak force is {p_ref!r} N; expected a compressive force > 0")
    threshold = threshold_fraction * p_ref
    iv_ref, iv_cand = contact_intervals(tr, fr, threshold), contact_intervals(tr, fc, threshold)
    d_ref = sum(b - a for a, b in iv_ref)
    d_cand = sum(b - a for a, b in iv_cand)
    inside = contact_window(tr, iv_ref + iv_cand)
    return Comparison(
        ncc=pearson(fr[inside], fc[inside]),
        peak_err=_rel("peak", p_cand, p_ref),
        impulse_err=_rel("impulse", float(np.trapezoid(fc, tr)), float(np.trapezoid(fr, tr))),
        duration_err=_rel("duration", d_cand, d_ref),
        ncc_whole=pearson(fr, fc),
    )


def contact_window(t: np.ndarray, intervals: list[tuple[float, float]]) -> np.ndarray:
    """Boolean mask of the samples t from the start of the first interval to the end of the
    last (the contact window of compare_force); InputError when it holds fewer than 3."""
    if not intervals:
        raise InputError("no contact in either history; the contact window is undefined")
    lo, hi = min(a for a, _ in intervals), max(b for _, b in intervals)
    inside = (t >= lo) & (t <= hi)
    if np.count_nonzero(inside) < 3:
        raise InputError(
            f"contact window [{lo:g}, {hi:g}] s holds {np.count_nonzero(inside)} "
            "reference samples; expected at least 3"
        )
    return inside


_TERM = re.compile(r"^\s*([a-z_]+)\s*(>=|<=)\s*(\S+)\s*$")
_KEYS = {
    "ncc": (">=", "ncc_min"),
    "peak": ("<=", "peak_err_max"),
    "impulse": ("<=", "impulse_err_max"),
    "duration": ("<=", "duration_err_max"),
}


@dataclass(frozen=True)
class Target:
    """Accuracy target: NCC at least ncc_min and, when given, the magnitude of the relative
    error at most peak_err_max, impulse_err_max, duration_err_max. Raises InputError on
    values out of range."""

    ncc_min: float = 0.99
    peak_err_max: float | None = None
    impulse_err_max: float | None = None
    duration_err_max: float | None = None

    def __post_init__(self) -> None:
        if (
            isinstance(self.ncc_min, bool)
            or not isinstance(self.ncc_min, (int, float))
            or not -1.0 <= self.ncc_min <= 1.0
        ):
            raise InputError(f"Target.ncc_min: expected a number in [-1, 1], got {self.ncc_min!r}")
        for key in ("peak_err_max", "impulse_err_max", "duration_err_max"):
            v = getattr(self, key)
            if v is not None and (
                isinstance(v, bool)
                or not isinstance(v, (int, float))
                or not math.isfinite(v)
                or v < 0
            ):
                raise InputError(f"Target.{key}: expected None or a finite number >= 0, got {v!r}")

    def met_by(self, c: Comparison) -> bool:
        """True when c reaches every bound of this target."""
        checks = (
            (self.peak_err_max, c.peak_err),
            (self.impulse_err_max, c.impulse_err),
            (self.duration_err_max, c.duration_err),
        )
        return c.ncc >= self.ncc_min and all(b is None or abs(e) <= b for b, e in checks)

    @classmethod
    def parse(cls, text: str) -> Target:
        """Parse ``"ncc>=0.99,peak<=0.02"``: comma-separated ``ncc>=X``, ``peak<=X``,
        ``impulse<=X``, ``duration<=X`` (each at most once; ncc defaults to 0.99).
        Raises InputError on unknown keys, wrong operators, repeated keys or bad numbers."""
        if not isinstance(text, str) or not text.strip():
            raise InputError(f"target: expected e.g. 'ncc>=0.99,peak<=0.02', got {text!r}")
        values: dict[str, float] = {}
        for term in text.split(","):
            m = _TERM.match(term.lower())
            if m is None:
                raise InputError(
                    f"target term {term.strip()!r}: expected KEY>=X or KEY<=X, e.g. 'peak<=0.02'"
                )
            key, op, num = m.groups()
            if key not in _KEYS:
                raise InputError(f"target key {key!r}: expected one of {', '.join(_KEYS)}")
            if op != _KEYS[key][0]:
                raise InputError(f"target term {term.strip()!r}: expected {key}{_KEYS[key][0]}X")
            if _KEYS[key][1] in values:
                raise InputError(f"target key {key!r} given twice in {text!r}")
            try:
                value = float(num)
            except ValueError:
                raise InputError(f"target term {term.strip()!r}: {num!r} is not a number") from None
            if not math.isfinite(value):
                raise InputError(
                    f"target term {term.strip()!r}: expected a finite number, got {num!r}"
                )
            values[_KEYS[key][1]] = value
        return cls(**values)
