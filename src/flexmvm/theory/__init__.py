"""Closed-form and semi-analytical references: 1D wave solutions of two colliding rods
(St Venant flat-end impact, wave + Hertz contact)."""

from flexmvm.theory.wave import (
    ContactLaw,
    Rod1D,
    WaveParams,
    WaveSolution,
    hertz_stiffness,
    st_venant_force,
    two_rod_impact,
)

__all__ = [
    "ContactLaw",
    "Rod1D",
    "WaveParams",
    "WaveSolution",
    "hertz_stiffness",
    "st_venant_force",
    "two_rod_impact",
]
