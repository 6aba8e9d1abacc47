"""Figures of a run, drawn with matplotlib's Agg canvas (no display, no pyplot state).

:func:`plot_run` is the seed's fig. 5 layout (Wang, Hong, Liu 2014): contact force against time
on top, the axial velocity of the probes (b2's impact end and free end) below, every run (FE,
MVM, theory, ...) overlaid with its own line style. PNGs are written atomically.
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from flexmvm.errors import InputError
from flexmvm.integrate.run_result import RunResult
from flexmvm.metrics.ncc import Comparison, compare_force
from flexmvm.results.atomic import atomic_path

__all__ = ["curves_from_run", "plot_force_comparison", "plot_run"]

#: One (t [s], contact force [N] or None, {probe name: velocity [m/s]}) per run label.
Curves = tuple[Any, Any, Mapping[str, Any]]

STYLES = ("-", "--", "-.", ":", (0, (5, 1, 1, 1, 1, 1)), (0, (1, 3)))
COLOURS = ("C0", "C1", "C2", "C3", "C4", "C5", "C6", "C7")
_THEORY = "theory"


def curves_from_run(run: RunResult, probe_axis: int = 0) -> Curves:
    """(t [s], contact force [N], {probe: velocity component probe_axis [m/s]}) of a run."""
    if isinstance(probe_axis, bool) or probe_axis not in (0, 1, 2):
        raise InputError(f"probe_axis: expected 0, 1 or 2 (x, y, z), got {probe_axis!r}")
    v = np.asarray(run.probe_v, dtype=float)
    return (
        np.asarray(run.t, dtype=float),
        np.asarray(run.contact_force, dtype=float),
        {name: v[:, i, probe_axis] for i, name in enumerate(run.probe_names)},
    )


def _series(label: str, what: str, t: np.ndarray, y: Any) -> np.ndarray:
    arr = np.asarray(y, dtype=float)
    if arr.shape != t.shape:
        raise InputError(f"run {label!r}: {what} has shape {arr.shape}; expected {t.shape} like t")
    return arr


def _checked(runs: Mapping[str, Curves]) -> list[tuple[str, np.ndarray, np.ndarray | None, dict]]:
    out = []
    for label, curves in runs.items():
        try:
            t, force, probes = curves
        except (TypeError, ValueError):
            raise InputError(
                f"run {label!r}: expected (t, contact_force, {{probe: velocity}}), got "
                f"{type(curves).__name__}"
            ) from None
        t = np.asarray(t, dtype=float)
        if t.ndim != 1 or t.size < 2:
            raise InputError(
                f"run {label!r}: expected a 1D time axis of >= 2 samples, got {t.shape}"
            )
        f = None if force is None else _series(label, "contact_force", t, force)
        v = {name: _series(label, f"probe {name!r}", t, y) for name, y in (probes or {}).items()}
        out.append((str(label), t, f, v))
    return out


def save_figure(fig: Figure, path: str | os.PathLike[str], dpi: int) -> None:
    FigureCanvasAgg(fig)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi)


def plot_run(
    path_png: str | os.PathLike[str],
    runs: Mapping[str, Curves],
    theory: Curves | None = None,
    *,
    title: str = "",
    dpi: int = 150,
) -> None:
    """Seed fig. 5: contact force [N] (top) and probe axial velocity [m/s] (bottom) vs t [ms].

    runs: label -> (t [s] (n,), contact force [N] (n,) or None, {probe: velocity [m/s] (n,)});
    theory: the same triple, drawn last as "theory" in black. Each label gets its own line style
    (and colour in the force panel); each probe its own colour in the velocity panel. Written
    atomically as PNG. Raises InputError for no runs or arrays whose length differs from t.
    """
    all_runs = dict(runs)
    if theory is not None:
        all_runs[_THEORY] = theory
    checked = _checked(all_runs)
    if not checked:
        raise InputError("plot_run: expected at least one run, got none")
    probes = list(dict.fromkeys(p for *_, v in checked for p in v))
    probe_colour = dict(zip(probes, itertools.cycle(COLOURS)))
    fig = Figure(figsize=(7.0, 6.5), layout="constrained")
    ax_f, ax_v = fig.subplots(2, 1, sharex=True)
    for (label, t, f, v), style, colour in zip(
        checked, itertools.cycle(STYLES), itertools.cycle(COLOURS)
    ):
        theo = label == _THEORY
        lw = 1.2 if theo else 1.0
        if f is not None:
            ax_f.plot(
                t * 1e3, f, linestyle=style, color="k" if theo else colour, lw=lw, label=label
            )
        for name, y in v.items():
            ax_v.plot(
                t * 1e3,
                y,
                linestyle=style,
                color=probe_colour[name],
                lw=lw,
                label=f"{label}: {name}",
            )
    ax_f.set_ylabel("contact force [N]")
    ax_v.set_ylabel("axial velocity [m/s]")
    ax_v.set_xlabel("time [ms]")
    for ax in (ax_f, ax_v):
        ax.grid(True, lw=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize="small")
    if title:
        fig.suptitle(title)
    save_figure(fig, path_png, dpi)


def plot_force_comparison(
    path_png: str | os.PathLike[str],
    reference: tuple[Any, Any],
    candidates: Mapping[str, tuple[Any, Any]],
    *,
    reference_label: str = "FE",
    dpi: int = 150,
) -> dict[str, Comparison]:
    """Contact force [N] vs t [ms] of candidates over a reference, each legend entry with its
    metrics.ncc.compare_force result (NCC, relative peak, impulse and duration errors).

    reference, candidates[label]: (t [s], force [N]). Returns label -> Comparison. Written
    atomically as PNG. Raises InputError as compare_force does.
    """
    t_ref, f_ref = (np.asarray(a, dtype=float) for a in reference)
    results: dict[str, Comparison] = {}
    fig = Figure(figsize=(7.0, 4.0), layout="constrained")
    ax = fig.subplots()
    ax.plot(t_ref * 1e3, f_ref, "k-", lw=1.4, label=reference_label)
    styles: Sequence = STYLES[1:] + STYLES[:1]
    for (label, (t, f)), style, colour in zip(
        candidates.items(), itertools.cycle(styles), itertools.cycle(COLOURS)
    ):
        t, f = np.asarray(t, dtype=float), np.asarray(f, dtype=float)
        c = compare_force(t_ref, f_ref, t, f)
        results[label] = c
        ax.plot(
            t * 1e3,
            f,
            linestyle=style,
            color=colour,
            lw=1.0,
            label=(
                f"{label}: NCC {c.ncc:.4f}, peak {c.peak_err:+.1%}, "
                f"impulse {c.impulse_err:+.1%}, duration {c.duration_err:+.1%}"
            ),
        )
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("contact force [N]")
    ax.grid(True, lw=0.3)
    ax.legend(fontsize="small")
    save_figure(fig, path_png, dpi)
    return results
