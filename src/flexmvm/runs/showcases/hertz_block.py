"""Sphere on block against Hertz: scenarios/sphere_block.toml as a check of contact on a
user's mesh (issue "Your own geometry", part 2).

A rigid steel sphere (R 10 mm, 0.5 m/s) strikes a free aluminium block 60 x 60 x 30 mm. The
quasi-static Hertz impact (Johnson, *Contact Mechanics*, 1985, eq. 11.24; theory.hertz)
with the block's recoil (1/m* = 1/m_sphere + 1/m_block) gives the peak force and the contact
duration: 615 N and 86.7 us for the sphere as meshed (32.2 g). Why the free block stands for
Hertz's half-space: the contact lasts ~9 P-wave round trips through its 30 mm (the waves settle
into a quasi-static field), its lowest elastic modes lie well above the contact's frequency,
and its global compliance beyond the Hertz zone, ~F / (pi E* 30 mm), is 0.5 % of the approach.
What sets the accuracy is the contact's discretization: the block (tet10) is the slave side,
its face nodes (corner and mid-side, 2.6 per contact radius on the coarse mesh) carry the
force, the sphere's 0.1 mm facets are the master surface (mesh/parts.py: hertz_block_part,
hertz_sphere_part). docs/notes/2026-11-27-hertz-block.md has the measurements.

:func:`hertz_block_check` runs the case at a given element size at the contact (the block's
mesh made with gmsh at run time) and returns the comparison; the default tests run the
committed coarse form (tests/test_sphere_block_hertz.py), the validation the finer one.
"""

from __future__ import annotations

import math
import tempfile
import tomllib
from pathlib import Path

import numpy as np

from flexmvm.errors import InputError
from flexmvm.mesh.io import read_mesh
from flexmvm.mesh.parts import HERTZ_BLOCK_FINE_M, hertz_block_part
from flexmvm.mesh.quality import mesh_volume
from flexmvm.scenarios.load import scenario_from_dict
from flexmvm.scenarios.schema import Scenario
from flexmvm.theory.hertz import HertzImpact, effective_modulus, hertz_impact

#: The shipped scenario (coarse form: its committed meshes).
SPHERE_BLOCK = Path(__file__).resolve().parents[4] / "scenarios" / "sphere_block.toml"
#: The end of the check's run [s]: the contact (~87 us) and a margin to see it open.
T_END_S = 110e-6


def hertz_reference(sc: Scenario, sphere: str = "ball", target: str = "block") -> HertzImpact:
    """Hertz impact of body ``sphere`` (its radius: its mesh nodes' largest distance from the
    mesh origin [m]) on body ``target`` at their initial relative speed, with the masses of the
    meshes as given (volume x density: a faceted sphere holds less than 4/3 pi R^3) and E* of
    both bodies (the target's alone if the sphere is rigid). InputError for an unknown body."""
    names = [b.name for b in sc.bodies]
    for name in (sphere, target):
        if name not in names:
            raise InputError(f"hertz_reference: no body {name!r}; expected one of {names}")
    ball, block = sc.body(sphere), sc.body(target)
    if ball.mesh_file is None or block.mesh_file is None:
        raise InputError(f"hertz_reference: bodies {sphere!r} and {target!r} need a mesh_file")
    ball_mesh, block_mesh = read_mesh(ball.mesh_file), read_mesh(block.mesh_file)
    mat_ball, mat_block = ball.material_obj(), block.material_obj()
    if not ball.model.kind.spec.has_basis:
        e_star = mat_block.E / (1.0 - mat_block.nu**2)
    else:
        e_star = effective_modulus(mat_ball.E, mat_ball.nu, mat_block.E, mat_block.nu)
    radius = float(np.linalg.norm(ball_mesh.nodes, axis=1).max())
    speed = float(
        np.linalg.norm(np.subtract(ball.placement.velocity_mps, block.placement.velocity_mps))
    )
    return hertz_impact(
        radius,
        speed,
        e_star,
        mat_ball.rho * mesh_volume(ball_mesh),
        mat_block.rho * mesh_volume(block_mesh),
    )


