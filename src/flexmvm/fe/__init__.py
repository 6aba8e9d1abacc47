"""Finite-element stage: sparse mass and stiffness (assembly) and eigenmodes (modes)."""

from flexmvm.fe.assembly import FEModel, assemble
from flexmvm.fe.modes import constrained_modes, free_modes, shift_invert_modes

__all__ = ["FEModel", "assemble", "constrained_modes", "free_modes", "shift_invert_modes"]
