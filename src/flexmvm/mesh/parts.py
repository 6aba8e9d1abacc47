"""The parts of the shipped scenarios, meshed with gmsh from the shapes of mesh/part_shapes.py
(sphere, block, beam, arm: re-exported here), and the command that regenerates them.

``python -m flexmvm.mesh.parts [DIR]`` regenerates the meshes of the shipped scenarios
(``scenarios/meshes/`` by default; see SCENARIO_MESHES, mesh.link's SLIDER_CRANK_MESHES and
mesh.plate_part's PLATE_MESHES).
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from pathlib import Path

from flexmvm.errors import InputError
from flexmvm.mesh.gmsh_session import Refinement, check_positive
from flexmvm.mesh.link import SLIDER_CRANK_MESHES
from flexmvm.mesh.part_shapes import arm, beam, block, sphere
from flexmvm.mesh.plate_part import PLATE_MESHES

#: Element size [m] at the contact point of the sphere_block meshes (hertz_block_part): the
#: coarse form (scenarios/meshes/, the default tests) and the finer one of the validation.
HERTZ_BLOCK_COARSE_M = 0.3e-3
HERTZ_BLOCK_FINE_M = 0.2e-3


def hertz_block_part(path: str | os.PathLike, fine_m: float = HERTZ_BLOCK_COARSE_M) -> Path:
    """The aluminium block of scenarios/sphere_block.toml, 60 x 60 x 30 mm (``block``), in
    tet10: fine_m [m] within 1 mm of the top face's centre, growing to 8 mm over 10 mm.

    Sized by the Hertz contact radius of the steel sphere's impact, a = 0.39 mm: the contact
    is carried by the block's face nodes (it is the slave side), corner and mid-side, whose
    spacing is fine_m / 2; a static indentation measured F / F_Hertz = 1.036 at fine_m = 0.3 mm
    (a / h = 2.6 with h the node spacing) and 1.022 at 0.2 mm (tests/test_quadratic_contact.py,
    docs/notes/2026-11-27-hertz-block.md). 8 mm elsewhere: the block's rigid recoil and its
    global compliance (~0.5 % of the approach) need no more."""
    check_positive(fine_m=fine_m)
    return block(
        path,
        0.060,
        0.060,
        0.030,
        8.0e-3,
        order=2,
        refine=Refinement((0.0, 0.0, 0.0), fine_m, 1.0e-3, 10.0e-3),
    )


def hertz_sphere_part(path: str | os.PathLike) -> Path:
    """The rigid sphere of scenarios/sphere_block.toml, R 10 mm (``sphere``), tet4: 0.1 mm
    within 0.6 mm of its -z pole, growing to 2.5 mm over 6 mm. It is the master surface: its
    facets stand for the sphere where the block's nodes touch it, so they must follow its
    curvature on the scale of the contact radius (0.39 mm): a chord of 0.1 mm lies 0.13 um
    inside the sphere (s^2 / 8 R), 1 % of the approach; with 0.4 mm facets (sphere_r10.msh)
    the contact lasted 5 % longer than Hertz's."""
    return sphere(
        path, 0.010, 0.0025, refine=Refinement((0.0, 0.0, -0.010), 0.1e-3, 0.6e-3, 6.0e-3)
    )


def hertz_beam_part(path: str | os.PathLike, fine_m: float = 0.2e-3) -> Path:
    """The aluminium beam of scenarios/sphere_beam.toml, 200 x 10 x 10 mm (``beam``), in
    tet10: fine_m [m] within 0.6 mm of the top face's mid-span point, growing to 5 mm over
    6 mm.

    Sized by the contact, as hertz_block_part: the steel sphere's Hertz contact radius on the
    free beam is a = (3 F R / 4 E*)^(1/3) = 0.28-0.30 mm at its first peak (250-300 N; Johnson
    eq. 4.22), and the beam's face nodes (the slave side, corner and mid-side, spaced fine_m /
    2) need a / spacing >= 2.5 for Hertz's law (docs/notes/2026-11-27-hertz-block.md): 2.8 at
    0.2 mm. 5 mm elsewhere, two quadratic tetrahedra through the 10 mm depth: the first three
    free-free bending frequencies in the impact plane within 0.03, 0.08, 0.21 % of the
    Timoshenko beam's (tet4 at 2 mm: +6.4 to +6.9 %, locking)."""
    check_positive(fine_m=fine_m)
    return beam(
        path,
        0.200,
        0.010,
        0.010,
        5.0e-3,
        order=2,
        refine=Refinement((0.100, 0.0, 0.0), fine_m, 0.6e-3, 6.0e-3),
    )


