"""Steps per second of the seed's aluminium rod, full FE and MVM (1-1 + 37 modes), same run.

    python benchmarks/bench_dynamics.py [--steps 200]

A free rod with an axial point load on its impact-end centre, stepped at h = 0.25 us; prints
steps/s of each model and their ratio (measured in the same run, so machine load cancels).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from flexmvm.bodies.build import body_from_fe
from flexmvm.fe.assembly import assemble
from flexmvm.integrate.driver import simulate
from flexmvm.integrate.run_result import TimeGrid
from flexmvm.integrate.state import BodyState
from flexmvm.integrate.system import NodeLoad, System
from flexmvm.materials import ALUMINIUM
from flexmvm.mesh.rod import RodSpec, rod_mesh
from flexmvm.reduction.basis import BasisKind, build_basis
from flexmvm.reduction.rod_reference import rod_reference


def _rate(body, node, steps, h=0.25e-6) -> float:
    sysm = System((body,), loads=(NodeLoad(0, node, (-600.0, 0.0, 0.0)),))
    st = BodyState(np.zeros(3), np.eye(3), np.zeros(body.nq), np.zeros(body.nv))
    simulate(sysm, [st], TimeGrid(5 * h, h, theta=0.5))  # warm-up: factorization
    t0 = time.perf_counter()
    simulate(sysm, [st], TimeGrid(steps * h, h, h, 10 * h, theta=0.5))
    return steps / (time.perf_counter() - t0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=200)
    args = ap.parse_args()
    rod = rod_mesh(RodSpec())
    fe = assemble(rod.mesh, ALUMINIUM)
    ref = rod_reference(rod)
    node = int(rod.mesh.node_set("end_a_centre")[0])
    t0 = time.perf_counter()
    full = body_from_fe("full", fe, build_basis(fe, BasisKind.FULL, ref))
    t_full = time.perf_counter() - t0
    t0 = time.perf_counter()
    mvm = body_from_fe(
        "mvm",
        fe,
        build_basis(
            fe, BasisKind.CRAIG_BAMPTON, ref, retained_nodes=rod.selection(1, 1), n_modes=37
        ),
    )
    t_mvm = time.perf_counter() - t0
    r_full = _rate(full, node, args.steps)
    r_mvm = _rate(mvm, node, args.steps)
    print(
        f"aluminium rod: {rod.mesh.n_nodes} nodes; full FE nq = {full.nq}, MVM 1-1+37 nq = {mvm.nq}"
    )
    print(f"body build: full {t_full:.2f} s, MVM {t_mvm:.2f} s")
    print(f"steps/s: full FE {r_full:.1f}, MVM {r_mvm:.1f}, ratio MVM/full = {r_mvm / r_full:.1f}")


if __name__ == "__main__":
    main()
