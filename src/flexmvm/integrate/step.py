"""The contract between the time loop (driver.py) and an integrator: what a step gives
(StepResult) and what the driver asks of the integrator that takes it (Integrator). The
Moreau-Jean scheme (moreau_jean.py) is the one integrator of the package; another one is
passed to driver.simulate as a factory (driver.IntegratorFactory)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

from flexmvm.constraints.contact import ContactRows
from flexmvm.integrate.state import BodyState

if TYPE_CHECKING:
    from flexmvm.integrate.carried import CarriedState
    from flexmvm.integrate.plastic_bodies import PlasticBodies
    from flexmvm.integrate.theta import ThetaRule


@dataclass
class StepResult:
    """One step's outcome: the end states, the constraint impulses [N s] of its joint and
    contact rows (the rows themselves in ``contact``) and its iteration report."""

    states: list[BodyState]
    joint_impulses: np.ndarray
    contact: ContactRows
    contact_impulses: np.ndarray
    iterations: int
    joint_drift: float = 0.0  # max |phi| of the joints at the end of the step [m or -]
    converged: bool = True  # False: stopped on the round-off floor above rtol
    residual: float = 0.0  # largest momentum residual at exit, relative to the body's scale
    translation_residual: np.ndarray | None = None  # (3,) sum over bodies of the exit
    # residual's translational rows as the solves left them, before their balance [N s]
    # (3,) the linear momentum the balance of the translational rows added to the step's
    # solution [N s] (integrate.momentum_balance): zero when not taken
    momentum_shift: np.ndarray | None = None
    lcp_residual: float = 0.0  # largest complementarity residual of the step's LCP solves
    # work [J] of the plastic bodies' force correction psi^T c(q_m) . dq (plastic_bodies)
    plastic_work: float = 0.0


class Integrator(Protocol):
    """What driver.simulate asks of an integrator: ``step`` from t over h (raising
    flexmvm.errors.SolverError when it fails: the driver then cuts the step), its order of
    accuracy for smooth motion, the number of joint rows, and counters for the run's report.
    ``carried(b, state)`` and ``carried_products(b, state)`` give (L(q), L(q_dot)) and
    (k_hat q, M_qq q_dot) of body b at a state, for the energies of an output. The driver
    and the energy ledger read the attributes below, each declared here (None where the
    integrator has none), never probed for."""

    order: int
    n_joint_rows: int
    n_nonrotating_steps: int
    # theta of each step size (the ledger's numerical dissipation); None: taken as 1/2
    theta_rule: ThetaRule | None
    # the elastic-plastic bodies' history (plastic_bodies); None or empty (false): none
    plastic: PlasticBodies | None
    # k_hat q and M_qq q_dot carried with the states it produced (carried.py); None: the
    # ledger computes its products afresh
    carried_state: CarriedState | None

    def step(self, t: float, states: list[BodyState], h: float) -> StepResult: ...

    @property
    def n_factorizations(self) -> int: ...

    def carried(self, b: int, st: BodyState) -> tuple[np.ndarray, np.ndarray]: ...

    def carried_products(self, b: int, st: BodyState) -> tuple[np.ndarray, np.ndarray]: ...
