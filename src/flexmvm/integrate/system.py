"""A multibody system: bodies, joints, contact providers, gravity, applied loads (flexmvm.loads)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from flexmvm.bodies.body import FlexibleBody
from flexmvm.constraints.contact import ContactProvider, ContactRows
from flexmvm.constraints.joints import Joint
from flexmvm.loads.point_force import PointForce

if TYPE_CHECKING:
    from flexmvm.integrate.plastic_bodies import PlasticPart

__all__ = ["ContactProvider", "ContactRows", "Load", "NodeLoad", "StoringLoad", "System"]


#: NodeLoad(body, node, force_n, t_start_s=0.0): a constant global force [N] on a node from
#: t_start_s on, the PointForce of loads.point_force that it became
NodeLoad = PointForce.on_node


class Load(Protocol):
    """What the step, the energy ledger and a run's report ask of every applied load
    (flexmvm.loads), each declared by every load (never probed for)."""

    name: str  # the key of its work ("": loads[k] <Kind>)

    @property
    def external(self) -> bool:
        """The force comes from outside the system: linear momentum is not conserved."""
        ...

    @property
    def state_independent(self) -> bool:
        """Fixed in space and independent of the state: the linear step of frames that do
        not rotate (integrate.moreau_jean.nonrotating) may take it."""
        ...

    @property
    def acted_on(self) -> frozenset[int]:
        """The bodies the load acts on, whatever its value (a run's momentum report groups
        the bodies that exchange momentum by them)."""
        ...

    def reset(self) -> None:
        """Forget what the load keeps between its evaluations (at the start of a run,
        loads.applied.start_run); nothing for a load that keeps nothing."""
        ...

    def forces(self, bodies, states, t: float) -> dict[int, np.ndarray]:
        """{body: generalized force (6 + nq,)} at states (with velocities) and time t [s]."""
        ...


@runtime_checkable
class StoringLoad(Load, Protocol):
    """A load that stores energy and dissipates some (a spring-damper: loads.spring,
    loads.revolute): its stored energy is set against its elastic work."""

    def energy(self, bodies, states) -> float:
        """The energy stored [J] at states."""
        ...

    def dissipation_rate(self, bodies, states) -> float:
        """The power its damper dissipates [W] at states (with velocities)."""
        ...


@dataclass(frozen=True)
class System:
    """What a run integrates: its bodies, joints (constraints.joints), contact providers,
    gravity [m/s^2], applied loads and plastic parts."""

    bodies: tuple[FlexibleBody, ...]
    joints: tuple[Joint, ...] = ()
    contacts: tuple[ContactProvider, ...] = ()
    gravity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    # applied loads (flexmvm.loads: forces, torques, springs), each with forces(bodies, states, t)
    loads: tuple[Load, ...] = ()
    # elastic-plastic full-FE bodies (integrate.plastic_bodies.PlasticPart); () : all elastic
    plastic: tuple[PlasticPart, ...] = ()
