"""A multibody system: bodies, joints, contact providers, gravity."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from flexmvm.bodies.body import FlexibleBody
from flexmvm.constraints.contact import ContactProvider, ContactRows

__all__ = ["ContactProvider", "ContactRows", "NodeLoad", "System"]


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
