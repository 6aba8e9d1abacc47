"""Which outputs of a run its field files hold (results.h5's /bodies and the ParaView series).

Histories (contact force, probes, energies, frames) are written at every output; the fields
(nodal displacements, velocities, stresses: q and q_dot of every body) only at some. A run
given a field output rate (TimeGrid.field_output_dt_s, the scenario's ``[time]
field_output_dt_s``) kept q only there, and those are written. A run that kept q at every
output gets DEFAULT_FIELD_FRAMES of them (default_field_rows): half spread evenly over the
window, the rest over the outputs inside its contact intervals, so that an impact a tenth of
the window long is still animated frame by frame.
"""

from __future__ import annotations

import math

import numpy as np

from flexmvm.errors import InputError
from flexmvm.integrate.run_result import RunResult

__all__ = ["DEFAULT_FIELD_FRAMES", "default_field_rows", "field_selection"]

#: About this many field frames by default (a run that kept q at every output).
DEFAULT_FIELD_FRAMES = 32


def _strided(rows: np.ndarray, frames: int) -> np.ndarray:
    """Every k-th of rows (k the smallest stride giving at most `frames`), and the last."""
    if len(rows) == 0:
        return rows
    k = max(1, math.ceil(len(rows) / max(frames, 1)))
    return np.union1d(rows[::k], rows[-1:])


def default_field_rows(t, contact_intervals=(), frames: int = DEFAULT_FIELD_FRAMES) -> np.ndarray:
    """Rows of t (sorted) to write fields at: all if there are at most `frames`; else every
    k-th output, k giving frames/2 over the whole window, and the outputs inside the contact
    intervals [(start, end)] [s] at the stride that spends the rest of the `frames` there
    (an impact a tenth of the window long gets half the frames); the first and last output
    always. About `frames` rows (at most frames + 2)."""
    t = np.asarray(t, dtype=float)
    n = len(t)
    if n <= frames:
        return np.arange(n)
    inside = np.zeros(n, dtype=bool)
    for start, end in np.asarray(contact_intervals, dtype=float).reshape(-1, 2):
        inside |= (t >= start) & (t <= end)
    coarse = _strided(np.arange(n), frames // 2 if inside.any() else frames)
    outside = coarse[~inside[coarse]]
    return np.union1d(outside, _strided(np.flatnonzero(inside), frames - len(outside)))


def field_selection(run: RunResult, every: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(rows of run.t, rows of run.q) of the fields to write: every `every`-th field row the
    run kept (every=None: all the rows a field output rate kept, or default_field_rows of a
    run that kept every output). InputError if run.q does not hold one row per field row."""
    kept = run.field_rows
    if len(kept) and (kept[0] < 0 or kept[-1] >= len(run.t) or np.any(np.diff(kept) <= 0)):
        raise InputError(
            f"RunResult.field_index: expected increasing rows of t (0...{len(run.t) - 1})"
        )
    if len(run.q) != len(run.body_names) or any(len(q) != len(kept) for q in run.q):
        raise InputError(
            f"RunResult.q: expected one ({len(kept)}, nq) array per body (the field rows)"
        )
    if every is not None:
        pos = np.arange(0, len(kept), every)
    elif run.field_index is not None:
        pos = np.arange(len(kept))
    else:
        pos = default_field_rows(run.t, run.contact_intervals)
    return kept[pos], pos
