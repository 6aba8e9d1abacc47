"""Finite-element stage: sparse mass and stiffness (assembly), eigenmodes (modes) and the
sparse direct solvers they and the later stages factor with (solvers)."""

from flexmvm.fe.assembly import FEModel, assemble
from flexmvm.fe.modes import constrained_modes, free_modes, shift_invert_modes

__all__ = ["FEModel", "assemble", "constrained_modes", "free_modes", "shift_invert_modes"]
