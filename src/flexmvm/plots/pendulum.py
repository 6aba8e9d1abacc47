"""Figure of a whole pendulum event (scenarios/pendulum_release.toml): string angles, the gap
of the contact surfaces and the contact force against time, the force's contact window zoomed
in an inset. Agg canvas, written atomically; import this module lazily (matplotlib).
"""

from __future__ import annotations

import os
from collections.abc import Mapping

import numpy as np
from matplotlib.figure import Figure

from flexmvm.errors import InputError
from flexmvm.plots.figures import COLOURS, save_figure

__all__ = ["plot_event"]


def plot_event(
    path_png: str | os.PathLike[str],
    t_s,
    angle_rad: Mapping[str, np.ndarray],
    gap_m,
    force_n,
    contact_intervals_s=(),
    *,
    title: str = "",
    dpi: int = 150,
) -> None:
    """Three panels against t [s]: the angle of every string from the vertical [deg]
    (angle_rad: label -> (n,)), the gap [mm] (NaN: not drawn) and the contact force [N] with
    an inset zoomed on the contact (the first interval's start to the last's end, padded by a
    quarter of the contact time each side). InputError for arrays whose length differs from
    t_s or fewer than 2 outputs."""
    t = np.asarray(t_s, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise InputError(f"plot_event: expected at least 2 output times, got shape {t.shape}")
    gap = np.asarray(gap_m, dtype=float)
    force = np.asarray(force_n, dtype=float)
    series = {
        "gap_m": gap,
        "force_n": force,
        **{f"angle_rad[{k}]": np.asarray(v, float) for k, v in angle_rad.items()},
    }
    for name, arr in series.items():
        if arr.shape != t.shape:
            raise InputError(f"plot_event: {name} has shape {arr.shape}; expected {t.shape}")
    fig = Figure(figsize=(8.0, 8.5))
    ax_a, ax_g, ax_f = fig.subplots(3, 1, sharex=True)
    for i, (label, a) in enumerate(angle_rad.items()):
        ax_a.plot(
            t,
            np.degrees(np.asarray(a, float)),
            color=COLOURS[i % len(COLOURS)],
            ls="-" if i % 2 == 0 else "--",
            label=f"string {label}",
        )
    ax_a.set_ylabel("string angle from vertical [deg]")
    ax_a.legend(loc="best", fontsize=8)
    ax_g.plot(t, 1e3 * gap, color="C0")
    ax_g.set_ylabel("gap of the contact surfaces [mm]")
    ax_f.plot(t, force, color="C3")
    ax_f.set_ylabel("contact force [N]")
    ax_f.set_xlabel("t [s]")
    for ax in (ax_a, ax_g, ax_f):
        ax.grid(True, alpha=0.3)
    ivs = [tuple(map(float, iv)) for iv in contact_intervals_s]
    if ivs:
        t0, t1 = ivs[0][0], ivs[-1][1]
        pad = 0.25 * max(t1 - t0, 1e-9)
        keep = (t >= t0 - pad) & (t <= t1 + pad)
        for ax in (ax_g, ax_f):
            ax.axvspan(t0, t1, color="0.85", zorder=0)
        ins = ax_f.inset_axes([0.06, 0.25, 0.45, 0.68])
        ins.plot(1e3 * (t[keep] - t0), force[keep], color="C3")
        ins.set_xlabel(f"t - {t0:.6f} s [ms]", fontsize=7)
        ins.set_ylabel("[N]", fontsize=7)
        ins.tick_params(labelsize=7)
        ins.grid(True, alpha=0.3)
        ins.set_title("contact (zoom)", fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    save_figure(fig, path_png, dpi)