def hertz_comparison(
    hz: HertzImpact, force_N: np.ndarray, summary: dict, target: str = "block"
) -> dict:
    """A run's first contact against the Hertz impact ``hz``: peak_N (of the contact force
    history force_N), duration_s (of the summary's first contact interval, from the steps with
    contact: to one step), the Hertz values hertz_peak_N and hertz_duration_s, the relative
    errors peak_err and duration_err, the contact radius hertz_contact_radius_m, and of the
    summary the target's dof, energy_rel_change, steps_on_roundoff_floor and status."""
    intervals = summary["contact_intervals_s"]
    duration = intervals[0][1] - intervals[0][0] if intervals else 0.0
    peak = float(np.max(force_N))
    return {
        "peak_N": peak,
        "hertz_peak_N": hz.force_max_n,
        "peak_err": peak / hz.force_max_n - 1.0,
        "duration_s": duration,
        "hertz_duration_s": hz.duration_s,
        "duration_err": duration / hz.duration_s - 1.0,
        "hertz_contact_radius_m": hz.contact_radius_m,
        "dof": summary["dof"][target],
        "energy_rel_change": summary["energy_rel_change"],
        "steps_on_roundoff_floor": summary["steps_on_roundoff_floor"],
        "status": summary["status"],
    }


def compare_with_hertz(sc: Scenario, t_end_s: float = T_END_S) -> dict:
    """Run ``sc`` (fm.run) over t_end_s and compare its first contact with
    :func:`hertz_reference` (:func:`hertz_comparison`'s dict)."""
    from flexmvm.runs.run import run_scenario

    hz = hertz_reference(sc)
    run = run_scenario(sc.with_time(t_end_s=t_end_s), warn=False)
    return hertz_comparison(hz, run.contact_force, run.summary)


def sphere_block_scenario(
    block_mesh: str | Path | None = None, path: str | Path = SPHERE_BLOCK
) -> Scenario:
    """The scenario file ``path`` (default scenarios/sphere_block.toml), with the block's mesh
    replaced by ``block_mesh`` if given (the sphere's committed mesh kept)."""
    path = Path(path)
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    if block_mesh is not None:
        for body in data["bodies"]:
            if body["name"] == "block":
                body["mesh_file"] = str(Path(block_mesh).resolve())
    return scenario_from_dict(data, source=str(path), base_dir=path.parent)


def hertz_block_check(
    fine_m: float = HERTZ_BLOCK_FINE_M, directory: str | Path | None = None
) -> dict:
    """The sphere-on-block Hertz check with the block meshed (gmsh, hertz_block_part) at
    element size fine_m [m] at the contact, in ``directory`` (default: a temporary one):
    :func:`compare_with_hertz`'s dict plus fine_m and node_spacing_m (fine_m / 2: tet10).
    The errors per fine_m: docs/notes/2026-11-27-hertz-block.md. InputError for
    fine_m not in (0, 1 mm]: coarser faces cannot resolve the contact radius of 0.39 mm."""
    if not (isinstance(fine_m, (int, float)) and math.isfinite(fine_m) and 0 < fine_m <= 1e-3):
        raise InputError(f"hertz_block_check: fine_m must be in (0, 1e-3] m, got {fine_m!r}")
    with tempfile.TemporaryDirectory() as tmp:
        where = Path(directory) if directory is not None else Path(tmp)
        path = hertz_block_part(where / f"block_{fine_m * 1e6:.0f}um.msh", fine_m)
        out = compare_with_hertz(sphere_block_scenario(path))
    return {**out, "fine_m": float(fine_m), "node_spacing_m": float(fine_m) / 2.0}


__all__ = [
    "SPHERE_BLOCK",
    "T_END_S",
    "compare_with_hertz",
    "hertz_block_check",
    "hertz_comparison",
    "hertz_reference",
    "sphere_block_scenario",
]
