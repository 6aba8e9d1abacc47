"""Run a scenario: build, simulate, summarise. No file I/O here (see results.output)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexmvm.assembly.build import BuiltScenario, build_scenario
from flexmvm.assembly.build_cache import SetupCache
from flexmvm.errors import SimulationFailed
from flexmvm.integrate.driver import simulate
from flexmvm.integrate.run_result import ProbeHistory, RunResult, StepHistory
from flexmvm.reduction.truncation import truncation_report, truncation_warnings
from flexmvm.runs.blowup import blowup_failure
from flexmvm.runs.energy_report import momentum_report, report_entries
from flexmvm.runs.guard import contact_guard, energy_gain_warning, guard_warnings
from flexmvm.runs.plastic_summary import plastic_guard_warnings, plastic_summary
from flexmvm.runs.showcases import pendulum
from flexmvm.scenarios.load import load_scenario
from flexmvm.scenarios.schema import Scenario


@dataclass
class ScenarioRun:
    """A finished run of a scenario: what was built (``built``: system, bodies' info), the
    histories (``result``: a RunResult) and the numbers every run reports (``summary``)."""

    label: str
    built: BuiltScenario
    result: RunResult
    summary: dict

    @property
    def t(self) -> np.ndarray:
        """Output times [s]."""
        return self.result.t

    @property
    def contact_force(self) -> np.ndarray:
        """Normal contact force at the output times [N] (impulse over the output interval)."""
        return self.result.contact_force

    @property
    def steps(self) -> StepHistory | None:
        """Every step's end time, size and normal contact impulse."""
        return self.result.steps

    def probe(self, name: str) -> ProbeHistory:
        """Position and velocity history of probe ``name``."""
        return self.result.probe(name)

    def elastic(self, body: str) -> tuple[np.ndarray, np.ndarray]:
        """(q, q_dot) of body ``body`` at the output times."""
        return self.result.elastic(body)

    def curves(self, axis: int = 0) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        """(t, contact force, {probe: velocity component ``axis``})."""
        return self.result.curves(axis)

    def dof(self, body: str) -> int:
        """Generalized coordinates of body ``body``: 6 frame + elastic."""
        return int(self.summary["dof"][body])


# summary.json's words on its two momentum errors (free systems; None otherwise)
MOMENTUM_ERROR_NOTE = (
    "momentum_rel_error: max over the outputs of |p(t) - p(0)| / |p(0)| of the run as "
    "returned, whose steps' translational rows are balanced after convergence (a shift of "
    "each frame velocity, integrate.moreau_jean.momentum_balance.balance_translation): round-off by "
    "construction, not evidence of convergence. momentum_rel_error_converged: the same of "
    "the momentum the steps converged to, before that shift (p(t) minus the shifts so far): "
    "what the Newton tolerance left, it grows when the tolerance is loosened. "
    "momentum_residual_rel: the steps' translational residuals summed, before that shift."
)


class ReducedBasisWarning(UserWarning):
    """Contact fell on surface nodes a reduced basis holds stiff (runs/guard.py)."""


class EnergyGainWarning(UserWarning):
    """The total energy of a run rose beyond the work of its loads and drives (energy_gain_warning)."""


def run_scenario(
    sc,
    label: str = "run",
    progress: bool = False,
    warn: bool = True,
    setup: SetupCache | None = None,
) -> ScenarioRun:
    """Build (through ``setup``, default: the process-wide setup cache) and simulate scenario
    sc; returns the run with its summary. warn: issue a ReducedBasisWarning when the validity
    guard fires (summary reduced_contact_guard).

    Raises SimulationFailed when the run stops before its end time (a step that did not
    converge at the smallest step), or when it blew up (runs.blowup: a contact gone
    through a surface, energy put in): its ``partial`` is the ScenarioRun up to the failure,
    whose summary has ``status = "failed"`` and the reason in ``failure``."""
    built = build_scenario(sc, setup)
    try:
        res = simulate(
            built.system,
            built.states,
            built.grid,
            built.probes,
            progress=progress,
            switches=built.switches,  # a moving region (assembly/moving_region.py)
        )
    except SimulationFailed as exc:
        if not isinstance(exc.partial, RunResult):
            raise
        exc.partial.scenario = sc.model_dump(mode="json")
        partial = ScenarioRun(label, built, exc.partial, summarize(exc.partial, built))
        raise SimulationFailed(str(exc), partial) from exc
    res.scenario = sc.model_dump(mode="json")  # what results.h5 keeps (results.read)
    summary = summarize(res, built)
    blown = blowup_failure(summary, built)  # a run that blew up fails (runs.blowup)
    if blown is not None:
        failed = {**summary, "status": "failed", "failure": blown}
        raise SimulationFailed(blown, ScenarioRun(label, built, res, failed))
    if warn:
        for line in guard_warnings(summary["reduced_contact_guard"]):
            warnings.warn(line, ReducedBasisWarning, stacklevel=2)
        for line in plastic_guard_warnings(summary):  # a reduced plastic body's zone
            warnings.warn(line, ReducedBasisWarning, stacklevel=2)
        for line in truncation_warnings(summary.get("modal_truncation_guard") or {}):
            warnings.warn(line, ReducedBasisWarning, stacklevel=2)
        gain = energy_gain_warning(summary)
        if gain is not None:
            warnings.warn(gain, EnergyGainWarning, stacklevel=2)
    return ScenarioRun(label, built, res, summary)


def run(
    scenario: Scenario | str | Path,
    *,
    t_end_s: float | None = None,
    dt_s: float | None = None,
    progress: bool = False,
    label: str = "run",
) -> ScenarioRun:
    """Simulate ``scenario`` (a Scenario, or the path of a scenario file), optionally over
    another end time or contact step [s]; nothing is written. The run's result has the
    histories by name (``probe``, ``elastic``, ``curves``), its ``summary`` the numbers the
    command line writes to summary.json."""
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    if t_end_s is not None or dt_s is not None:
        sc = sc.with_time(t_end_s=t_end_s, dt_s=dt_s)
    return run_scenario(sc, label=label, progress=progress)


def _energy_change(E: np.ndarray) -> tuple[float | None, float | None]:
    """(E(t_end) - E(0)) / E(0) and the largest |E(t) - E(0)| / |E(0)| (None at E(0) = 0)."""
    if E[0] == 0:
        return None, None
    return float((E[-1] - E[0]) / E[0]), float(np.abs(E - E[0]).max() / abs(E[0]))


def summarize(res: RunResult, built: BuiltScenario) -> dict:
    """Numbers every run reports (units in the keys)."""
    p0 = res.momentum[0]
    why_not, subsystems = momentum_report(res, built)
    free = why_not is None
    scale = max(float(np.linalg.norm(p0)), 1e-300)
    mom_err = float(np.abs(res.momentum - p0).max() / scale) if free else None
    mom_err_converged = None
    if free and res.momentum_shift is not None and len(res.momentum_shift) == len(res.momentum):
        mom_err_converged = float(np.abs(res.momentum - res.momentum_shift - p0).max() / scale)
    E = res.total_energy
    counts = res.steps.size_counts() if res.steps is not None else {}  # steps per size [s]
    e_err, e_err_max = _energy_change(E)
    f = res.contact_force
    f_max, f_min = (float(f.max()), float(f.min())) if f.size else (0.0, 0.0)
    gain = energy_gain(res)
    return {
        # "completed", or "failed" with the reason: the histories then end at the failure
        "status": "completed" if res.failure is None else "failed",
        **({"failure": res.failure} if res.failure is not None else {}),
        "t_end_reached_s": float(res.t[-1]),
        "max_contact_force_interval_mean_N": f_max,  # an output interval's impulse / length
        "min_contact_force_interval_mean_N": f_min,
        "contact_intervals_s": [[float(a), float(b)] for a, b in res.contact_intervals],
        "dof": {i.name: int(i.dof) for i in built.info},
        "model": {i.name: i.model.value for i in built.info},
        "retained_nodes": {i.name: int(i.n_retained_nodes) for i in built.info},
        "modes": {i.name: int(i.n_modes) for i in built.info},
        "wall_time_s": float(res.wall_time_s),
        "n_steps": int(res.n_steps),
        # steps per step size {"<h [s]>": count} and the smallest / largest step taken
        "step_size_counts": {f"{h:.6g}": int(n) for h, n in counts.items()},
        "dt_min_taken_s": float(min(counts)) if counts else None,
        "dt_max_taken_s": float(max(counts)) if counts else None,
        "n_factorizations": int(res.n_factorizations),
        "momentum_rel_error": mom_err,
        "momentum_rel_error_converged": mom_err_converged,
        "momentum_error_note": MOMENTUM_ERROR_NOTE,
        **report_entries(res, built, why_not, subsystems),  # runs.energy_report
        "energy_rel_change": e_err,
        "energy_rel_change_max": e_err_max,
        # the largest rise of the total energy over its start beyond the inputs' work [-] (energy_gain)
        "energy_gain_rel_max": gain,
        # every contact on a law whose step adds no energy (the position law), not that the
        # scheme keeps it: theta > 1/2 damps (numerical_dissipation_J); before issue 51
        # "energy_conserving_scheme" (results.summary_keys reads old runs)
        "contact_laws_add_no_energy": bool(
            built.system.contacts
            and all(c.law.spec.conserves_energy for c in built.system.contacts)
        ),
        **numerical_dissipation(res, built),
        "max_penetration_m": float(res.max_penetration_m),
        "max_penetration_at": res.max_penetration_at,
        "max_penetration_by_direction_m": dict(res.max_penetration_by_direction_m),
        "max_joint_drift": float(res.max_joint_drift),
        # per driven joint (by name) its largest drive torque in magnitude [N m]
        "drive_torque_max_abs_Nm": {k: float(np.abs(v).max()) for k, v in res.drive_torque.items()},
        # steps accepted on the Newton iteration's round-off floor above rtol, at the
        # smallest step (integrate.driver: such a step is first cut in halves)
        "steps_on_roundoff_floor": int(res.steps_on_roundoff_floor),
        # steps retried as two halves (dt_min_taken_s: the smallest step taken)
        "step_cuts": int(res.step_cuts),
        "newton_residual_max": float(res.newton_residual_max),
        "lcp_residual_max": float(res.lcp_residual_max),
        # the momentum the solves left unbalanced (their translational residuals summed,
        # before the balance), relative to the initial momentum (free systems)
        "momentum_residual_rel": (
            float(np.linalg.norm(res.momentum_residual) / scale) if free else None
        ),
        # per guarded (MVM or interface) body: the share of its contact impulse carried on
        # surface nodes its basis holds stiff, when it first happened, a model covering them
        "reduced_contact_guard": contact_guard(res, built),
        # per Craig-Bampton body: the time of the inertia its cut modes miss, against contact's
        "modal_truncation_guard": truncation_report(built, res.steps),
        **_friction_summary(res),
        # plastic bodies: peak alpha, plastic work, permanent indentation (plastic_summary)
        **plastic_summary(res, built),
        # strings, gravity and a contact: the pendulum release's own measures
        **({"pendulum": pendulum.event_summary(built, res)} if pendulum.is_pendulum(built) else {}),
    }


def numerical_dissipation(res: RunResult, built: BuiltScenario) -> dict:
    """summary.json's cost of the scheme's damping: the energy the Moreau-Jean step at
    theta > 1/2 took [J] (the energy ledger's sum of (theta - 1/2)(dv^T M dv + dq^T k_hat dq),
    integrate.energy_ledger), its share of the initial energy [-] (None when that is 0), and
    the damping time in use [s] (hf_damping_time_s, "auto" resolved; None: a fixed theta)."""
    led = res.energy_ledger
    dissipated = float(led.numerical[-1]) if led is not None and len(led.numerical) else None
    e0 = abs(float(res.total_energy[0])) if len(res.total_energy) else 0.0
    return {
        "numerical_dissipation_J": dissipated,
        "numerical_dissipation_share": (
            dissipated / e0 if dissipated is not None and e0 > 0.0 else None
        ),
        "hf_damping_time_s": built.grid.hf_damping_time_s,
    }


#: A run whose scheme took more than this share of its initial energy is told so with its line
#: (numerical_dissipation_line): hf_damping_time_s = 12.5e-6 took 10 % of a plate impact's
#: (issue 51); "auto" keeps the contact's resolved motion to 1e-3 (integrate.theta)
DAMPING_SHARE_WARN = 0.01


def numerical_dissipation_line(summary: dict) -> str | None:
    """The line a run with numerical damping ends with: the energy the scheme took, in J and as
    a share of the initial energy, and the damping time (None: no damping, theta = 1/2);
    above DAMPING_SHARE_WARN it says that the scheme, not the physics, took it."""
    taken = summary.get("numerical_dissipation_J")
    if not taken:
        return None
    share = summary.get("numerical_dissipation_share")
    tau = summary.get("hf_damping_time_s")
    line = f"numerical damping (theta > 1/2) took {taken:.4g} J"
    if share is not None:
        line += f", {100 * share:.3g} % of the initial energy"
    if tau is not None:
        line += f" (hf_damping_time_s = {tau:.4g} s)"
    if share is not None and share > DAMPING_SHARE_WARN:
        line += (
            f"; more than {DAMPING_SHARE_WARN:.0%}: the scheme, not the physics, took it; "
            'try time.hf_damping_time_s = "auto" (docs/scenario_format.md)'
        )
    return line


def _friction_summary(res) -> dict:
    """Friction entries of the summary (none for a run without friction): the largest
    per-step friction force, the resultant tangential impulse and its ratio to the total
    normal impulse, the most cones sticking / sliding in a step."""
    fr = res.friction
    if fr is None:
        return {}
    normal = float(res.steps.contact_impulse_Ns.sum()) if res.steps is not None else 0.0
    tangential = float(np.linalg.norm(fr.impulse_ns))
    return {
        "max_friction_force_N": fr.force_max_n,
        "friction_impulse_Ns": tangential,
        "normal_impulse_Ns": normal,
        "friction_to_normal_impulse": tangential / normal if normal > 0 else None,
        "max_sticking_contacts": fr.max_sticking,
        "max_sliding_contacts": fr.max_sliding,
    }


def energy_gain(res: RunResult) -> float | None:
    """The largest rise of the total energy above its start that no input accounts for [-]:
    E(t) - E(0) less the work of the applied loads, the joints (drives, prescribed motions)
    and a spinning body's stiffening (integrate.energy_ledger), relative to E(0) or, for a run
    that starts at rest, to the largest input work; None when both are zero. Contact and the
    scheme may only take energy (runs.guard.ENERGY_GAIN_WARN)."""
    E = res.total_energy
    led = res.energy_ledger
    inputs = np.zeros_like(E)
    if led is not None:
        inputs[: len(led.contact)] = led.inputs()
    ref = abs(float(E[0])) or float(np.abs(inputs).max())
    if ref == 0.0:
        return None
    return float(max(0.0, (E - E[0] - inputs).max()) / ref)
