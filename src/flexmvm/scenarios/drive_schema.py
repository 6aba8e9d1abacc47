"""The scenario's motion histories (pydantic v2): a joint's ``drive`` (an angle or an
angular-velocity history of a revolute joint, or of a prescribed frame's turn) and a
prescribed joint's ``path`` (a table of displacements or of velocities); each becomes a
flexmvm.time_functions history. docs/scenario_format.md lists the keys."""

from __future__ import annotations

from pydantic import model_validator

from flexmvm.errors import InputError
from flexmvm.scenarios.fields import Frozen, Num, Positive
from flexmvm.scenarios.problems import problem
from flexmvm.time_functions import Constant, Integral, SpinUp, Table, TimeFunction

__all__ = ["DriveConfig", "HistoryConfig", "PathConfig", "SpinUpConfig"]


def _table(rows, width: int, key: str) -> Table:
    """The Table of rows [t_s, width values]; a one-line problem at ``key`` otherwise."""
    try:
        return Table.of_rows(rows, width, what="table")
    except InputError as exc:
        raise problem(str(exc).removeprefix("table: "), key) from None


def _exactly_one(model: Frozen, keys: tuple[str, ...]) -> str:
    """The one key of ``keys`` that is given; a problem naming them otherwise."""
    given = [k for k in keys if getattr(model, k) is not None]
    if len(given) != 1:
        raise problem(f"give exactly one of {', '.join(keys)}, got {given or 'none'}")
    return given[0]


class SpinUpConfig(Frozen):
    """The spin-up profile of Kane, Ryan, Banerjee 1987 (time_functions.SpinUp): from 0 to
    ``final`` over ``duration_s``, smoothly (zero rate at both ends)."""

    final: Num
    duration_s: Positive


class HistoryConfig(Frozen):
    """A scalar history: ``constant``, ``table`` (rows [t_s, value], piecewise linear, held at
    its end values outside) or ``spin_up``; exactly one."""

    constant: Num | None = None
    table: tuple[tuple[Num, Num], ...] | None = None
    spin_up: SpinUpConfig | None = None

    @model_validator(mode="after")
    def _check(self) -> HistoryConfig:
        if _exactly_one(self, ("constant", "table", "spin_up")) == "table":
            _table(self.table, 1, "table")
        return self

    def function(self) -> TimeFunction:
        """The time_functions history of this table."""
        if self.constant is not None:
            return Constant(self.constant)
        if self.table is not None:
            return _table(self.table, 1, "table")
        assert self.spin_up is not None  # exactly one of the three (the validator)
        return SpinUp(self.spin_up.final, self.spin_up.duration_s)


class DriveConfig(Frozen):
    """A joint's drive: its rotation from the placement, ``angle_rad`` [rad] (0 at t = 0), or
    its rate ``angular_velocity_radps`` [rad/s] (integrated from 0 analytically); exactly
    one."""

    angle_rad: HistoryConfig | None = None
    angular_velocity_radps: HistoryConfig | None = None

    @model_validator(mode="after")
    def _check(self) -> DriveConfig:
        if (
            self.angle_rad is not None
            and _exactly_one(self, ("angle_rad", "angular_velocity_radps")) == "angle_rad"
        ):
            start = self.angle_rad.function().value(0.0)
            if start != 0.0:
                raise problem(
                    f"must be 0 rad at t = 0 (the joint's placement), got {start!r}", "angle_rad"
                )
        return self

    def angle(self) -> TimeFunction:
        """The prescribed angle history [rad]."""
        if self.angle_rad is not None:
            return self.angle_rad.function()
        assert self.angular_velocity_radps is not None  # exactly one (the validator)
        return Integral(self.angular_velocity_radps.function())


class PathConfig(Frozen):
    """A prescribed point's path: ``displacement_m`` rows [t_s, dx, dy, dz] (global [m], zero
    at t = 0) or ``velocity_mps`` rows [t_s, vx, vy, vz] (global [m/s], integrated from 0
    analytically); piecewise linear, held at the end values outside; exactly one."""

    displacement_m: tuple[tuple[Num, Num, Num, Num], ...] | None = None
    velocity_mps: tuple[tuple[Num, Num, Num, Num], ...] | None = None

    @model_validator(mode="after")
    def _check(self) -> PathConfig:
        key = _exactly_one(self, ("displacement_m", "velocity_mps"))
        table = _table(getattr(self, key), 3, key)
        if key == "displacement_m" and any(table.value(0.0)):
            raise problem(
                f"must be [0, 0, 0] at t = 0 (the point's placement), got "
                f"{table.value(0.0).tolist()}",
                key,
            )
        return self

    def displacement(self) -> TimeFunction:
        """The displacement history d(t) [m], (3,) values."""
        if self.displacement_m is not None:
            return _table(self.displacement_m, 3, "displacement_m")
        return Integral(_table(self.velocity_mps, 3, "velocity_mps"))
