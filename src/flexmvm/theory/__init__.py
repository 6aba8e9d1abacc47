"""Closed-form and semi-analytical references: 1D wave solutions of two colliding rods
(St Venant flat-end impact, wave + Hertz contact; wave.py), Hertz's impact scales (hertz.py),
a sphere striking a free Timoshenko beam through a Hertz spring (timoshenko.py,
beam_impact.py, sphere_beam.py), the onset of yield under a Hertz contact (hertz_yield.py) and
Thornton's restitution of an elastic-perfectly plastic sphere (thornton.py), and the
restitution from Jackson and Green's FE-fitted sphere-flat law (restitution_fits.py)."""

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
