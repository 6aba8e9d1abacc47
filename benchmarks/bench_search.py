"""Contact search on large surfaces: the cost of search.scan_nodes (broad phase, candidate
supersets, closest-point projection) against the size of the master surface, with the facet
grid (contact.search_state.facet_grid) and with one cell holding every facet (the search before the
grid: a node's superset rebuilt from all facets).

    python benchmarks/bench_search.py [--sizes 10000 100000] [--slave 2000]

Master: a flat square of n nodes (quads, z = 0, 0.3 m wide). Slave: a spherical cap (R 10 mm)
of --slave nodes touching its centre, and the same number spread over the whole square 0.1 mm
above it (every node near a facet). Times: the first scan (every superset built) and a scan
after a 1 um move (warm: supersets kept), medians of 5, in ms; the ratio of the grid's first
scan at the largest size to the smallest shows how the cost follows the surface's size.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from flexmvm.contact.geometry import facet_adjacency
from flexmvm.contact.projection import REC_LEN, projection_params
from flexmvm.contact.search import scan_nodes
from flexmvm.contact.search_state import (
    FacetGrid,
    FacetSurface,
    MemoArrays,
    SearchState,
    facet_edges,
    facet_grid,
    facet_planes,
)


def square(n: int, width: float = 0.3):
    k = round(float(np.sqrt(n)))
    x = np.linspace(-width / 2, width / 2, k)
    X, Y = np.meshgrid(x, x, indexing="ij")
    xm = np.column_stack([X.ravel(), Y.ravel(), np.zeros(k * k)])
    idx = np.arange(k * k).reshape(k, k)
    conn = np.column_stack(
        [idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()]
    ).astype(np.int64)
    corners = xm[conn]
    cent = corners.mean(axis=1)
    geo = np.column_stack([cent, np.linalg.norm(corners - cent[:, None], axis=2).max(axis=1)])
    return xm, conn, geo


def cap(n: int, R: float = 0.01):
    rng = np.random.default_rng(1)
    th = np.arccos(1 - rng.random(n) * (1 - np.cos(np.radians(30))))
    ph = rng.random(n) * 2 * np.pi
    return np.column_stack(
        [R * np.sin(th) * np.cos(ph), R * np.sin(th) * np.sin(ph), R - R * np.cos(th)]
    )


def spread(n: int, width: float = 0.3):
    rng = np.random.default_rng(2)
    return np.column_stack([(rng.random((n, 2)) - 0.5) * width * 0.98, np.full(n, 1e-4)])


def scan_ms(xs, xm, conn, geo, one_cell: bool, reach: float = 2e-4) -> tuple[float, float]:
    ns, nf = len(xs), len(conn)
    adj = facet_adjacency(conn)
    rho = max(reach, 0.5 * float(np.median(geo[:, 3])))
    box = np.vstack([xm.min(axis=0), xm.max(axis=0)])
    if one_cell:
        lo = geo[:, :3].min(axis=0)
        span = float((geo[:, :3].max(axis=0) - lo).max()) + 1.0
        grid = FacetGrid(
            np.array([*lo, span, float(geo[:, 3].max())]),
            np.ones(3, np.int64),
            np.array([0, nf], np.int64),
            np.arange(nf, dtype=np.int64),
        )
    else:
        grid = facet_grid(geo)
    planes = facet_planes(xm[conn], 0, geo[:, :3])
    edges = facet_edges(xm[conn], 0)
    surface = FacetSurface(geo, conn, 0, *adj, box, rho, projection_params(), grid, planes, edges)
    times = {True: [], False: []}
    for rep in range(5):
        state = SearchState.empty(ns, nf, 256)
        facet, out = np.full(ns, -1, np.int64), np.zeros((ns, 11))
        for cold, shift in ((True, 0.0), (False, 1e-6)):
            x = xs + shift
            memo = MemoArrays(
                np.zeros((ns, 0), np.int64),
                np.zeros(ns, np.int64),
                np.zeros((ns, 0, REC_LEN)),
                np.full(2, -1, np.int64),
                np.array([rep * 2 + cold], np.int64),
                np.zeros(1, np.int64),
            )
            t0 = time.perf_counter()
            scan_nodes(
                x,
                np.zeros_like(x),
                xm,
                np.zeros_like(xm),
                np.zeros(3),
                np.eye(3),
                reach,
                0.0,
                surface,
                state,
                memo,
                facet,
                out,
                np.inf,  # every node searched
                np.zeros(len(x), np.int64),
            )
            times[cold].append(1e3 * (time.perf_counter() - t0))
    return float(np.median(times[True])), float(np.median(times[False]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10_000, 100_000])
    ap.add_argument("--slave", type=int, default=2000)
    args = ap.parse_args()
    print(f"CPU: {platform.processor() or platform.machine()}")
    scan_ms(cap(10), *square(400), one_cell=False)  # compile
    first = {}
    for n in args.sizes:
        xm, conn, geo = square(n)
        for name, xs in (("cap", cap(args.slave)), ("spread", spread(args.slave))):
            g = scan_ms(xs, xm, conn, geo, one_cell=False)
            a = scan_ms(xs, xm, conn, geo, one_cell=True)
            first.setdefault(name, []).append(g[0])
            print(
                f"master {len(xm):>7} nodes, {args.slave} slave nodes ({name}): grid first "
                f"{g[0]:8.1f} ms, warm {g[1]:6.2f} ms | all facets first {a[0]:9.1f} ms, "
                f"warm {a[1]:6.2f} ms | all/grid first {a[0] / g[0]:6.1f}"
            )
    for name, v in first.items():
        print(
            f"{name}: grid first scan, largest / smallest master: {v[-1] / v[0]:.2f} "
            f"(master {args.sizes[-1] / args.sizes[0]:.0f} x larger)"
        )


if __name__ == "__main__":
    main()
