"""A multibody system: bodies, joints, contact providers, gravity."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from flexmvm.bodies.body import FlexibleBody
from flexmvm.constraints.rows import Rows


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

    @classmethod
    def empty(cls) -> ContactRows:
        return cls(Rows.empty(), np.zeros(0), [], np.zeros(0), 0)

    def normal_impulse(self, lam: np.ndarray) -> float:
        """Total compressive normal impulse [N s] of the row impulses lam."""
        if lam.size == 0:
            return 0.0
        w = self.normal_weight
        return float(lam[self.n_eq:].sum() if w is None else w @ lam)


class ContactProvider:
    """Interface of a contact definition used by the integrator."""

    def candidate_rows(self, bodies, states, h: float) -> ContactRows:
        raise NotImplementedError

    def min_gap_ahead(self, bodies, states, horizon_s: float) -> float:
        """Smallest predicted gap [m] within horizon_s at current velocities (step policy)."""
        raise NotImplementedError

    def penetration(self, bodies, states, deep: bool = False, floors=None):
        """Deepest penetration per measured direction (contact.penetration.Penetration list) at
        `states`; None when the provider does not measure it (the driver then falls back on
        the gaps of its candidate rows). deep: the start-of-run check (larger reach); floors:
        per direction, only deeper penetrations are sought (shallower ones read 0)."""


@dataclass(frozen=True)
class NodeLoad:
    """A constant global force [N] on node `node` of body `body`, applied from t_start_s on."""

    body: int
    node: int
    force_n: tuple[float, float, float]
    t_start_s: float = 0.0


@dataclass(frozen=True)
class System:
    bodies: tuple[FlexibleBody, ...]
    joints: tuple = ()
    contacts: tuple = ()
    gravity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    loads: tuple[NodeLoad, ...] = ()