def arm_stop_part(
    path: str | os.PathLike, size_m: float = 4.0e-3, fine_m: float = 1.0e-3, order: int = 2
) -> Path:
    """The aluminium arm of scenarios/arm_stop.toml (``arm``): 300 x 20 x 10 mm on a hub of
    radius 15 mm with a pivot hole of radius 5 mm, tet10 (order 2); fine_m [m] within 3 mm of
    the point of its +y side face where the stop strikes, (0.270, 0.010, 0.005), growing to
    size_m over 12 mm. The stop's Hertz contact radius at the impact (a steel sphere R 10 mm,
    ~700 N on aluminium) is ~0.6 mm, a few node spacings (fine_m / 2) of a tet10 face. The
    tests use the same part at a coarse size in tet4."""
    return arm(
        path,
        0.300,
        0.020,
        0.010,
        0.015,
        0.005,
        size_m,
        order=order,
        refine=Refinement((0.270, 0.010, 0.005), fine_m, 3.0e-3, 12.0e-3),
    )


#: The meshes of the shipped scenarios (scenarios/sphere_block.toml, sphere_beam.toml,
#: arm_stop.toml): file name and how it is made. The sphere and beam scenarios strike with the
#: rigid sphere of hertz_sphere_part (0.1 mm facets at the cap: the master surface); the block
#: (hertz_block_part, tet10, 11,748 DOF) and the beam (hertz_beam_part, tet10) are the slave
#: sides, fine enough at the contact for Hertz's law; the arm: arm_stop_part, struck by the
#: stop sphere_r10 (tet4, 0.4 mm at its -z pole, whose nodes are the slave side).
SCENARIO_MESHES: tuple[tuple[str, Callable[[Path], Path]], ...] = (
    (
        "sphere_r10.msh",
        lambda p: sphere(
            p, 0.010, 0.0025, refine=Refinement((0.0, 0.0, -0.010), 0.4e-3, 0.8e-3, 6.0e-3)
        ),
    ),
    ("sphere_r10_cap.msh", hertz_sphere_part),
    ("block_60x60x30.msh", hertz_block_part),
    ("beam_200x10x10.msh", hertz_beam_part),
    ("arm_300x20x10.msh", arm_stop_part),
)


def write_scenario_meshes(directory: str | os.PathLike) -> list[Path]:
    """Mesh every part of SCENARIO_MESHES and mesh.link's into ``directory``; returns the paths
    written."""
    made = SCENARIO_MESHES + SLIDER_CRANK_MESHES + PLATE_MESHES
    return [make(Path(directory) / n) for n, make in made]


def main(argv: list[str] | None = None) -> int:
    """``python -m flexmvm.mesh.parts [DIR]``: regenerate the scenario meshes (default
    scenarios/meshes); prints one line per file, or one error line and returns 2."""
    args = sys.argv[1:] if argv is None else argv
    directory = Path(args[0]) if args else Path("scenarios") / "meshes"
    try:
        for path in write_scenario_meshes(directory):
            print(f"wrote {path} ({path.stat().st_size / 1e6:.2f} MB)")
    except InputError as exc:
        print(f"flexmvm.mesh.parts: error: {exc}", file=sys.stderr)
        return 2
    return 0


__all__ = [
    "HERTZ_BLOCK_COARSE_M",
    "HERTZ_BLOCK_FINE_M",
    "SCENARIO_MESHES",
    "Refinement",
    "arm",
    "arm_stop_part",
    "beam",
    "block",
    "hertz_beam_part",
    "hertz_block_part",
    "hertz_sphere_part",
    "main",
    "sphere",
    "write_scenario_meshes",
]


if __name__ == "__main__":
    sys.exit(main())
