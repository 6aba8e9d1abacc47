"""Static stiffness of b2's contact nodes in each reduction basis (issue 15, item 2).

    python benchmarks/seed_stiffness.py [--mesh seed|default|both] [--modes 37]
                                        [--selections 1-1,1-3] [--json FILE]

The aluminium target rod b2 (1 m x 0.01 m, flat ends) is supported by its frame reference
condition (rod_reference: end B) and loaded statically on its impact face (end A), 1 N in total
pushing into the rod, by (a) a point force on the face's centre node and (b) the Hertz pressure
p(r) = p0 sqrt(1 - r^2/a^2) over a patch of radius a (default 0.461 mm, the wave-Hertz patch at
the peak force 615 N of the seed case), integrated on the quadratic faces (consistent nodal
forces). For each basis Psi the static response is u = Psi (Psi^T K Psi)^-1 Psi^T f; printed: the
compliance f.u / |F|^2 [m/N] (the displacement of the loaded node for (a), the pressure-weighted
mean displacement of the patch for (b)), its local part (minus L/(E A), the 1D compression of the
whole rod that every basis must carry) and the stiffness ratio to full FE. Full FE is the
reference: Craig-Bampton reproduces it exactly for loads on its retained nodes (its constraint
modes are the static response); the seed's eq. (4) bases do not.

Each mesh's record carries a provenance stamp (runs.provenance.script_stamp: code, libraries,
this script, its settings and the run key of the scenario the rod is read from).

Meshes: `seed` = scenarios/rod_impact_seed_mesh.toml's b2 (779 nodes), `default` =
scenarios/rod_impact.toml's b2 (8,349 nodes).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from flexmvm.assembly.build_cache import default_setup
from flexmvm.fe.assembly import assemble
from flexmvm.fe.modes import factor
from flexmvm.reduction.basis import BasisKind, build_basis
from flexmvm.reduction.rod_reference import rod_reference
from flexmvm.runs.provenance import script_stamp, stamp
from flexmvm.scenarios import load_scenario

ROOT = Path(__file__).resolve().parents[1]
MESHES = {
    "seed": ROOT / "scenarios" / "rod_impact_seed_mesh.toml",
    "default": ROOT / "scenarios" / "rod_impact.toml",
}
KINDS = (BasisKind.CRAIG_BAMPTON, BasisKind.SEED_BLOCK, BasisKind.SEED_FIXED)


def hertz_load(rod, a_m: float, n_min: int = 20) -> tuple[np.ndarray, float]:
    """Consistent nodal forces (3n,) [N] of a Hertz pressure of total 1 N over radius a_m on
    the end_a face (pointing +x, into the rod), midpoint rule on an n x n grid of each quad9
    face (n >= 10 points per patch radius), scaled to 1 N exactly; returns (f, the total [N]
    the rule integrated before scaling: its quadrature error)."""
    mesh = rod.mesh
    p0 = 3.0 / (2.0 * math.pi * a_m**2)
    f = np.zeros(3 * mesh.n_nodes)
    xi_nodes = np.array([-1, 1, 1, -1, 0, 1, 0, -1, 0], float)
    eta_nodes = np.array([-1, -1, 1, 1, -1, 0, 1, 0, 0], float)

    def lag(t, t_node):  # 1D quadratic Lagrange at -1, 0, 1 and its derivative
        val = np.where(
            t_node < 0, t * (t - 1) / 2, np.where(t_node > 0, t * (t + 1) / 2, 1 - t * t)
        )
        der = np.where(t_node < 0, t - 0.5, np.where(t_node > 0, t + 0.5, -2 * t))
        return val, der

    total = 0.0
    for face in rod.faces9["end_a"]:
        yz = mesh.nodes[face][:, 1:]
        size = float(np.ptp(yz, axis=0).max())
        if np.hypot(yz[:, 0], yz[:, 1]).min() > a_m + size:
            continue
        n = max(n_min, math.ceil(10 * size / a_m))
        t = (np.arange(n) + 0.5) / n * 2 - 1
        xi, eta = (g.ravel() for g in np.meshgrid(t, t, indexing="ij"))
        lx, dx = lag(xi[:, None], xi_nodes[None])
        ly, dy = lag(eta[:, None], eta_nodes[None])
        shape = lx * ly
        pts = shape @ yz
        jac = np.stack([(dx * ly) @ yz, (lx * dy) @ yz], axis=1)  # (npt, 2, 2)
        area = np.abs(np.linalg.det(jac)) * (2.0 / n) ** 2
        r2 = (pts**2).sum(axis=1) / a_m**2
        p = p0 * np.sqrt(np.clip(1 - r2, 0.0, None))
        fn = shape.T @ (p * area)
        np.add.at(f, 3 * face, fn)
        total += float((p * area).sum())
    return f / total, total


def full_response(fe, ref, f: np.ndarray) -> np.ndarray:
    """Static displacement (3n,) [m] of the reference-supported FE model under load f [N]."""
    free = ref.free_dofs(fe.n_dof)
    u = np.zeros(fe.n_dof)
    u[free] = factor(sp.csc_matrix(fe.K[free][:, free]))(f[free])
    return u


def reduced_response(fe, basis, f: np.ndarray) -> np.ndarray:
    """Static displacement Psi (Psi^T K Psi)^-1 Psi^T f [m] in a dense basis."""
    psi = basis.psi
    k_hat = psi.T @ (fe.K @ psi)
    q = np.linalg.solve(0.5 * (k_hat + k_hat.T), psi.T @ f)
    return psi @ q


def study(mesh_name: str, selections: list[tuple[int, int]], modes: int, a_m: float) -> dict:
    sc = load_scenario(MESHES[mesh_name])
    cfg = sc.body("b2")
    rod = default_setup().rod_mesh(cfg.rod.spec())
    material = cfg.material_obj()
    fe = assemble(rod.mesh, material)
    ref = rod_reference(rod)
    centre = int(rod.mesh.node_set("end_a_centre")[0])
    point = np.zeros(fe.n_dof)
    point[3 * centre] = 1.0  # +x: into the rod (end A is at x = 0, the rod covers x > 0)
    hertz, total = hertz_load(rod, a_m)
    loads = {"point": point, "hertz": hertz}
    area = math.pi * cfg.rod.radius_m**2
    rod_1d = cfg.rod.length_m / (material.E * area)
    out = {
        "mesh": mesh_name,
        "n_nodes": int(rod.mesh.n_nodes),
        "n_dof": int(fe.n_dof),
        "rod_1d_compliance_m_per_N": rod_1d,
        "modes": modes,
        "hertz_radius_m": a_m,
        "hertz_load_integrated_N": total,
        "rows": [],
        "provenance": script_stamp(
            Path(__file__),
            {
                "mesh": mesh_name,
                "scenario_key": stamp(sc)["key"],
                "modes": modes,
                "selections": [f"{i}-{j}" for i, j in selections],
                "hertz_radius_m": a_m,
            },
        ),
    }
    full = {}
    for name, f in loads.items():
        full[name] = float(f @ full_response(fe, ref, f))
    out["rows"].append(
        {
            "basis": "full",
            "selection": "-",
            "nq": int(ref.free_dofs(fe.n_dof).size),
            **{f"{k}_compliance_m_per_N": v for k, v in full.items()},
            **{f"{k}_local_m_per_N": v - rod_1d for k, v in full.items()},
            **{f"{k}_stiffness_vs_full": 1.0 for k in full},
        }
    )
    for i, j in selections:
        nodes = rod.selection(i, j)
        for kind in KINDS:
            t0 = time.perf_counter()
            basis = build_basis(fe, kind, ref, retained_nodes=nodes, n_modes=modes)
            row = {"basis": kind.value, "selection": f"{i}-{j}", "nq": basis.nq}
            for name, f in loads.items():
                c = float(f @ reduced_response(fe, basis, f))
                row[f"{name}_compliance_m_per_N"] = c
                row[f"{name}_local_m_per_N"] = c - rod_1d
                row[f"{name}_stiffness_vs_full"] = full[name] / c
            row["build_s"] = time.perf_counter() - t0
            out["rows"].append(row)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", choices=["seed", "default", "both"], default="both")
    ap.add_argument("--modes", type=int, default=37)
    ap.add_argument("--selections", default="1-1,1-3")
    ap.add_argument("--hertz-radius", type=float, default=0.461e-3, help="patch radius a [m]")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    sels = [tuple(int(x) for x in s.split("-")) for s in args.selections.split(",")]
    names = ["seed", "default"] if args.mesh == "both" else [args.mesh]
    results = []
    for name in names:
        r = study(name, sels, args.modes, args.hertz_radius)
        results.append(r)
        print(
            f"b2 on the {name} mesh: {r['n_nodes']} nodes, {r['n_dof']} DOF; {args.modes} modes; "
            f"L/(EA) = {r['rod_1d_compliance_m_per_N']:.4e} m/N; Hertz patch a = "
            f"{1e3 * args.hertz_radius:.3f} mm (integrated load {r['hertz_load_integrated_N']:.4f} N)"
        )
        print(
            f"  {'basis':16s} {'sel':4s} {'nq':>6s} | point: {'C [m/N]':>11s} {'local':>11s} "
            f"{'k/k_full':>8s} | Hertz: {'C [m/N]':>11s} {'local':>11s} {'k/k_full':>8s}"
        )
        for row in r["rows"]:
            cells = "".join(
                f" | {'point' if k == 'point' else 'Hertz'}: "
                f"{row[k + '_compliance_m_per_N']:11.4e} {row[k + '_local_m_per_N']:11.4e} "
                f"{row[k + '_stiffness_vs_full']:8.3f}"
                for k in ("point", "hertz")
            )
            print(f"  {row['basis']:16s} {row['selection']:4s} {row['nq']:6d}{cells}")
    if args.json is not None:
        args.json.write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
