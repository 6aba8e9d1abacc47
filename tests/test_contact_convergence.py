"""The contact force history converges at second order with the step on the seed scenarios'
scheme (issue 14 part 3): theta = 1/2 + h / (4 tau), position law, massless contact nodes.

The short seed case (scenarios/rod_impact_short.toml: b1 full FE, b2 Craig-Bampton 1-3 + 37)
at h = 2, 1 and 0.5 us (theta 0.54, 0.52, 0.51), the force at the 2-us outputs (impulse
averages); the relative L2 differences between successive steps, |f(h) - f(h/2)| / |f(h_min)|,
and the observed order log2 of their ratio, for the whole history and for its content below
100 kHz (an FFT low-pass: the force is zero before and after the impact). Measured: whole
2.84e-3, 7.26e-4, order 1.97; below 100 kHz 2.82e-3, 7.18e-4, order 1.98 (at h = 1, 0.5 and
0.25 us, as benchmarks/contact_law_convergence.py prints: whole 7.26e-4, 2.01e-4, order 1.85;
below 100 kHz 7.18e-4, 1.86e-4, order 1.95). The same runs at a fixed theta fail the bounds:
0.55 gives order 1.05 below 100 kHz and 1.06 whole (first order), 1/2 gives 1.77 below
100 kHz and 1.38 whole (the meshes' undamped content at the step's scale; at h = 1, 0.5 and
0.25 us: 1.01 and 1.01 at 0.55, 1.78 and 1.04 at 1/2). The h = 0.5 us run is the scenario's own, shared with
test_contact_ringing and test_validation_live (tests/_short_case.py).
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import pytest
from _short_case import short_run

# A convergence study (three step sizes): in `pytest -m validation`, not the default run; the
# stored validation's step_convergence rows check the same case at dt and dt/2.
pytestmark = pytest.mark.validation


def _below(f: np.ndarray, dt_s: float, cut_hz: float | None) -> np.ndarray:
    if cut_hz is None:
        return f
    spec = np.fft.rfft(f)
    spec[np.fft.rfftfreq(f.size, dt_s) > cut_hz] = 0.0
    return np.fft.irfft(spec, f.size)


def test_force_history_second_order_in_the_step():
    """Observed order >= 1.8 below 100 kHz and >= 1.6 whole (measured 1.98 and 1.97: the
    bounds leave room for the pre-asymptotic spread of three steps, while first order reads
    ~1); theta follows the step as the scenario's hf_damping_time_s says."""
    runs = [short_run("scenario", h)[0] for h in (2e-6, 1e-6, None)]
    assert [r.built.grid.theta for r in runs] == [0.54, 0.52, 0.51]
    curves = [r.result.curves()[:2] for r in runs]
    n = min(len(t) for t, _ in curves)
    t = curves[0][0][:n]
    assert all(np.allclose(c[0][:n], t, rtol=0, atol=1e-12) for c in curves)
    for cut, least in ((100e3, 1.8), (None, 1.6)):
        f = [_below(c[1][:n], float(t[1] - t[0]), cut) for c in curves]
        d1, d2 = (np.linalg.norm(a - b) / np.linalg.norm(f[-1]) for a, b in pairwise(f))
        assert np.log2(d1 / d2) >= least, (cut, d1, d2)
