"""The time loop: step-size policy, outputs, contact bookkeeping. The scheme is separate
(moreau_jean/scheme.py, the default; simulate's ``integrator`` chooses another, behind the contract
of step.py); this file decides which step to take and what to keep, and calls simulate's
``on_step`` hook after every accepted step.

Time runs on an integer grid of ticks of dt_s, so output times are hit exactly. Steps are
dt * 2^k <= dt_max (a handful of step sizes, each factored once): the smallest near contact,
doubling every few steps in free flight, never past the next output time. A step that fails
is cut in halves inside its tick span (_advance), down to dt_s / 2^MAX_STEP_CUTS. A run that
cannot go on raises SimulationFailed carrying the histories up to the last good output.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from flexmvm.errors import InputError, SimulationFailed, SolverError
from flexmvm.integrate.energy_ledger import EnergyLedger, step_theta
from flexmvm.integrate.moreau_jean import MoreauJeanIntegrator
from flexmvm.integrate.progress import StepProgress
from flexmvm.integrate.recorder import OutputRecorder
from flexmvm.integrate.run_result import FrictionSummary, RunResult, StepHistory, TimeGrid
from flexmvm.integrate.state import BodyState
from flexmvm.integrate.step import Integrator, StepResult
from flexmvm.integrate.system import System

GROW_AFTER_STEPS = 4
# A failed step is retried as two halves, down to dt_s / 2^MAX_STEP_CUTS (_advance): deep
# enough for a stiff transient (a corner node slipping off its facet, an active-set change),
# shallow enough that a run that cannot go on stops in seconds, not hours.
MAX_STEP_CUTS = 6
# Start of a run: a node more than this inside the other contact surface is an overlap of the
# bodies (InputError). 1e-9 m: the constraint pass's gap tolerance (contact.pairs gap_tol_m);
# seven orders above the round-off of metre-scale coordinates, far below any physical overlap.
OVERLAP_TOL_M = 1e-9


#: What chooses the integrator of a run: (system, grid) -> an integrator (integrate.step's
#: Integrator contract: step, order, counters), made once per run.
IntegratorFactory = Callable[[System, TimeGrid], Integrator]


@dataclass(frozen=True)
class AcceptedStep:
    """One accepted step, as simulate's per-step hook sees it: start time t_s and size h_s
    [s], the states at t_s (``start``) and the step's result (end states ``result.states``,
    constraint rows and impulses [N s], iteration report: iterations, converged, residual).
    The states are the run's own: read them, do not change them."""

    t_s: float
    h_s: float
    start: list[BodyState]
    result: StepResult
    theta: float = 0.5  # the scheme's theta of this step (energy_ledger.step_theta)

    @property
    def t_end_s(self) -> float:
        return self.t_s + self.h_s

    @property
    def states(self) -> list[BodyState]:
        """The states at t_s + h_s."""
        return self.result.states


def moreau_jean(exploit_nonrotating: bool = True) -> IntegratorFactory:
    """The default integrator: the Moreau-Jean scheme (moreau_jean/scheme.py) with the grid's
    theta of each step size (TimeGrid.theta_rule)."""

    def make(system: System, grid: TimeGrid) -> Integrator:
        return MoreauJeanIntegrator(
            system, theta=grid.theta_rule(), exploit_nonrotating=exploit_nonrotating
        )

    return make


def simulate(
    system: System,
    states: list[BodyState],
    grid: TimeGrid,
    probes=(),
    progress: bool = False,
    t0: float = 0.0,
    exploit_nonrotating: bool = True,
    check_overlap: bool = True,
    integrator: IntegratorFactory | None = None,
    on_step: Callable[[AcceptedStep], None] | None = None,
    switches=None,
) -> RunResult:
    """Integrate from t0 over grid.t_end_s; returns histories at every output time.

    check_overlap: InputError when a node of a contact surface is more than OVERLAP_TOL_M
    inside the other surface at t0 (bodies may touch, not overlap); False for a continuation
    from a state in contact, whose penetration is then only measured.

    exploit_nonrotating: let steps whose frames do not rotate take the linear one-solve step
    (integrate.moreau_jean.nonrotating; verified against the full equations). False forces the
    general Newton step everywhere (for comparison). For the default integrator only.

    integrator: the factory of the run's integrator (default: moreau_jean()).
    on_step: called after every accepted step with an AcceptedStep (custom output,
    monitoring); what it raises stops the run.

    BLAS runs single-threaded inside the loop: its operations are small (vectors of nq,
    matrices of a few hundred), where thread start-up costs more than it saves, and on a
    loaded machine far more (docs/notes/2026-11-27-comment-measurements.md).

    switches: a moving region (integrate.moving_region.MovingRegion) asked after every accepted
    step whether its body switches window (after_step -> (system, states) or None); at a
    switch the integrator is made again for the new system; its guard (outside_stop) stops
    the run as plastic_outside does."""
    make = integrator if integrator is not None else moreau_jean(exploit_nonrotating)
    with threadpool_limits(limits=1, user_api="blas"):
        return _simulate(
            system, states, grid, probes, progress, t0, make, on_step, check_overlap, switches
        )


