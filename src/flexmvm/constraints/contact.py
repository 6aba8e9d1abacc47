"""The interface between contact definitions (contact/) and the time step (integrate/): the
rows a contact contributes to a step and the methods the step calls. It sits below both, so
neither stage imports the other.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Protocol, runtime_checkable

import numpy as np

from flexmvm.constraints.contact_laws import ContactLaw
from flexmvm.constraints.rows import Rows

__all__ = ["ContactKind", "ContactLaw", "ContactProvider", "ContactRows", "FrictionRows"]


class ContactKind(StrEnum):
    """What a contact constrains (values: the scenario file's ``kind``)."""

    FRICTIONLESS = "frictionless"  # normal gap >= 0 (default)
    BONDED = "bonded"  # seed eq. (7): all three relative components once closed


@dataclass(frozen=True)
class FrictionRows:
    """The friction cones of a set of contact rows: contact i has its normal row normal[i],
    its two tangent rows tangent[i] (indices into the contact rows), friction coefficient
    mu[i] > 0 and the global unit tangents directions[i] (2, 3) of those rows."""

    normal: np.ndarray  # (k,) int
    tangent: np.ndarray  # (k, 2) int
    mu: np.ndarray  # (k,)
    directions: np.ndarray  # (k, 2, 3)

    def shifted(self, offset: int) -> FrictionRows:
        return FrictionRows(self.normal + offset, self.tangent + offset, self.mu, self.directions)


@dataclass
class ContactRows:
    """Unilateral rows from contacts at the start of a step: Phi_c v+ >= lower.

    keys identify the pairs (for reporting and for caching W^-1 Phi^T); gaps are the current
    normal gaps [m]; eq_rows (leading rows) are equalities Phi v+ = lower (bonded contact).
    """

    rows: Rows
    lower: np.ndarray
    keys: list
    gaps: np.ndarray
    n_eq: int = 0
    normal_weight: np.ndarray | None = None  # (m,): row impulse -> compressive normal impulse
    friction: FrictionRows | None = None  # None: no friction cone (the exact LCP path)
    # (sticking, sliding) cones at the last solution of the step (set by
    # integrate.moreau_jean.coulomb)
    stick_slip: tuple[int, int] = (0, 0)

    @classmethod
    def empty(cls) -> ContactRows:
        return cls(Rows.empty(), np.zeros(0), [], np.zeros(0), 0)

    def normal_impulse(self, lam: np.ndarray) -> float:
        """Total compressive normal impulse [N s] of the row impulses lam."""
        if lam.size == 0:
            return 0.0
        w = self.normal_weight
        return float(lam[self.n_eq :].sum() if w is None else w @ lam)

    def tangential_impulse(self, lam: np.ndarray) -> np.ndarray:
        """Resultant tangential (friction) impulse (3,) [N s] of the row impulses lam: the sum
        over the friction cones of l_T1 t1 + l_T2 t2 (global)."""
        fr = self.friction
        if fr is None or lam.size == 0:
            return np.zeros(3)
        return np.einsum("ik,ikj->j", lam[fr.tangent], fr.directions)


@runtime_checkable
class ContactProvider(Protocol):
    """Every attribute and method the time step, the time loop and a run's report ask of a
    contact definition."""

    name: str  # the contact's name (the first item of its rows' keys, the outputs' key)
    mu: float  # Coulomb friction coefficient of the contact (0: frictionless)
    law: ContactLaw  # the normal rows' law (its spec: law.spec, constraints/contact_laws/)
    slave: int  # the body of the slave nodes (index in System.bodies)
    master: int  # the body of the master facets
    search_radius: float  # [m] the reach within which a pair is a candidate row

    def candidate_rows(self, bodies, states, h: float) -> ContactRows:
        """Rows of the pairs that may close within the coming step of size h [s]."""
        ...

    def after_step(self, crows: ContactRows, impulses: np.ndarray, h: float) -> None:
        """The step with rows crows was accepted with these row impulses [N s]."""
        ...

    def min_gap_ahead(self, bodies, states, horizon_s: float) -> float:
        """Smallest predicted gap [m] within horizon_s at current velocities (step policy)."""
        ...

    def rebind(self, index: int, body) -> None:
        """Body ``index``'s basis changed (a moving region's window switch): the contact's
        rows of its nodes gathered again from ``body``."""
        ...

    def penetration(self, bodies, states, deep: bool = False, floors=None):
        """Deepest penetration per measured direction (contact.penetration.Penetration list) at
        `states`; None when the provider does not measure it (the driver then falls back on
        the gaps of its candidate rows). deep: the start-of-run check (larger reach); floors:
        per direction, only deeper penetrations are sought (shallower ones read 0)."""
        ...
