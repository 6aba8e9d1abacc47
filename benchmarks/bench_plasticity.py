"""PlasticBody.respond compiled (plasticity.kernels) against its numpy reference
(plasticity.kernels_numpy), same bodies, same states, one run.

    python benchmarks/bench_plasticity.py [--repeats 3] [--cells 100]

Bodies: the gmsh block of the sphere-on-block case (scenarios/meshes/block_60x60x30.msh,
TET10, 11 points per cell, ~25,000 points) and a HEX27 beam (27 points per cell), each in
a plastic state (about half the points yielding, the rest elastic or unloading), whole and
on ``--cells`` cells (on_cells: the time step's cells that can yield). Prints the best wall
time per 1,000 integration points of each path and their ratio (side by side, so machine
load mostly cancels; alternate calls, at least --repeats and 0.3 s of each), and the one-off cost of the tangent's CSR structure of a body (its
first respond).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from flexmvm.materials import ALUMINIUM
from flexmvm.mesh.io import read_mesh
from flexmvm.mesh.structured import hex27_beam
from flexmvm.plasticity.body import PlasticBody
from flexmvm.plasticity.kernels_numpy import respond_numpy
from flexmvm.plasticity.material import J2Plasticity
from flexmvm.plasticity.return_mapping import von_mises

ROOT = Path(__file__).resolve().parents[1]
PLASTIC = J2Plasticity(276e6, hardening_pa=1e9, kinematic_hardening_pa=1e9)


def _loaded(body: PlasticBody):
    """A displacement u2 and the state it is applied from (body's history after u1), random
    fields scaled so that u1 yields about half of the points (the tests' recipe)."""
    rng = np.random.default_rng(0)
    u = rng.normal(0.0, 1.0, body.n_dof)
    elastic = PlasticBody(body.mesh, body.material, J2Plasticity(1e30), body.blocks)
    scale = PLASTIC.yield_pa / np.median(
        von_mises(elastic.respond(u, elastic.virgin_state()).stress)
    )
    state = body.respond(scale * u, body.virgin_state()).state
    return scale * (u + rng.normal(0.0, 1.0, body.n_dof)), state


def _best_pair(compiled, numpy_path, repeats: int) -> tuple[float, float]:
    """Best wall times of the two paths, called alternately (so load drift hits both) at
    least ``repeats`` times and until each has run 0.3 s."""
    best, spent = [float("inf")] * 2, [0.0, 0.0]
    k = 0
    while k < repeats or min(spent) < 0.3:
        for i, fn in enumerate((compiled, numpy_path)):
            t0 = time.perf_counter()
            fn()
            dt = time.perf_counter() - t0
            best[i], spent[i] = min(best[i], dt), spent[i] + dt
        k += 1
    return best[0], best[1]


def _compare(name: str, body: PlasticBody, u, state, repeats: int) -> None:
    t0 = time.perf_counter()
    fresh = PlasticBody(body.mesh, body.material, body.plastic, body.blocks, body.cell_ids)
    fresh.respond(u, state)  # the first call finds the CSR structure
    first = time.perf_counter() - t0
    t_c, t_n = _best_pair(
        lambda: fresh.respond(u, state), lambda: respond_numpy(fresh, u, state), repeats
    )
    k = body.n_points / 1000.0
    yielding = fresh.respond(u, state).yielding.mean()
    print(
        f"{name:34s} {body.n_points:7d} pts ({yielding:4.0%} yield)  numpy {t_n / k * 1e3:8.3f}"
        f" ms/1k pts  compiled {t_c / k * 1e3:7.3f} ms/1k pts  ratio {t_n / t_c:6.1f}"
        f"  (first call {first * 1e3:.1f} ms)"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--cells", type=int, default=100)
    args = ap.parse_args()
    bodies = {
        "gmsh block, TET10": read_mesh(ROOT / "scenarios/meshes/block_60x60x30.msh"),
        "beam, HEX27": hex27_beam(0.4, 0.02, 0.02, 200),
    }
    for name, mesh in bodies.items():
        body = PlasticBody.build(mesh, ALUMINIUM, PLASTIC)
        u, state = _loaded(body)
        body.respond(u, state)  # compile (or load the cached kernels)
        _compare(f"{name}, whole", body, u, state, args.repeats)
        cells = np.arange(min(args.cells, mesh.n_cells))
        ids = body.point_ids(cells)
        _compare(
            f"{name}, {len(cells)} cells", body.on_cells(cells), u, state.take(ids), args.repeats
        )


if __name__ == "__main__":
    main()