class _Tally:
    """What a run adds up over its accepted steps (RunResult's counters and histories
    besides the outputs)."""

    def __init__(self, system: System, n_joint_rows: int, pen: _Penetrations, dt_s: float):
        self.pen = pen
        self.n_steps, self.calm = 0, 0
        self.impulse, self.jimpulse = 0.0, np.zeros(n_joint_rows)
        self.intervals: list[list[float]] = []
        self.max_pen, self.drift = 0.0, 0.0
        # per accepted step: its end time [s], size [s] and normal contact impulse [N s]
        self.step_t: list[float] = []
        self.step_h: list[float] = []
        self.step_impulse: list[float] = []
        self.row_impulses: dict = {}  # normal contact row key -> [impulse [N s], first time [s]]
        self.n_loose, self.worst_res, self.worst_lcp = 0, 0.0, 0.0
        self.p_res = np.zeros(3)
        self.shift = np.zeros(3)  # the momentum the balance of the steps added so far [N s]
        self.shifts = [self.shift.copy()]  # ... at every output time
        self.friction = (
            FrictionSummary() if any(c.mu > 0 for c in system.contacts) else None
        )  # runs with friction report it even if no contact closes
        self.cuts = [0, dt_s]  # steps cut in two, smallest step taken [s]
        self.ledger: EnergyLedger | None = None  # the works of the steps (energy_ledger)
        # factorisations and non-rotating steps of integrators a window switch retired
        self.retired = [0, 0]

    def add(self, t_s: float, h_s: float, res: StepResult) -> None:
        """One accepted step from t_s over h_s; its end states measured for penetration."""
        self.n_steps += 1
        self.drift = max(self.drift, res.joint_drift)
        self.n_loose += not res.converged
        self.worst_res = max(self.worst_res, res.residual)
        self.worst_lcp = max(self.worst_lcp, res.lcp_residual)
        if res.translation_residual is not None:
            self.p_res += res.translation_residual
        f = res.contact.normal_impulse(res.contact_impulses)
        if res.contact.friction is not None:
            self.friction = (self.friction or FrictionSummary()).add(
                res.contact, res.contact_impulses, h_s
            )
        if not self.pen.measured and res.contact.gaps.size:
            self.max_pen = max(self.max_pen, float(-res.contact.gaps.min()))
        self.pen.after_step(res.states, t_s + h_s)
        in_contact = f > 0.0
        self.calm = 0 if (in_contact or res.contact.rows.m) else self.calm + 1
        _track_intervals(self.intervals, in_contact, t_s, t_s + h_s)
        self.impulse += f
        self.jimpulse += res.joint_impulses
        if f > 0.0:
            _add_row_impulses(self.row_impulses, res.contact, res.contact_impulses, t_s + h_s)
        self.step_t.append(t_s + h_s)
        self.step_h.append(h_s)
        self.step_impulse.append(f)
        if res.momentum_shift is not None:
            self.shift += res.momentum_shift

    def output(self) -> None:
        """An output was recorded: the impulses start again, the momentum shift is kept."""
        self.shifts.append(self.shift.copy())
        self.impulse, self.jimpulse = 0.0, np.zeros_like(self.jimpulse)

    def result(
        self, rec: OutputRecorder, integ, wall0: float, failure: str | None = None
    ) -> RunResult:
        pen = self.pen
        depth = pen.depth if pen.measured else self.max_pen
        return rec.result(
            contact_intervals=[tuple(iv) for iv in self.intervals],
            max_penetration_m=max(depth, 0.0),
            max_penetration_at=pen.at,
            max_penetration_by_direction_m=pen.by_direction,
            max_joint_drift=self.drift,
            n_steps=self.n_steps,
            n_factorizations=integ.n_factorizations + self.retired[0],
            n_nonrotating_steps=integ.n_nonrotating_steps + self.retired[1],
            steps_on_roundoff_floor=self.n_loose,
            newton_residual_max=self.worst_res,
            lcp_residual_max=self.worst_lcp,
            momentum_residual=self.p_res,
            wall_time_s=time.perf_counter() - wall0,
            friction=self.friction,
            contact_row_impulses=self.row_impulses,
            steps=StepHistory(
                np.array(self.step_t),
                np.array(self.step_h),
                np.array(self.step_impulse, dtype=float),
            ),
            step_cuts=self.cuts[0],
            smallest_step_s=self.cuts[1],
            failure=failure,
            momentum_shift=np.array(self.shifts),
            energy_ledger=self.ledger.history(len(rec.rows)) if self.ledger else None,
            plastic=(
                self.ledger.plastic.reports([r["plastic"] for r in rec.rows])
                if self.ledger and self.ledger.plastic
                else None
            ),
        )


