"""Histories of time t [s]: the prescribed motions of drives and paths (constraints.drives,
constraints.prescribed), each giving its value, first and second derivative in t, and its
integral from 0 (an angular-velocity history integrated analytically to an angle).

| history | f(t) | source |
|---|---|---|
| Constant(c) | c | |
| Table(t_i, f_i) | piecewise linear through (t_i, f_i); before t_0 f_0, after t_n f_n | |
| SpinUp(f_s, T) | (f_s / T)(t - T/(2 pi) sin(2 pi t / T)) on [0, T), f_s after, 0 before | Kane, Ryan, Banerjee 1987 |
| Integral(g) | int_0^t g(s) ds (its rate g, its acceleration g') | |

A Table's f' is that of the segment holding t (right-sided at a knot: t in [t_i, t_i+1)), its
f'' zero: a table of angles has a velocity that jumps at the knots, i.e. an impulsive drive
torque there; a table of angular velocities (integrated: Integral) has a continuous angle.
Values may be scalars or vectors (a table of rows [t, x, y, z] gives (3,) values).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError

__all__ = ["Constant", "Integral", "SpinUp", "Table", "TimeFunction"]


class TimeFunction:
    """A history f(t): value f, rate f', acceleration f'' and integral int_0^t f ds."""

    def value(self, t: float):
        raise NotImplementedError

    def rate(self, t: float):
        raise NotImplementedError

    def acceleration(self, t: float):
        raise NotImplementedError

    def integral(self, t: float):
        raise NotImplementedError


@dataclass(frozen=True)
class Constant(TimeFunction):
    """f(t) = c for all t (a scalar or a vector)."""

    c: float | tuple[float, ...]

    def value(self, t):
        return np.asarray(self.c, float) if np.ndim(self.c) else float(self.c)

    def rate(self, t):
        return 0.0 * self.value(t)

    def acceleration(self, t):
        return 0.0 * self.value(t)

    def integral(self, t):
        return self.value(t) * t


@dataclass(frozen=True, eq=False)
class Table(TimeFunction):
    """Piecewise-linear history through the points (times[i], values[i]): times (n,) strictly
    increasing [s], values (n,) or (n, k). Held at the first value before times[0] and at the
    last after times[-1]. Made by :meth:`of_rows` from rows [t, f...] with one-line errors."""

    times: np.ndarray
    values: np.ndarray

    def __post_init__(self) -> None:
        # int_{times[0]}^{times[i+1]} f ds: the trapezoids of the whole segments, made once
        vs = self.values
        area = np.cumsum(0.5 * (vs[1:] + vs[:-1]) * _col(np.diff(self.times), vs), axis=0)
        object.__setattr__(self, "_area", area)

    @classmethod
    def of_rows(cls, rows, width: int = 1, what: str = "table") -> Table:
        """From rows [t, f_1, ..., f_width]: InputError unless there are >= 2 rows of
        1 + width finite numbers with strictly increasing times."""
        try:
            a = np.asarray(rows, dtype=float)
        except (TypeError, ValueError):
            raise InputError(
                f"{what}: expected rows of {1 + width} numbers, got {rows!r}"
            ) from None
        if a.ndim != 2 or a.shape[1] != 1 + width:
            raise InputError(
                f"{what}: expected rows [t_s, {width} value(s)], got shape {list(np.shape(a))}"
            )
        if a.shape[0] < 2:
            raise InputError(f"{what}: expected at least 2 rows, got {a.shape[0]}")
        if not np.all(np.isfinite(a)):
            i, j = (int(k) for k in np.argwhere(~np.isfinite(a))[0])
            col = "its time" if j == 0 else f"value {j}"
            raise InputError(
                f"{what}: every entry must be finite, got {a[i, j].item()!r} in row {i} ({col})"
            )
        steps = np.diff(a[:, 0])
        if not np.all(steps > 0):
            i = int(np.argmax(steps <= 0))
            raise InputError(
                f"{what}: times must increase strictly, got t = {_as_written(rows, i, a)!r} "
                f"then {_as_written(rows, i + 1, a)!r}"
            )
        return cls(a[:, 0].copy(), a[:, 1].copy() if width == 1 else a[:, 1:].copy())

    def _segment(self, t: float) -> int:
        """i with times[i] <= t < times[i + 1], clipped to 0 .. n - 2."""
        i = int(np.searchsorted(self.times, t, side="right")) - 1
        return min(max(i, 0), len(self.times) - 2)

    def _slope(self, i: int):
        return (self.values[i + 1] - self.values[i]) / (self.times[i + 1] - self.times[i])

    def value(self, t):
        ts = self.times
        if t <= ts[0]:
            return self._out(self.values[0])
        if t >= ts[-1]:
            return self._out(self.values[-1])
        i = self._segment(t)
        return self._out(self.values[i] + self._slope(i) * (t - ts[i]))

    def rate(self, t):
        if t < self.times[0] or t >= self.times[-1]:
            return self._out(0.0 * self.values[0])
        return self._out(self._slope(self._segment(t)))

    def acceleration(self, t):
        return self._out(0.0 * self.values[0])

    def integral(self, t):
        return self._out(self._primitive(t) - self._primitive(0.0))

    def _primitive(self, t):
        """int_{times[0]}^t f ds (negative below times[0]: the held first value)."""
        ts, vs = self.times, self.values
        if t <= ts[0]:
            return vs[0] * (t - ts[0])
        area = self._area  # whole segments before t, then the part of t's segment
        if t >= ts[-1]:
            return area[-1] + vs[-1] * (t - ts[-1])
        i = self._segment(t)
        before = area[i - 1] if i > 0 else 0.0 * vs[0]
        dt = t - ts[i]
        return before + vs[i] * dt + 0.5 * self._slope(i) * dt * dt

    @staticmethod
    def _out(x):
        return np.array(x, float) if np.ndim(x) else float(x)


