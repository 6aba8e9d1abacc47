"""Applied loads: point forces and body torques (point_force), point-to-point spring-dampers
(spring), rotational spring-dampers and motor torques on revolute joints (revolute), their
time histories (history) and their sum at the step's midpoint (applied)."""

from flexmvm.loads.history import TimeHistory
from flexmvm.loads.point_force import BodyTorque, PointForce
from flexmvm.loads.revolute import MotorTorque, RevoluteAxis, RotationalSpring
from flexmvm.loads.spring import PointSpring

__all__ = [
    "BodyTorque",
    "MotorTorque",
    "PointForce",
    "PointSpring",
    "RevoluteAxis",
    "RotationalSpring",
    "TimeHistory",
]
