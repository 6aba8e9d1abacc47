"""The time settings of a scenario (its ``[time]`` table: steps, outputs, theta or the damping
time that sets it) and what ``flexmvm run`` compares it with (``[compare]``); the scenario
schema (scenarios/schema.py) holds both."""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from annotated_types import Ge, Le
from pydantic import Discriminator, Strict, Tag, model_serializer, model_validator

from flexmvm.integrate import DEFAULT_THETA
from flexmvm.integrate.run_result import FieldPrecision
from flexmvm.integrate.theta import auto_damping_time
from flexmvm.integrate.theta import theta_for_damping_time as damped_theta
from flexmvm.scenarios.fields import Frozen, Positive
from flexmvm.scenarios.problems import problem


def theta_for_damping_time(dt_s: float, tau_s: float) -> float:
    """The Moreau-Jean theta whose step damps what it cannot resolve with time constant tau_s
    [s]: theta = 1/2 + dt_s / (4 tau_s) (integrate.theta, which applies it to every step size
    up to dt_s, capped at 1, and 1/2 + dt_s^2 / (4 tau_s h) to the longer ones). Per step the amplification at omega h >> 1 is
    -(1 - theta) / theta = -exp(-dt_s / tau_s) (1 + O((dt_s / tau_s)^3)); for resolved
    motion the local error (theta - 1/2) h^2 y'' is O(h^3), so the scheme stays second
    order as dt_s -> 0 (a theta fixed above 1/2 is first order)."""
    return damped_theta(dt_s, tau_s)


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and x > 0


def _damping_time(data: dict) -> Any:
    """hf_damping_time_s as a number: "auto" resolved from dt_s, t_end_s and
    contact_duration_s (integrate.theta.auto_damping_time), None while one is missing."""
    tau = data.get("hf_damping_time_s")
    if tau != "auto":
        return tau
    dt, t_end, duration = (data.get(k) for k in ("dt_s", "t_end_s", "contact_duration_s"))
    if not all(_is_number(x) for x in (dt, t_end, duration)):
        return None
    assert dt is not None and t_end is not None and duration is not None  # numbers (above)
    return auto_damping_time(float(dt), float(t_end), float(duration))


def _damped_theta(data: dict) -> Any:
    """time.theta from hf_damping_time_s (a "before" check: numbers of the wrong type are
    left to the fields' own checks)."""
    tau, dt = _damping_time(data), data.get("dt_s")
    if tau is None:
        return data.get("theta", DEFAULT_THETA)
    if not all(
        isinstance(x, (int, float)) and not isinstance(x, bool) and x > 0 for x in (tau, dt)
    ):
        return data.get("theta", DEFAULT_THETA)
    assert dt is not None  # a positive number (above)
    theta = theta_for_damping_time(float(dt), float(tau))
    given = data.get("theta")
    if given is not None and not (
        isinstance(given, (int, float))
        and not isinstance(given, bool)
        and math.isclose(given, theta, rel_tol=1e-12)
    ):
        raise problem(
            f"give theta or hf_damping_time_s, not both (hf_damping_time_s = "
            f"{tau!r} s sets theta = 1/2 + dt_s / (4 tau) = {theta!r}, theta = "
            f"{given!r})",
            "theta",
        )
    if theta > 1.0:
        raise problem(
            f"must be >= dt_s / 2 = {dt / 2!r} (theta = 1/2 + dt_s / (4 tau) <= 1), got {tau!r}",
            "hf_damping_time_s",
        )
    return theta


def _damping_tag(value: Any) -> str:
    return "auto" if isinstance(value, str) else "number"


# hf_damping_time_s: a number of seconds, or "auto" (scenarios/problems.py drops the tags from
# error locations, as it does the material's)
DampingTime = Annotated[
    Annotated[Positive, Tag("number")] | Annotated[Literal["auto"], Tag("auto")],
    Discriminator(_damping_tag),
]