def _as_written(rows, i: int, a: np.ndarray):
    """Row i's time as the user wrote it (an int stays an int; numpy scalars become Python
    numbers, never a numpy repr such as np.float64(5e-06))."""
    try:
        t = rows[i][0]
    except (TypeError, IndexError, KeyError):
        return float(a[i, 0])
    return t.item() if isinstance(t, np.generic) else t


def _col(dt: np.ndarray, values: np.ndarray) -> np.ndarray:
    """dt shaped to multiply rows of values (n - 1,) or (n - 1, k)."""
    return dt if values.ndim == 1 else dt[:, None]


@dataclass(frozen=True)
class SpinUp(TimeFunction):
    """The classic smooth spin-up (Kane, Ryan, Banerjee 1987, J. Guidance 10(2)):

        f(t) = (f_s / T) (t - T / (2 pi) sin(2 pi t / T))   0 <= t < T,   f_s after, 0 before

    f' = (f_s / T)(1 - cos(2 pi t / T)) (zero at both ends), f'' = (2 pi f_s / T^2) sin(2 pi t / T);
    int_0^t f = (f_s / T)(t^2 / 2 + (T / 2 pi)^2 (cos(2 pi t / T) - 1)) on [0, T), f_s T / 2 at T.
    final: f_s (e.g. a steady angular speed [rad/s]); duration_s: T [s]."""

    final: float
    duration_s: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.final) and math.isfinite(self.duration_s)):
            raise InputError(
                f"spin-up: expected finite numbers, got {self.final!r}, {self.duration_s!r}"
            )
        if not self.duration_s > 0:
            raise InputError(f"spin-up: duration_s must be > 0 s, got {self.duration_s!r}")

    def value(self, t):
        T, fs = self.duration_s, self.final
        if t <= 0.0:
            return 0.0
        if t >= T:
            return fs
        return fs / T * (t - T / (2 * math.pi) * math.sin(2 * math.pi * t / T))

    def rate(self, t):
        T = self.duration_s
        if t <= 0.0 or t >= T:
            return 0.0
        return self.final / T * (1.0 - math.cos(2 * math.pi * t / T))

    def acceleration(self, t):
        T = self.duration_s
        if t <= 0.0 or t >= T:
            return 0.0
        return 2 * math.pi * self.final / T**2 * math.sin(2 * math.pi * t / T)

    def integral(self, t):
        T, fs = self.duration_s, self.final
        if t <= 0.0:
            return 0.0
        if t >= T:
            return fs * T / 2 + fs * (t - T)
        k = T / (2 * math.pi)
        return fs / T * (0.5 * t * t + k * k * (math.cos(t / k) - 1.0))


@dataclass(frozen=True)
class Integral(TimeFunction):
    """F(t) = int_0^t g(s) ds of a history g (an angle from an angular velocity, a
    displacement from a velocity): F' = g, F'' = g'. Its own integral is not needed (and not
    given: InputError)."""

    g: TimeFunction

    def value(self, t):
        return self.g.integral(t)

    def rate(self, t):
        return self.g.value(t)

    def acceleration(self, t):
        return self.g.rate(t)

    def integral(self, t):
        raise InputError("the integral of an integrated history is not provided")
