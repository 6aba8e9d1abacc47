"""The mode count of an estimated region model (studies.region_estimate's step 6), from a criterion
rather than a fixed number: the body's elastic free-free modes below f_max = k / T_c, T_c the
expected contact duration and k = BANDWIDTH (the rule of `flexmvm select`'s a-priori
estimate, studies/estimate.py: a pulse of duration T_c has its energy below ~3 / T_c).

Measured on a clamped 100 x 100 x 4 mm aluminium plate struck by a rigid ball (T_c 46 us:
f_max 65 kHz, 96 modes by this rule; docs/notes/2026-11-29-region-estimates.md): the former
fixed 30 modes left the peak force 7.8 % high, 60 modes -0.07 %. The free-free spectrum of a
supported body has more modes below a frequency than its fixed-interface spectrum (free
edges), so the count is on the safe side; a body whose modes are not counted within
MAX_MODES takes MAX_MODES (said by ``capped``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["BANDWIDTH", "MAX_MODES", "ModeCount", "estimated_modes", "mode_count"]

#: f_max = BANDWIDTH / T_c (module doc).
BANDWIDTH = 3.0
#: The largest mode count the rule returns (and eigen-solves for).
MAX_MODES = 400
#: The first eigen solve's size (then extrapolated at a density growing with f).
FIRST_POOL = 32


@dataclass(frozen=True)
class ModeCount:
    """The rule's mode count ``modes``, its frequency ``f_max_hz`` [Hz], and ``capped``: the
    count was cut at MAX_MODES (or the body's elastic DOF) before reaching f_max."""

    modes: int
    f_max_hz: float
    capped: bool


def mode_count(fe, free, duration_s: float) -> ModeCount:
    """The number of elastic free-free modes of ``fe`` below BANDWIDTH / ``duration_s``
    (module doc), from ``free`` (k -> the lowest k free-free modes, frequencies first: the
    setup cache's source); at least 1, at most MAX_MODES (or the body's elastic DOF)."""
    f_max = BANDWIDTH / duration_s
    n_free = max(fe.n_dof - 7, 1)
    pool = min(FIRST_POOL, n_free)
    while True:
        f_hz = np.asarray(free(pool + 6)[0], float)[6:]
        if f_hz[-1] >= f_max or pool >= min(MAX_MODES, n_free):
            break
        # the count grows at least linearly with f (a plate's density; faster in a solid)
        pool = min(math.ceil(1.2 * pool * f_max / max(f_hz[-1], 1.0)), MAX_MODES, n_free)
    n = int(np.count_nonzero(f_hz < f_max))
    capped = n >= pool and f_hz[-1] < f_max
    return ModeCount(max(n, 1), f_max, bool(capped))


def estimated_modes(cfg, modes: int | None, duration_s: float) -> tuple[int, str, float, bool]:
    """(mode count, "given" | "model" | "criterion", f_max [Hz], capped) of the estimated
    model: ``modes`` if given, else the body's model's (a kind that uses modes), else the
    criterion of studies/mode_estimate.py at the contact duration ``duration_s`` [s]."""
    from flexmvm.assembly.build_cache import default_setup

    if modes is not None:
        return int(modes), "given", math.nan, False
    if cfg.model.kind.uses_modes and cfg.model.modes:
        return int(cfg.model.modes), "model", math.nan, False
    fe, free = default_setup().free_modes_source(cfg)
    c = mode_count(fe, free, duration_s)
    return c.modes, "criterion", c.f_max_hz, c.capped
