"""Step convergence of the contact force history (issue 14 part 3).

    python benchmarks/contact_law_convergence.py MODEL THETA LAW REDIS SCENARIO DT_US [DT_US ...]

Runs benchmarks/contact_law_study.py's case (MODEL: shipped or a model kind for every body;
LAW: velocity or position; REDIS: 0 or 1) at each step DT_US [us] (largest first, each half
the one before), prints each run's measures line, then the relative L2 differences of the
force histories at the outputs (2-us impulse averages) between successive steps,
|f(h) - f(h/2)| / |f(h_min)|, and the observed order log2 of their ratio: for the whole
history and for its content below 200, 100 and 50 kHz (an FFT low-pass of the output series;
the force is zero before and after the impact, so the series needs no window). The
contact-step h of the scenario is overridden; free flight keeps the scenario's dt_max.
"""

from __future__ import annotations

import sys
from itertools import pairwise

import numpy as np
from contact_law_study import main as study

CUTS_KHZ = (None, 200.0, 100.0, 50.0)


def low_pass(f: np.ndarray, dt_s: float, cut_khz: float | None) -> np.ndarray:
    if cut_khz is None:
        return f
    spec = np.fft.rfft(f)
    spec[np.fft.rfftfreq(f.size, dt_s) > cut_khz * 1e3] = 0.0
    return np.fft.irfft(spec, f.size)


def orders(histories: dict[float, tuple[np.ndarray, np.ndarray]]) -> list[dict]:
    hs = sorted(histories, reverse=True)
    t0, _ = histories[hs[-1]]
    n = min(len(histories[h][1]) for h in hs)
    for h in hs:
        if not np.allclose(histories[h][0][:n], t0[:n], rtol=0, atol=1e-12):
            raise SystemExit(f"output times differ at h = {h} us")
    dt = float(t0[1] - t0[0])
    out = []
    for cut in CUTS_KHZ:
        g = {h: low_pass(histories[h][1][:n], dt, cut) for h in hs}
        norm = np.linalg.norm(g[hs[-1]])
        diffs = [float(np.linalg.norm(g[a] - g[b]) / norm) for a, b in pairwise(hs)]
        ords = [float(np.log2(a / b)) for a, b in pairwise(diffs)]
        out.append({"below_khz": cut, "diffs": diffs, "orders": ords})
    return out


def run(model, theta, law, redis, scenario, *dts):
    hs = sorted((float(d) for d in dts), reverse=True)
    histories = {}
    for h in hs:
        _, t, f = study(model, theta, law, redis, h, None, scenario)
        histories[h] = (t, f)
    print(f"h [us]: {hs}")
    for row in orders(histories):
        cut = "whole history" if row["below_khz"] is None else f"below {row['below_khz']:g} kHz"
        print(
            f"{cut:>16}: |f(h) - f(h/2)| / |f| = "
            + ", ".join(f"{d:.3e}" for d in row["diffs"])
            + "; observed order "
            + ", ".join(f"{o:.2f}" for o in row["orders"])
        )


if __name__ == "__main__":
    if len(sys.argv) < 8:
        raise SystemExit(__doc__)
    run(*sys.argv[1:])