def _simulate(
    system, states, grid, probes, progress, t0, make_integrator, on_step, check_overlap, switches
) -> RunResult:
    n_ticks, out_ticks, k_max = grid.ticks()
    fine_ticks = grid.contact_output_ticks()
    integ = make_integrator(system, grid)
    dt = grid.dt_s
    rec = OutputRecorder(system, probes, n_ticks // out_ticks + 2, integ.n_joint_rows, grid)
    plastic = integ.plastic or None  # integrate.plastic_bodies (empty: none)
    rec.plastic = plastic
    states = [s.copy() for s in states]
    pen = _Penetrations(system)
    pen.start(states, t0, check_overlap)
    rec.record(t0, states, 0.0, np.zeros(integ.n_joint_rows))
    bar = StepProgress(progress, n_ticks, dt)
    tally = _Tally(system, integ.n_joint_rows, pen, grid.dt_s)
    tally.ledger = EnergyLedger(system, integ.carried, integ.carried_state, plastic)
    tally.ledger.record(states)
    wall0 = time.perf_counter()
    h_min = grid.dt_s / (1 << MAX_STEP_CUTS)
    tick, level, last_out = 0, 0, 0

    def fail(message: str, cause: Exception | None = None):
        """The run stops here: SimulationFailed with what it computed up to now."""
        bar.close()
        raise SimulationFailed(message, tally.result(rec, integ, wall0, message)) from cause

    while tick < n_ticks:
        to_out = out_ticks - tick % out_ticks
        if tally.calm == 0 and tally.n_steps:
            level = 0
        else:  # a degenerate deformed facet met looking ahead stops the run here (_or_fail)
            args = (system, states, level, tally.calm, k_max, dt)
            level = _or_fail(fail, tally, t0 + tick * dt, _choose_level, *args)
        span = 1 << level
        while span > to_out or tick + span > n_ticks and span > 1:
            span >>= 1
        h = span * dt
        t = t0 + tick * dt
        try:
            parts = _advance(integ, t, states, h, h_min, tally.cuts)
        except SolverError as exc:
            message = (
                f"at t = {t:.6g} s (step {tally.n_steps + 1}, h = {h:.3g} s, cut down "
                f"to {h_min:.3g} s): {exc}"
            )
            fail(message, exc)
        states = _or_fail(fail, tally, t + h, _accept, parts, states, tally, integ, on_step)
        stop = plastic.outside_stop() if plastic is not None else None
        if stop is not None:  # a reduced plastic body's zone left its region (plastic_outside)
            fail(f"at t = {t + h:.6g} s (step {tally.n_steps}): {stop}")
        if switches is not None:  # a moving region's window switch (integrate/moving_region.py)
            moved = switches.after_step(t + h, system, states, parts[-1][2])
            if switches.outside_stop() is not None:
                fail(f"at t = {t + h:.6g} s (step {tally.n_steps}): {switches.outside_stop()}")
            if moved is not None:
                system, states = moved
                integ = _rebound(system, integ, make_integrator(system, grid), rec, pen, tally)
        tick += span
        fine = fine_ticks is not None and level == 0 and tick % fine_ticks == 0
        if tick % out_ticks == 0 or tick >= n_ticks or fine:
            span_t = (tick - last_out) * dt
            last_out = tick
            rec.record(
                t0 + tick * dt, states, tally.impulse / span_t, tally.jimpulse / span_t,
                integ.carried, integ.carried_products,
            )  # fmt: skip
            try:
                _check_finite(rec.rows[-1], system, t0 + tick * dt)
            except SolverError as exc:
                rec.rows.pop()
                fail(str(exc), exc)
            tally.output()
            tally.ledger.record(states)
            bar.update(min(tick, n_ticks), tally.n_steps)
    bar.close()
    return tally.result(rec, integ, wall0)


def _rebound(system, old, integ, rec, pen, tally):
    """integ, the integrator made for ``system`` after a window switch, with the recorder,
    the penetration measure and the energy ledger pointed at the new system and integrator;
    the counts of the retired integrator ``old`` kept in the tally (the run's totals)."""
    tally.retired[0] += old.n_factorizations
    tally.retired[1] += old.n_nonrotating_steps
    rec.system = pen.system = tally.ledger.system = system
    tally.ledger.carried, tally.ledger.fresh = integ.carried, integ.carried_state
    return integ


def _or_fail(fail, tally, t_s: float, fn, *args):
    """fn(*args); a SolverError in it (a degenerate deformed facet met choosing the step level
    or measuring an accepted step) stops the run through ``fail`` at t_s [s] and the last
    accepted step, keeping what was computed, as a step that does not converge does."""
    try:
        return fn(*args)
    except SolverError as exc:
        fail(f"at t = {t_s:.6g} s (step {tally.n_steps}): {exc}", exc)


def _accept(parts, states, tally, integ, on_step):
    """The states after the accepted steps [(start, size, StepResult)] of one advance from
    ``states``, each added to the tally and its energy ledger and passed to on_step."""
    for t_s, h_s, res in parts:
        start, states = states, res.states
        tally.add(t_s, h_s, res)
        step = AcceptedStep(t_s, h_s, start, res, step_theta(integ, h_s))
        tally.ledger.add(step)
        if on_step is not None:
            on_step(step)
    return states


def _advance(
    integ: Integrator, t: float, states: list[BodyState], h: float, h_min: float, cuts: list
) -> list[tuple[float, float, StepResult]]:
    """Steps from t over h: [(start, size, StepResult)]. A step whose Newton iteration fails
    (it diverges, or has not reached the tolerance or the round-off floor in max_iter
    iterates) is taken as two halves instead, recursively down to h_min = dt_s /
    2^MAX_STEP_CUTS, as implicit codes cut their step; the next step is back at the grid's
    size; a failure at h_min raises SolverError. A step that stops on the round-off floor
    (below newton_iterate.ROUNDOFF_FLOOR, no longer decreasing) is accepted, and the run counts
    it in steps_on_roundoff_floor and warns: cutting it would cost up to 2^MAX_STEP_CUTS steps
    for a residual that is round-off. cuts = [number of steps cut, smallest step taken [s]],
    updated."""
    try:
        res = integ.step(t, states, h)
    except SolverError:
        if h * 0.5 < h_min * (1 - 1e-9):
            raise
    else:
        cuts[1] = min(cuts[1], h)
        return [(t, h, res)]
    cuts[0] += 1
    half = 0.5 * h
    first = _advance(integ, t, states, half, h_min, cuts)
    second = _advance(integ, t + half, first[-1][2].states, half, h_min, cuts)
    return first + second


def _add_row_impulses(acc: dict, crows, lam: np.ndarray, t: float) -> None:
    """Add the compressive normal impulses of the step's unilateral normal rows (keys
    (contact, slave node, master facet); not tangent or bond rows) to acc[key] = [impulse
    [N s], first time [s] it carried one]: where on the surfaces a run's contact was carried
    (the validity guard of reduced bases, runs/guard.py)."""
    w = crows.normal_weight
    for i in np.nonzero(lam > 0.0)[0]:
        key = crows.keys[i]
        if i < crows.n_eq or len(key) != 3:
            continue
        x = float(lam[i] * (1.0 if w is None else w[i]))
        entry = acc.get(key)
        if entry is None:
            acc[key] = [x, t]
        else:
            entry[0] += x


def _check_finite(row: dict, system, t: float) -> None:
    """SolverError naming the time and the first body whose recorded state is NaN/inf."""
    if np.isfinite(row["kin"] + row["strain"] + row["force"]) and np.isfinite(row["v"]).all():
        return
    bad = [
        body.name
        for body, q, v in zip(system.bodies, row["q"], row["v"])
        if not (np.isfinite(q).all() and np.isfinite(v).all())
    ]
    where = f"body {bad[0]!r}" if bad else "the contact force"
    raise SolverError(f"at t = {t:.6g} s: the solution became non-finite (NaN/inf) in {where}")


class _Penetrations:
    """The deepest penetration over a run, from the contact providers' surface measure
    (contact.penetration: both directions, every node of both surfaces) on the state after
    every step; measured = False when no provider measures (then the driver keeps the gaps
    of the candidate rows)."""

    def __init__(self, system: System):
        self.system = system
        self.measured = bool(system.contacts)
        self.depth, self.at = 0.0, None
        self.by_direction: dict[str, float] = {}  # "b1 nodes into b2" -> deepest [m]
        self.floors: dict[int, list[float]] = {}  # per provider, per direction: deepest so far

    def _measure(self, states, t, deep):
        bodies = self.system.bodies
        found = []
        for k, provider in enumerate(self.system.contacts):
            floors = None if deep else self.floors.get(k)
            pens = provider.penetration(bodies, states, deep=deep, floors=floors)
            if pens is None:
                self.measured = False
                return []
            seen = self.floors.get(k, [0.0] * len(pens))
            self.floors[k] = [max(f, p.depth_m) for f, p in zip(seen, pens)]
            for p in pens:
                key = f"{bodies[p.body].name} nodes into {bodies[p.against].name}"
                self.by_direction[key] = max(self.by_direction.get(key, 0.0), p.depth_m)
                if p.depth_m > self.depth:
                    self.depth = p.depth_m
                    self.at = {
                        "t_s": float(t),
                        "body": bodies[p.body].name,
                        "node": p.node,
                        "against": bodies[p.against].name,
                    }
                found.append(p)
        return found

    def start(self, states, t0: float, check: bool = True) -> None:
        """Measure the initial state; InputError when the bodies overlap (OVERLAP_TOL_M) and
        check is set."""
        if not self.measured:
            return
        bodies = self.system.bodies
        found = self._measure(states, t0, deep=True)
        if found:
            p = max(found, key=lambda p: p.depth_m)
            if check and p.depth_m > OVERLAP_TOL_M:
                a, b = bodies[p.body].name, bodies[p.against].name
                raise InputError(
                    f"bodies {a!r} and {b!r} overlap at t = {t0:g} s by {p.depth_m:.4g} m (node "
                    f"{p.node} of {a!r} inside the contact surface of {b!r}; tolerance "
                    f"{OVERLAP_TOL_M:g} m): place them apart or touching"
                )

    def after_step(self, states, t: float) -> None:
        if self.measured:
            self._measure(states, t, deep=False)


def _choose_level(system, states, level, calm, k_max, dt) -> int:
    """The step level k (step dt 2^k): one up after GROW_AFTER_STEPS steps without contact
    rows, then down to the largest k whose horizon of 4 steps of 2^k dt is predicted free of
    contact by every provider (min_gap_ahead > 0), so an approach comes down level by level and
    reaches the contact at dt."""
    if k_max == 0:
        return 0
    if not system.contacts:
        return k_max
    want = min(level + 1, k_max) if calm >= GROW_AFTER_STEPS else (level if calm else 0)
    while want > 0 and not _clear_ahead(system, states, 4 * (1 << want) * dt):
        want -= 1
    return want


def _clear_ahead(system, states, horizon: float) -> bool:
    return all(
        provider.min_gap_ahead(system.bodies, states, horizon) > 0.0 for provider in system.contacts
    )


def _track_intervals(intervals, in_contact, t0, t1):
    if in_contact:
        if intervals and abs(intervals[-1][1] - t0) < 1e-15 + 1e-9 * max(t0, 1e-12):
            intervals[-1][1] = t1
        else:
            intervals.append([t0, t1])
