"""Figures of the studies (seed figs. 7, 8, 9), Agg canvas, written atomically as PNG.

- :func:`plot_ncc_map`: NCC of the contact force over node selection (x, ordered by node
  count) x mode count (y), seed fig. 7; cells not evaluated (a search) are blank.
- :func:`plot_ncc_modes`: NCC against the number of modes, one line per selection, the node
  count in the legend, seed fig. 8.
- :func:`plot_materials`: NCC against modes per material and selection, seed fig. 9 / table 2.
- :func:`plot_ncc_dof_fronts`: force NCC against DOF, every model of each kind (node
  selections, interface bases) as points and its front (the best NCC at or below each DOF).
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from flexmvm.errors import InputError
from flexmvm.plots.figures import COLOURS, STYLES, save_figure

__all__ = ["front", "plot_materials", "plot_ncc_dof_fronts", "plot_ncc_map", "plot_ncc_modes"]


def front(points: Sequence[tuple[float, float]]) -> list[tuple[float, float]]:
    """The Pareto front of (dof, ncc) points: the points with a higher NCC than every point
    of fewer or equal DOF, in DOF order."""
    out: list[tuple[float, float]] = []
    for dof, ncc in sorted(points, key=lambda p: (p[0], -p[1])):
        if not out or ncc > out[-1][1]:
            out.append((dof, ncc))
    return out


def plot_ncc_dof_fronts(
    path_png: str | os.PathLike[str],
    kinds: Mapping[str, Sequence[tuple[float, float]]],
    *,
    target: float | None = None,
    title: str = "",
    dpi: int = 150,
) -> None:
    """Force NCC against DOF (log x): per kind (label -> (dof, ncc) points) the points and
    their front; y as 1 - NCC on a log axis so that 0.99 and 0.999 are apart; ``target``: a
    horizontal line at that NCC."""
    if not any(kinds.values()):
        raise InputError("plot_ncc_dof_fronts: expected at least one (dof, ncc) point")
    fig = Figure(figsize=(7.0, 4.6))
    ax = fig.add_subplot(1, 1, 1)
    for (label, pts), colour in zip(kinds.items(), itertools.cycle(COLOURS), strict=False):
        pts = [(float(d), float(n)) for d, n in pts if np.isfinite(n)]
        if not pts:
            continue
        d, n = np.array(pts).T
        ax.scatter(d, np.clip(1.0 - n, 1e-6, None), s=12, color=colour, alpha=0.45)
        fd, fn = np.array(front(pts)).T
        ax.step(
            fd,
            np.clip(1.0 - fn, 1e-6, None),
            where="post",
            color=colour,
            lw=1.8,
            label=f"{label}: front",
        )
    if target is not None:
        ax.axhline(1.0 - target, color="k", ls=":", lw=1.0, label=f"NCC = {target:g}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("elastic DOF of the body")
    ax.set_ylabel("1 - force NCC against full FE")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title, fontsize=10)
    save_figure(fig, path_png, dpi=dpi)


def _selections(rows: Sequence[Mapping[str, Any]]) -> list[tuple[int, int, int]]:
    """(layers, laps, nodes) of the rows, ordered by node count then (layers, laps)."""
    sel = {(int(r["layers"]), int(r["laps"])): int(r["nodes"]) for r in rows}
    return sorted(((i, j, n) for (i, j), n in sel.items()), key=lambda s: (s[2], s[0], s[1]))


def _check(rows: Sequence[Mapping[str, Any]], what: str) -> None:
    if not rows:
        raise InputError(f"{what}: expected at least one row, got none")


def plot_ncc_map(
    path_png: str | os.PathLike[str],
    rows: Sequence[Mapping[str, Any]],
    *,
    title: str = "",
    dpi: int = 150,
) -> None:
    """Seed fig. 7: colour map of ncc_force, node selection 'i-j (n)' x modes; the value is
    written in each evaluated cell, failed/missing cells are blank."""
    _check(rows, "plot_ncc_map")
    sels = _selections(rows)
    modes = sorted({int(r["modes"]) for r in rows})
    grid = np.full((len(modes), len(sels)), np.nan)
    col = {(i, j): c for c, (i, j, _) in enumerate(sels)}
    for r in rows:
        if r.get("ncc_force") is not None:
            grid[modes.index(int(r["modes"])), col[(int(r["layers"]), int(r["laps"]))]] = float(
                r["ncc_force"]
            )
    fig = Figure(
        figsize=(max(5.0, 0.45 * len(sels) + 2.5), max(3.0, 0.4 * len(modes) + 1.8)),
        layout="constrained",
    )
    ax = fig.subplots()
    finite = grid[np.isfinite(grid)]
    lo = float(finite.min()) if finite.size else 0.0
    hi = float(finite.max()) if finite.size else 1.0
    im = ax.imshow(
        np.ma.masked_invalid(grid),
        origin="lower",
        aspect="auto",
        cmap="viridis",
        vmin=lo,
        vmax=hi if hi > lo else lo + 1e-12,
    )
    if len(sels) * len(modes) <= 200:
        for (a, b), v in np.ndenumerate(grid):
            if np.isfinite(v):
                ax.text(
                    b,
                    a,
                    f"{v:.4f}",
                    ha="center",
                    va="center",
                    fontsize=5,
                    color="w" if v < 0.5 * (lo + hi) else "k",
                )
    ax.set_xticks(
        range(len(sels)), [f"{i}-{j} ({n})" for i, j, n in sels], rotation=90, fontsize="small"
    )
    ax.set_yticks(range(len(modes)), [str(m) for m in modes])
    ax.set_xlabel("node selection i-j (retained nodes)")
    ax.set_ylabel("modes")
    fig.colorbar(im, ax=ax, label="NCC of the contact force")
    if title:
        ax.set_title(title)
    save_figure(fig, path_png, dpi)


def plot_ncc_modes(
    path_png: str | os.PathLike[str],
    rows: Sequence[Mapping[str, Any]],
    *,
    title: str = "",
    max_lines: int = 8,
    dpi: int = 150,
) -> None:
    """Seed fig. 8: ncc_force against modes, one line per selection (at most max_lines,
    spread over the node counts), legend 'i-j: n nodes'."""
    _check(rows, "plot_ncc_modes")
    sels = _selections(rows)
    if len(sels) > max_lines:
        pick = np.unique(np.linspace(0, len(sels) - 1, max_lines).round().astype(int))
        sels = [sels[k] for k in pick]
    fig = Figure(figsize=(7.0, 4.0), layout="constrained")
    ax = fig.subplots()
    for (i, j, n), style, colour in zip(sels, itertools.cycle(STYLES), itertools.cycle(COLOURS)):
        pts = sorted(
            (int(r["modes"]), float(r["ncc_force"]))
            for r in rows
            if (int(r["layers"]), int(r["laps"])) == (i, j) and r.get("ncc_force") is not None
        )
        if pts:
            m, v = zip(*pts)
            ax.plot(
                m,
                v,
                linestyle=style,
                color=colour,
                marker="o",
                ms=3,
                lw=1.0,
                label=f"{i}-{j}: {n} node{'s' if n != 1 else ''}",
            )
    _finish_ncc_axes(fig, ax, path_png, title, dpi)


def _finish_ncc_axes(fig, ax, path_png, title: str, dpi: int) -> None:
    """Labels, grid, legend and title of an NCC-against-modes panel; saves the figure."""
    ax.set_xlabel("modes")
    ax.set_ylabel("NCC of the contact force")
    ax.grid(True, lw=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize="small")
    if title:
        ax.set_title(title)
    save_figure(fig, path_png, dpi)


def plot_materials(
    path_png: str | os.PathLike[str],
    rows: Sequence[Mapping[str, Any]],
    *,
    title: str = "",
    dpi: int = 150,
) -> None:
    """Seed fig. 9: ncc_force against modes, a colour per material, a line style per
    selection; rows carry material, selection ('i-j'), modes, ncc_force. Rows with
    ``valid`` False (a run outside its model's validity, runs.guard.invalid_reason) get
    open markers."""

    _check(rows, "plot_materials")
    materials = list(dict.fromkeys(str(r["material"]) for r in rows))
    selections = list(dict.fromkeys(str(r["selection"]) for r in rows))
    colour = dict(zip(materials, itertools.cycle(COLOURS)))
    style = dict(zip(selections, itertools.cycle(STYLES)))
    fig = Figure(figsize=(7.0, 4.0), layout="constrained")
    ax = fig.subplots()
    for mat in materials:
        for sel in selections:
            pts = sorted(
                (int(r["modes"]), float(r["ncc_force"]))
                for r in rows
                if r["material"] == mat and r["selection"] == sel and r.get("ncc_force") is not None
            )
            if pts:
                m, v = zip(*pts)
                ax.plot(m, v, linestyle=style[sel], color=colour[mat], lw=1.0, label=f"{mat} {sel}")
                bad = {
                    int(r["modes"])
                    for r in rows
                    if r["material"] == mat and r["selection"] == sel and not r.get("valid", True)
                }
                for filled in (True, False):
                    mk = [(a, b) for a, b in pts if (a not in bad) is filled]
                    if mk:
                        ax.plot(
                            *zip(*mk),
                            linestyle="none",
                            marker="o",
                            ms=3 if filled else 5,
                            color=colour[mat],
                            markerfacecolor=colour[mat] if filled else "white",
                        )
    if not all(r.get("valid", True) for r in rows):
        ax.plot(
            [],
            [],
            linestyle="none",
            marker="o",
            ms=5,
            color="grey",
            markerfacecolor="white",
            label="outside validity (guard / energy)",
        )
    _finish_ncc_axes(fig, ax, path_png, title, dpi)