class TimeConfig(Frozen):
    """Step ``dt_s`` while a contact is active or near, up to ``dt_max_s`` in free flight."""

    t_end_s: Positive
    dt_s: Positive
    dt_max_s: Positive
    output_dt_s: Positive
    theta: Annotated[float, Strict(), Ge(0.5), Le(1.0)] = DEFAULT_THETA
    # extra outputs this often while the step is dt_s (contact active or near); None: none
    output_contact_dt_s: Positive | None = None
    # tau [s]: theta(h) = 1/2 + h / (4 tau) for each step size h up to dt_s (capped at 1) and
    # 1/2 + dt_s^2 / (4 tau h) for the free-flight steps up to dt_max_s, instead of a fixed
    # theta; theta is then its value at dt_s (theta_for_damping_time): what the contact step
    # cannot resolve decays as exp(-t / tau), the free-flight steps damp resolved motion as
    # dt_s does, and theta - 1/2 = O(h) keeps the scheme second order (integrate.theta;
    # docs/contact_law.md, "theta = 1/2 + h / (4 tau)")
    # "auto": tau chosen from dt_s, t_end_s and contact_duration_s (integrate.theta,
    # auto_damping_time: the contact's resolved motion loses at most AUTO_WINDOW_LOSS of its
    # energy over the window); the property damping_time_s gives the number
    hf_damping_time_s: DampingTime | None = None
    # the contact's duration [s] that hf_damping_time_s = "auto" protects (read by it only);
    # default for two rods in end impact: the 1D wave-Hertz pulse's (theory.scenario)
    contact_duration_s: Positive | None = None
    # fields (q, q_dot: displacements, stresses) kept and written every field_output_dt_s [s]
    # (the first output at or after each multiple, and the last), the histories every
    # output_dt_s; None: q kept at every output, about 100 frames written
    # (results.writers.default_field_rows)
    field_output_dt_s: Positive | None = None
    # the precision of the fields written (results.h5's q and q_dot, the ParaView series):
    # float32 (7 digits, half the bytes) unless "float64" is asked for
    field_precision: FieldPrecision = FieldPrecision.FLOAT32

    @model_validator(mode="before")
    @classmethod
    def _derived_defaults(cls, data: Any) -> Any:
        # dt_max_s defaults to dt_s; theta follows from hf_damping_time_s and dt_s
        if isinstance(data, dict) and data.get("dt_max_s") is None and "dt_s" in data:
            data = {**data, "dt_max_s": data["dt_s"]}
        if isinstance(data, dict) and data.get("hf_damping_time_s") is not None:
            data = {**data, "theta": _damped_theta(data)}
        return data

    @model_serializer(mode="wrap")
    def _dump(self, handler):
        # without hf_damping_time_s a dump is as before the key existed (cache identities);
        # with it, theta is derived, not given: a dump edited (dt_s) and read back derives it
        data = handler(self)
        if isinstance(data, dict):
            data.pop(
                "hf_damping_time_s" if data.get("hf_damping_time_s") is None else "theta", None
            )
            for key in ("field_output_dt_s", "contact_duration_s"):  # as before the keys existed
                if data.get(key) is None:
                    data.pop(key, None)
            if data.get("field_precision") in (FieldPrecision.FLOAT32, "float32"):
                data.pop("field_precision", None)
        return data

    @property
    def damping_time_s(self) -> float | None:
        """hf_damping_time_s as a number [s] ("auto" resolved), None without one."""
        return _damping_time(self.__dict__)

    @model_validator(mode="after")
    def _check(self) -> TimeConfig:
        if self.hf_damping_time_s == "auto" and self.contact_duration_s is None:
            raise problem(
                'hf_damping_time_s = "auto" needs contact_duration_s [s], the duration of the '
                "contact whose motion the damping must keep (e.g. Hertz's: "
                "flexmvm.theory.hertz.hertz_impact); found only for two rods in end impact",
                "contact_duration_s",
            )
        if self.dt_s > self.t_end_s:  # first: the checks below compare with dt_s
            raise problem(f"must be <= t_end_s = {self.t_end_s!r}, got {self.dt_s!r}", "dt_s")
        if self.dt_max_s < self.dt_s:
            raise problem(f"must be >= dt_s = {self.dt_s!r}, got {self.dt_max_s!r}", "dt_max_s")
        if self.output_dt_s < self.dt_s:
            raise problem(
                f"must be >= dt_s = {self.dt_s!r}, got {self.output_dt_s!r}", "output_dt_s"
            )
        if self.output_contact_dt_s is not None and self.output_contact_dt_s < self.dt_s:
            raise problem(
                f"must be >= dt_s = {self.dt_s!r}, got {self.output_contact_dt_s!r}",
                "output_contact_dt_s",
            )
        fdt = self.field_output_dt_s
        if fdt is not None and fdt < self.output_dt_s:
            raise problem(
                f"must be >= output_dt_s = {self.output_dt_s!r}, got {fdt!r}", "field_output_dt_s"
            )
        if self.output_dt_s > self.t_end_s:
            raise problem(
                f"must be <= t_end_s = {self.t_end_s!r}, got {self.output_dt_s!r}", "output_dt_s"
            )
        return self


class CompareConfig(Frozen):
    """What `flexmvm run` lays beside the scenario's own run: a full-FE copy of every reduced
    body (``full_reference``) and the theory (``theory``: the 1D wave solution of a two-rod
    impact, or a Timoshenko beam + Hertz for a sphere on a beam; flexmvm.theory.scenario).
    Neither runs unless asked: on a user's part a full-FE copy can cost hours."""

    full_reference: bool = False
    theory: bool = False
