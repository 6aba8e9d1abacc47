"""What the driver takes and gives: the time grid, the probes, and the run's histories.

TimeGrid and Probe are the inputs of integrate.driver.simulate besides the system and its
states; RunResult is its output, kept in memory (writers in flexmvm.results turn it into files).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import Any

import numpy as np

from flexmvm.errors import InputError
from flexmvm.integrate import DEFAULT_THETA
from flexmvm.integrate.energy_ledger import EnergyLedgerHistory
from flexmvm.integrate.theta import ThetaRule


class FieldPrecision(Enum):
    """The precision a run's fields (q, q_dot; the ParaView series' point data) are written
    in (flexmvm.results.writers); histories are always float64. float32 keeps 7 digits: a
    1 um displacement to 1e-13 m, at half the bytes of float64."""

    FLOAT32 = "float32"
    FLOAT64 = "float64"


#: The names of the global velocity components a probe's curve can take (RunResult.curves).
PROBE_AXES = ("x", "y", "z")


@dataclass(frozen=True)
class TimeGrid:
    """t_end_s, dt_s (smallest step), dt_max_s (largest), output_dt_s; all [s]; theta of the
    Moreau-Jean scheme (1/2: implicit midpoint; default flexmvm.integrate.DEFAULT_THETA), or
    with hf_damping_time_s tau [s] theta(h) for each step size h the driver takes
    (integrate.theta: min(1, 1/2 + h / (4 tau)) up to dt_s, 1/2 + dt_s^2 / (4 tau h) above it;
    theta is then the value at dt_s, not used)."""

    t_end_s: float
    dt_s: float
    dt_max_s: float | None = None
    output_dt_s: float | None = None
    theta: float = DEFAULT_THETA
    # outputs every output_contact_dt_s [s] (a whole multiple of dt_s) while the driver takes
    # the contact step dt_s (a contact active or predicted within the step horizon), on top of
    # the output_dt_s grid: a long approach recorded coarsely, the impact finely. None: off.
    output_contact_dt_s: float | None = None
    hf_damping_time_s: float | None = None
    # the elastic coordinates q, q_dot (the fields: displacements, stresses) kept at the first
    # output at or after every multiple of field_output_dt_s [s] and at the last output; the
    # histories stay at every output. None: q at every output.
    field_output_dt_s: float | None = None
    # the precision the fields are written in (RunResult.field_precision)
    field_precision: FieldPrecision = FieldPrecision.FLOAT64

    @classmethod
    def from_config(cls, time: Any) -> TimeGrid:
        """The grid of a scenario's [time] table (scenarios.schema.TimeConfig: the same field
        names; its damping time with "auto" resolved), every field by name rather than seven by
        position."""
        return cls(
            t_end_s=time.t_end_s,
            dt_s=time.dt_s,
            dt_max_s=time.dt_max_s,
            output_dt_s=time.output_dt_s,
            theta=time.theta,
            output_contact_dt_s=time.output_contact_dt_s,
            hf_damping_time_s=time.damping_time_s,  # "auto" resolved
            field_output_dt_s=time.field_output_dt_s,
            field_precision=time.field_precision,
        )

    def theta_rule(self) -> ThetaRule:
        """theta of each step size (integrate.theta)."""
        if self.hf_damping_time_s is None:
            return ThetaRule(self.theta)
        return ThetaRule(self.theta, self.hf_damping_time_s, contact_step_s=self.dt_s)

    def contact_output_ticks(self) -> int | None:
        """Ticks between the contact-phase outputs (None: none); InputError if not a whole
        multiple of dt_s."""
        if self.output_contact_dt_s is None:
            return None
        dt, out = self.dt_s, self.output_contact_dt_s
        n = round(out / dt)
        if n < 1 or abs(n * dt - out) > 1e-9 * out:
            raise InputError(
                f"time: output_contact_dt_s = {out!r} must be a whole multiple of dt_s = {dt!r}"
            )
        return n

    def ticks(self) -> tuple[int, int, int]:
        """(total ticks, output ticks, largest step level k with 2^k ticks <= dt_max)."""
        dt = self.dt_s
        if not (dt > 0 and self.t_end_s > 0):
            raise InputError(f"time: dt_s and t_end_s must be > 0, got {dt!r}, {self.t_end_s!r}")
        out = self.output_dt_s or dt
        n_out = round(out / dt)
        if n_out < 1 or abs(n_out * dt - out) > 1e-9 * out:
            raise InputError(
                f"time: output_dt_s = {out!r} must be a whole multiple of dt_s = {dt!r}"
            )
        fdt = self.field_output_dt_s
        if fdt is not None and not fdt > 0:
            raise InputError(f"time: field_output_dt_s must be > 0 [s], got {fdt!r}")
        dt_max = self.dt_max_s or dt
        k_max = int(np.floor(np.log2(dt_max / dt) + 1e-9)) if dt_max >= dt else 0
        return int(np.ceil(self.t_end_s / dt - 1e-9)), n_out, max(k_max, 0)


@dataclass(frozen=True)
class Probe:
    """A named point of a body whose position and velocity are recorded: its node, or with
    ``nodes`` and ``weights`` the point interpolated in an element (x = sum_i w_i x_i, the
    element's shape functions at the point, sum_i w_i = 1; ``node`` then the nearest of
    them). axis: the velocity component its comparisons use (x, y, z or norm)."""

    name: str
    body: int
    node: int
    axis: str = "x"
    nodes: tuple[int, ...] = ()
    weights: tuple[float, ...] = ()


@dataclass(frozen=True)
class FrictionSummary:
    """Friction over a run (contacts with friction_coefficient > 0): the resultant of all
    tangential impulses [N s] (global, summed over steps), the largest per-step tangential
    force |sum l_T t| / h [N], and the most cones sticking / sliding in one step (cones
    carrying a compressive impulse; integrate.moreau_jean.coulomb.stick_slip)."""

    impulse_ns: np.ndarray = field(default_factory=lambda: np.zeros(3))
    force_max_n: float = 0.0
    max_sticking: int = 0
    max_sliding: int = 0

    def add(self, contact, impulses: np.ndarray, h: float) -> FrictionSummary:
        """This summary with one more step (rows `contact`, impulses, size h [s])."""
        ft = contact.tangential_impulse(impulses)
        stick, slip = contact.stick_slip
        return FrictionSummary(
            self.impulse_ns + ft,
            max(self.force_max_n, float(np.linalg.norm(ft)) / h),
            max(self.max_sticking, stick),
            max(self.max_sliding, slip),
        )


@dataclass
class RunResult:
    """Histories at output times (arrays with their time axis t [s])."""

    t: np.ndarray
    body_names: list[str]
    frame_r: np.ndarray  # (n_out, n_bodies, 3)
    frame_v: np.ndarray  # (n_out, n_bodies, 6)
    probe_names: list[str]
    probe_x: np.ndarray  # (n_out, n_probes, 3)
    probe_v: np.ndarray  # (n_out, n_probes, 3)
    contact_force: (
        np.ndarray
    )  # (n_out,) normal force, impulse-averaged over the interval ending at t [N]
    joint_force: np.ndarray  # (n_out, n_joint_rows) averaged constraint forces [N]
    kinetic: np.ndarray
    strain: np.ndarray
    potential: np.ndarray
    momentum: np.ndarray  # (n_out, 3) total linear momentum [kg m/s]
    angular_momentum: np.ndarray  # (n_out, 3) about the origin [kg m^2/s]
    q: list[np.ndarray]  # per body: (n_fields, nq) elastic coordinates at the rows field_index
    frame_A: np.ndarray  # (n_out, n_bodies, 3, 3)
    q_dot: list[np.ndarray] = field(default_factory=list)  # per body: (n_fields, nq) their rates
    steps: StepHistory | None = None  # every step: its end time, size and contact impulse
    # (n_out, n_bodies, 3) linear momentum of each body [kg m/s] (None: not recorded)
    body_momentum: np.ndarray | None = None
    contact_intervals: list[tuple[float, float]] = field(default_factory=list)
    max_penetration_m: float = 0.0  # deepest node penetration after any step, both directions
    # where and when: {"t_s", "body", "node", "against"} (None: no penetration measured)
    max_penetration_at: dict | None = None
    # deepest per measured direction, "<body> nodes into <against>" -> depth [m]
    max_penetration_by_direction_m: dict = field(default_factory=dict)
    max_joint_drift: float = 0.0  # largest joint violation |phi| after any step (position level)
    n_steps: int = 0
    #: per probe, the velocity component its comparisons use (Probe.axis); empty: x for all
    probe_axes: list[str] = field(default_factory=list)
    n_factorizations: int = 0
    n_nonrotating_steps: int = 0  # steps taken by the linear non-rotating step (nonrotating.py)
    steps_on_roundoff_floor: int = 0  # steps that stopped above the Newton rtol (round-off floor)
    newton_residual_max: float = 0.0  # largest relative momentum residual at a step's exit
    lcp_residual_max: float = 0.0  # largest complementarity residual of any LCP solve
    # normal contact row (contact name, slave node, master facet) -> [impulse [N s], first
    # time it carried one [s]] over the run (the reduced-basis guard, runs/guard.py)
    contact_row_impulses: dict = field(default_factory=dict)
    momentum_residual: np.ndarray = field(default_factory=lambda: np.zeros(3))
    # sum over all steps of the translational momentum residuals of all bodies as the solves
    # left them, before their balance [N s]: a free system's momentum error without it
    # (n_out, 3) the linear momentum the steps' translational balance
    # (integrate.moreau_jean.momentum_balance.balance_translation) added up to each output time [N
    # s]: momentum - momentum_shift is the momentum of the steps as converged, before the balance
    momentum_shift: np.ndarray | None = None
    wall_time_s: float = 0.0
    friction: FrictionSummary | None = None  # None: no contact with friction in the system
    step_cuts: int = 0  # steps retried as two halves (driver.MAX_STEP_CUTS deep)
    smallest_step_s: float = 0.0  # the smallest step taken [s] (below dt_s only after cuts)
    failure: str | None = None  # a run that stopped early: why (the histories end there)
    # per driven joint (constraints.drives, by name): its drive torque on body 1 about the
    # axis [N m] at the output times (its joint_force column: impulse over the output interval)
    drive_torque: dict[str, np.ndarray] = field(default_factory=dict)
    # cumulative works and dissipations at the outputs (integrate.energy_ledger)
    energy_ledger: EnergyLedgerHistory | None = None
    # per plastic body name: integrate.plastic_bodies.PlasticReport (None: no plastic body)
    plastic: dict | None = None
    # rows of t at which q and q_dot are kept (TimeGrid.field_output_dt_s); None: every row
    field_index: np.ndarray | None = None
    # the precision the writers write q, q_dot and the ParaView point data in (kept float64
    # in memory)
    field_precision: FieldPrecision = FieldPrecision.FLOAT64
    # the resolved scenario's JSON form the run was made of (runs.run; written to
    # results.h5, read back by flexmvm.results.read); None: not made from a scenario
    scenario: dict | None = None

    @property
    def field_rows(self) -> np.ndarray:
        """Rows of t at which q and q_dot are kept (every row unless the run was given a
        field output rate, TimeGrid.field_output_dt_s)."""
        if self.field_index is None:
            return np.arange(len(self.t))
        return np.asarray(self.field_index, dtype=int)

    @property
    def field_t(self) -> np.ndarray:
        """The times [s] of the rows of q and q_dot (t[field_rows])."""
        return self.t[self.field_rows]

    @property
    def total_energy(self) -> np.ndarray:
        return self.kinetic + self.strain + self.potential

    def body_index(self, name: str) -> int:
        """Index of body ``name`` in the histories; InputError naming the bodies otherwise."""
        try:
            return self.body_names.index(name)
        except ValueError:
            raise InputError(
                f"no body {name!r} in this run (bodies: {', '.join(self.body_names)})"
            ) from None

    def probe(self, name: str) -> ProbeHistory:
        """Position and velocity history of probe ``name`` (global, [m], [m/s])."""
        try:
            i = self.probe_names.index(name)
        except ValueError:
            raise InputError(
                f"no probe {name!r} in this run (probes: {', '.join(self.probe_names) or 'none'})"
            ) from None
        return ProbeHistory(name, self.t, self.probe_x[:, i], self.probe_v[:, i])

    def torque(self, drive: str) -> np.ndarray:
        """The drive torque history [N m] of the driven joint named ``drive`` (at t)."""
        try:
            return self.drive_torque[drive]
        except KeyError:
            raise InputError(
                f"no drive {drive!r} in this run (drives: {', '.join(self.drive_torque) or 'none'})"
            ) from None

    def elastic(self, body: str) -> tuple[np.ndarray, np.ndarray]:
        """(q, q_dot) of body ``body`` at the field times field_t (every output time unless
        the run was given a field output rate), each (n_fields, nq): its elastic coordinates
        and their rates as the scheme integrated them (not differenced)."""
        b = self.body_index(body)
        return self.q[b], self.q_dot[b]

    def curves(
        self, axis: int | str | None = None
    ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        """(t, contact force, {probe: velocity component ``axis``}): 0, 1, 2 (or "x", "y",
        "z") a global component, "norm" the speed, None each probe's own (probe_axes, the
        scenario's probe ``axis``; x when not given); the curves that comparisons, history
        files and figures use. InputError for another axis."""
        if axis is None:
            axes = self.probe_axes or ["x"] * len(self.probe_names)
            if len(set(axes)) > 1:
                curves = {}
                for i, (n, a) in enumerate(zip(self.probe_names, axes, strict=True)):
                    curves[n] = self.curves(a)[2][n]
                return self.t, self.contact_force, curves
            axis = axes[0] if axes else 0
        if isinstance(axis, str) and axis in PROBE_AXES:
            axis = PROBE_AXES.index(axis)
        if axis == "norm":
            v = np.linalg.norm(self.probe_v, axis=2)
        elif not isinstance(axis, bool) and axis in (0, 1, 2):
            v = self.probe_v[:, :, axis]
        else:
            raise InputError(f"axis: expected 0, 1, 2, 'x', 'y', 'z' or 'norm', got {axis!r}")
        return self.t, self.contact_force, {n: v[:, i] for i, n in enumerate(self.probe_names)}


@dataclass(frozen=True)
class ProbeHistory:
    """One probe's histories: t [s] (n_out,), x [m] and v [m/s] (n_out, 3), global axes."""

    name: str
    t: np.ndarray
    x: np.ndarray
    v: np.ndarray


@dataclass(frozen=True)
class StepHistory:
    """One entry per time step: t_s the step's end time [s], h_s its size [s],
    contact_impulse_Ns the normal contact impulse of all contacts over the step [N s]
    (the contact force at outputs is the sum of these over the output interval / interval)."""

    t_s: np.ndarray
    h_s: np.ndarray
    contact_impulse_Ns: np.ndarray

    def size_counts(self) -> dict[float, int]:
        """{step size [s]: number of steps taken with it}, smallest first."""
        sizes, counts = np.unique(self.h_s, return_counts=True)
        return {float(h): int(n) for h, n in zip(sizes, counts, strict=True)}
