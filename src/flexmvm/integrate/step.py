"""The contract between the time loop (driver.py) and an integrator: what a step gives
(StepResult), what the driver and the energy ledger ask of the integrator that takes it
(Integrator) and of the products it may carry with its states (CarriedStates). The Moreau-Jean
scheme (integrate/moreau_jean/) is the one integrator of the package; another one is passed to
driver.simulate as a factory (driver.IntegratorFactory). Nothing here imports the scheme."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

from flexmvm.constraints.contact import ContactRows
from flexmvm.integrate.state import BodyState

if TYPE_CHECKING:
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
    # solution [N s] (integrate.moreau_jean.momentum_balance): zero when not taken
    momentum_shift: np.ndarray | None = None
    lcp_residual: float = 0.0  # largest complementarity residual of the step's LCP solves
    # work [J] of the plastic bodies' force correction psi^T c(q_m) . dq (plastic_bodies)
    plastic_work: float = 0.0


class CarriedProducts(Protocol):
    """L(q) (bodies.body.carried_contractions: (3, 3, nq), or (3, n) for full FE), k_hat q and
    M_qq q_dot of one body at the state they were made for (the scheme's
    carried.CarriedContractions)."""

    @property
    def Lq(self) -> np.ndarray: ...

    @property
    def Kq(self) -> np.ndarray: ...

    @property
    def Mqd(self) -> np.ndarray: ...


class CarriedStates(Protocol):
    """What the energy ledger asks of the products an integrator carries with its states:
    ``of_state(b, state)`` gives body b's CarriedProducts if they were made for exactly that
    state (its q and v arrays), else None (the ledger then computes them)."""

    def of_state(self, b: int, st: BodyState) -> CarriedProducts | None: ...


class Integrator(Protocol):
    """What driver.simulate asks of an integrator: ``step`` from t over h (raising
    flexmvm.errors.SolverError when it fails: the driver then cuts the step), its order of
    accuracy for smooth motion, the number of joint rows, and counters for the run's report.
    ``carried(b, state)`` and ``carried_products(b, state)`` give (L(q), L(q_dot)) and
    (k_hat q, M_qq q_dot) of body b at a state, for the energies of an output. The driver
    and the energy ledger read the attributes below, each declared here (None where the
    integrator has none), never probed for."""

    @property
    def order(self) -> int: ...

    @property
    def n_joint_rows(self) -> int: ...

    @property
    def n_nonrotating_steps(self) -> int: ...

    @property
    def theta_rule(self) -> ThetaRule | None:
        """theta of each step size (the ledger's numerical dissipation); None: taken as 1/2."""
        ...

    @property
    def plastic(self) -> PlasticBodies | None:
        """The elastic-plastic bodies' history (plastic_bodies); None or empty (false): none."""
        ...

    @property
    def carried_state(self) -> CarriedStates | None:
        """k_hat q and M_qq q_dot carried with the states it produced; None: the ledger
        computes its products afresh."""
        ...

    def step(self, t: float, states: list[BodyState], h: float) -> StepResult: ...

    @property
    def n_factorizations(self) -> int: ...

    def carried(self, b: int, st: BodyState) -> tuple[np.ndarray, np.ndarray]: ...

    def carried_products(self, b: int, st: BodyState) -> tuple[np.ndarray, np.ndarray]: ...
