"""Foundation timings: rod mesh, FE assembly, free-free eigen solve, Craig-Bampton basis.

Run: ``python benchmarks/bench_foundation.py [--skip-large]``. Prints, for the default rods
(flat-flat aluminium, hemisphere-flat brass) and a rod mesh about 8 times larger, the wall
times of rod_mesh, assemble, free_modes (first 20 free-free modes) and build_basis
(Craig-Bampton, 43 fixed-interface modes, seed selection 1-1, reference = 3-2-1 support on
end B). Times from time.perf_counter, one run each, in seconds.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TypeVar

from flexmvm.fe import assemble, free_modes
from flexmvm.materials import ALUMINIUM, BRASS, Material
from flexmvm.mesh.rod import EndShape, RodSpec, rod_mesh
from flexmvm.reduction import BasisKind, build_basis, three_two_one

T = TypeVar("T")


@dataclass(frozen=True)
class Case:
    """A rod to time."""

    name: str
    spec: RodSpec
    material: Material


def timed(fn: Callable[[], T]) -> tuple[T, float]:
    """Call fn() once; return (result, wall seconds)."""
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def refined(spec: RodSpec) -> RodSpec:
    """About 8x the nodes: twice the cross-section divisions, half the axial element sizes."""
    return replace(
        spec,
        core_elements=2 * spec.core_elements,
        n_rings=2 * spec.n_rings,
        first_element_m=spec.first_element_m / 2,
        max_element_m=spec.max_element_m / 2,
    )


def run_case(case: Case, n_free: int = 20, n_cb: int = 43) -> dict[str, float]:
    """Time one rod; returns the numbers printed."""
    rod, t_mesh = timed(lambda: rod_mesh(case.spec))
    mesh = rod.mesh
    fe, t_asm = timed(lambda: assemble(mesh, case.material))
    (freqs, _), t_eig = timed(lambda: free_modes(fe, n_free))
    reference = three_two_one(mesh, mesh.node_set("end_b"))
    basis, t_cb = timed(
        lambda: build_basis(fe, BasisKind.CRAIG_BAMPTON, reference, rod.selection(1, 1), n_cb)
    )
    return {
        "nodes": mesh.n_nodes,
        "cells": mesh.n_cells,
        "dof": fe.n_dof,
        "nnz_K": fe.K.nnz,
        "mesh_s": t_mesh,
        "assemble_s": t_asm,
        "eig20_s": t_eig,
        "cb43_s": t_cb,
        "f7_hz": float(freqs[6]),
        "nq": basis.nq,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skip-large", action="store_true", help="skip the 8x rod")
    args = parser.parse_args()
    flat = RodSpec()
    cases = [
        Case("al flat-flat", flat, ALUMINIUM),
        Case("brass hemi-flat", RodSpec(end_a=EndShape.HEMISPHERE), BRASS),
    ]
    if not args.skip_large:
        cases.append(Case("al flat-flat 8x", refined(flat), ALUMINIUM))
    head = (
        f"{'case':18s} {'nodes':>7s} {'cells':>6s} {'dof':>7s} {'nnz(K)':>10s} "
        f"{'mesh':>7s} {'assemble':>9s} {'eig20':>7s} {'CB43 1-1':>9s} {'f7 [Hz]':>9s}"
    )
    print(head)
    print("-" * len(head))
    for case in cases:
        r = run_case(case)
        print(
            f"{case.name:18s} {r['nodes']:7d} {r['cells']:6d} {r['dof']:7d} {r['nnz_K']:10d} "
            f"{r['mesh_s']:7.3f} {r['assemble_s']:9.3f} {r['eig20_s']:7.3f} "
            f"{r['cb43_s']:9.3f} {r['f7_hz']:9.3f}",
            flush=True,
        )
    print(
        "times in seconds (time.perf_counter, one run); CB: 43 fixed-interface modes, "
        "selection 1-1, reference three_two_one(end_b)"
    )


if __name__ == "__main__":
    main()
