"""A quantity given over time: constant (from a start time on) or a table piecewise linear in t.

Applied loads (forces [N], torques [N m]) are given this way. Before the first point and after
the last the table holds its end values (np.interp's rule); a constant is zero before its start
time t_start_s and its value from then on (the step of the old NodeLoad).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError


@dataclass(frozen=True, eq=False)
class TimeHistory:
    """value(t) (n,) of a table of times_s (k,) [s], strictly increasing, and values (k, n);
    zero before t_start_s [s] (-inf: none). Made by :meth:`constant` or :meth:`table`."""

    times_s: np.ndarray
    values: np.ndarray
    t_start_s: float = -math.inf

    @classmethod
    def constant(cls, value, t_start_s: float = -math.inf, what: str = "value") -> TimeHistory:
        """``value`` (a number or a vector) from t_start_s [s] on, zero before."""
        v = np.atleast_1d(np.asarray(value, dtype=float))
        if v.ndim != 1 or not np.all(np.isfinite(v)):
            raise InputError(f"{what}: expected a finite number or vector, got {value!r}")
        if math.isnan(t_start_s):
            raise InputError(f"{what}: start time must be a number, got {t_start_s!r}")
        return cls(np.zeros(1), v[None, :], float(t_start_s))

    @classmethod
    def table(cls, times_s, values, width: int | None = None, what: str = "table") -> TimeHistory:
        """A table: times_s (k,) strictly increasing [s], values (k,) or (k, width)."""
        t = np.asarray(times_s, dtype=float)
        v = np.asarray(values, dtype=float)
        if t.ndim != 1 or t.size < 1:
            raise InputError(f"{what}: times must be a list of at least one time, got {times_s!r}")
        if v.ndim == 1 and width in (None, 1):
            v = v[:, None]
        if v.ndim != 2 or v.shape[0] != t.size or (width is not None and v.shape[1] != width):
            shape = f"({t.size}, {width})" if width not in (None, 1) else f"({t.size},)"
            raise InputError(
                f"{what}: values must have shape {shape} to match {t.size} time(s), "
                f"got shape {np.shape(values)}"
            )
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
            raise InputError(f"{what}: times and values must be finite")
        if np.any(np.diff(t) <= 0.0):
            k = int(np.flatnonzero(np.diff(t) <= 0.0)[0])
            raise InputError(
                f"{what}: times must be strictly increasing, got {float(t[k])!r} then "
                f"{float(t[k + 1])!r} s"
            )
        return cls(t, v)

    @property
    def width(self) -> int:
        """Components of a value."""
        return int(self.values.shape[1])

    def at(self, t: float) -> np.ndarray:
        """The value at t [s] (width,): linear between the points, the end values outside."""
        if t < self.t_start_s:
            return np.zeros(self.width)
        if self.times_s.size == 1:
            return self.values[0].copy()
        return np.array([np.interp(t, self.times_s, col) for col in self.values.T])
