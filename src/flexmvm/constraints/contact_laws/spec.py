"""What a contact law declares (ContactLawSpec). LawSpec is a frozen base with the common
answers (those of the velocity law), so a law's module states only where it differs."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

#: the scheme's theta: a number or a rule of the step size h (integrate.theta.ThetaRule)
Theta = float | Callable[[float], float] | None


@runtime_checkable
class ContactLawSpec(Protocol):
    """Everything the program asks of a contact law (contact.pairs, contact.pair_options,
    the scenario schema, integrate.moreau_jean.massless, the run's summary)."""

    # read-only properties, so that a frozen dataclass satisfies them
    @property
    def name(self) -> str: ...  # the scenario file's contact ``law``
    @property
    def bonded(self) -> bool: ...  # may constrain a bonded contact
    @property
    def needs_theta(self) -> bool: ...  # reads theta (pair_options checks it in [0.5, 1])
    @property
    def massless_nodes(self) -> bool: ...  # may carry massless (redistributed) contact nodes
    @property
    def conserves_energy(self) -> bool: ...  # adds no energy (contact_laws_add_no_energy)
    @property
    def holds_pairs(self) -> bool: ...  # closed pairs keep the geometry they closed with

    def row_window(self, h: float, gap_tol: float, speed: float) -> tuple[float, float]:
        """(hp, tol): a pair becomes a row when g + hp u_N- <= tol (contact.pair_rows)."""
        ...

    def lower(
        self, gaps: np.ndarray, u_n: np.ndarray, h: float, beta: float, theta: Theta
    ) -> np.ndarray:
        """Lower bounds (m,) of u_N+ [m/s] of normal rows with gaps g [m] and start normal
        velocities u_N- [m/s] over a step h [s]."""
        ...

    def options_problem(self, bonded: bool, theta: Theta) -> str | None:
        """What is wrong with a contact's options under this law (None: nothing)."""
        ...

    def scenario_problem(
        self, bonded: bool, penetration_recovery: float | None
    ) -> tuple[str, str] | None:
        """(message, key) of a scenario contact's keys this law refuses (None: none)."""
        ...


@dataclass(frozen=True)
class LawSpec:
    """The common answers: a law for any contact kind, without theta, with the penetration
    recovery beta, on nodes with mass; its rows the pairs predicted to close within h."""

    name: str
    bonded: bool = True
    needs_theta: bool = False
    massless_nodes: bool = False
    conserves_energy: bool = False
    holds_pairs: bool = False

    def row_window(self, h: float, gap_tol: float, speed: float) -> tuple[float, float]:
        """(h, gap_tol): the pairs predicted to close within the step, g + h u_N- <= gap_tol."""
        return h, gap_tol

    def lower(
        self, gaps: np.ndarray, u_n: np.ndarray, h: float, beta: float, theta: Theta
    ) -> np.ndarray:
        raise NotImplementedError(f"contact law {self.name!r} states no lower bound")

    def options_problem(self, bonded: bool, theta: Theta) -> str | None:
        """The scheme's theta in [0.5, 1] (a number or a rule) when the law reads it; not a
        bonded contact when the law is not for one."""
        if self.needs_theta and (
            theta is None or (not callable(theta) and not 0.5 <= theta <= 1.0)
        ):
            return f"the {self.name} law needs the scheme's theta in [0.5, 1], got {theta!r}"
        if bonded and not self.bonded:
            return f"the {self.name} law is not for bonded contact"
        return None

    def scenario_problem(
        self, bonded: bool, penetration_recovery: float | None
    ) -> tuple[str, str] | None:
        """A bonded contact under a law not for one."""
        if bonded and not self.bonded:
            return f'law = "{self.name}" is for frictionless contact, not bonded', "law"
        return None
