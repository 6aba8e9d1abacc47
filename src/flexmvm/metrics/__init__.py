"""Comparison of histories: NCC (seed section 3.1) with peak, impulse and duration errors."""

from flexmvm.metrics.ncc import (
    Comparison,
    Target,
    compare_force,
    contact_intervals,
    contact_window,
    impulse,
    ncc,
    peak,
    pearson,
)

__all__ = [
    "Comparison",
    "Target",
    "compare_force",
    "contact_intervals",
    "contact_window",
    "impulse",
    "ncc",
    "peak",
    "pearson",
]
