"""A multibody system: bodies, joints, contact providers, gravity, applied loads (flexmvm.loads)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from flexmvm.bodies.body import FlexibleBody
from flexmvm.constraints.contact import ContactProvider, ContactRows
from flexmvm.loads.point_force import PointForce

__all__ = ["ContactProvider", "ContactRows", "NodeLoad", "System"]


#: NodeLoad(body, node, force_n, t_start_s=0.0): a constant global force [N] on a node from
#: t_start_s on, the PointForce of loads.point_force that it became
NodeLoad = PointForce.on_node


@dataclass(frozen=True)
class System:
    bodies: tuple[FlexibleBody, ...]
    joints: tuple = ()
    contacts: tuple = ()
    gravity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    # applied loads (flexmvm.loads: forces, torques, springs), each with forces(bodies, states, t)
    loads: tuple = ()
    # elastic-plastic full-FE bodies (integrate.plastic_bodies.PlasticPart); () : all elastic
    plastic: tuple = ()
