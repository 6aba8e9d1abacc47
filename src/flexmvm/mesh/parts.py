"""Parts meshed with gmsh: sphere, block, beam, arm with a pivot hub, as MSH 4.1 files.

Every part is a tetrahedral mesh (tet4, or tet10 with ``order = 2``) with physical groups
named after its natural faces, which read_mesh turns into facet and node sets (and the skin
``surface``, always added by read_mesh). The element size is ``size_m`` everywhere, or, with a
``Refinement``, ``fine_m`` within ``radius_m`` of a point, growing linearly to ``size_m`` at
``radius_m + grow_m`` (a gmsh Threshold field on the distance to the point): the contact zone
fine, the rest coarse, so that a full-FE body stays small. Units: metres. Coordinates are the
part's own (body) frame, stated per part. gmsh is an optional dependency, imported when a part
is meshed; without it an InputError says so in one line.

``python -m flexmvm.mesh.parts [DIR]`` regenerates the meshes of the shipped scenarios
(``scenarios/meshes/`` by default; see SCENARIO_MESHES).
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable
from pathlib import Path

from flexmvm.errors import InputError
from flexmvm.mesh.gmsh_session import (
    Refinement,
    check_positive,
    close_to,
    faces_where,
    physical_group,
    run_gmsh,
)


def sphere(
    path: str | os.PathLike,
    radius_m: float,
    size_m: float,
    *,
    order: int = 1,
    refine: Refinement | None = None,
    cap_deg: float = 30.0,
) -> Path:
    """Sphere of radius_m centred at the origin. Groups: ``front``, the spherical cap within
    cap_deg of the -z pole (where it strikes when moving along -z), ``back``, the rest of the
    sphere's surface, volume ``sphere``. Returns the path written."""
    check_positive(radius_m=radius_m)
    if not 0.0 < cap_deg < 90.0:
        raise InputError(f"sphere: cap_deg must be in (0, 90) degrees, got {cap_deg!r}")
    r, z_cap = radius_m, -radius_m * math.cos(math.radians(cap_deg))

    def build(gmsh) -> None:
        occ = gmsh.model.occ
        ball = occ.addSphere(0.0, 0.0, 0.0, r)
        slab = occ.addBox(-r, -r, -r, 2 * r, 2 * r, z_cap + r)
        cap, _ = occ.intersect([(3, ball)], [(3, slab)], removeObject=False, removeTool=True)
        occ.fragment([(3, ball)], cap)
        occ.synchronize()
        curved = [t for _, t in gmsh.model.getEntities(2) if gmsh.model.getType(2, t) != "Plane"]
        front = [t for t in curved if gmsh.model.occ.getCenterOfMass(2, t)[2] < z_cap]
        physical_group(gmsh, 2, front, "front")
        physical_group(gmsh, 2, [t for t in curved if t not in front], "back")
        physical_group(gmsh, 3, [t for _, t in gmsh.model.getEntities(3)], "sphere")

    return run_gmsh(path, size_m, order, refine, build)


def block(
    path: str | os.PathLike,
    lx_m: float,
    ly_m: float,
    lz_m: float,
    size_m: float,
    *,
    order: int = 1,
    refine: Refinement | None = None,
) -> Path:
    """Block x in [-lx/2, lx/2], y in [-ly/2, ly/2], z in [-lz, 0] (top face centre at the
    origin). Groups: ``top`` (z = 0), ``bottom`` (z = -lz), ``side`` (the four lateral faces),
    volume ``block``. Returns the path written."""
    check_positive(lx_m=lx_m, ly_m=ly_m, lz_m=lz_m)
    scale = max(lx_m, ly_m, lz_m)

    def build(gmsh) -> None:
        vol = gmsh.model.occ.addBox(-lx_m / 2, -ly_m / 2, -lz_m, lx_m, ly_m, lz_m)
        gmsh.model.occ.synchronize()
        top = faces_where(gmsh, lambda com, box: close_to(com[2], 0.0, scale))
        bottom = faces_where(gmsh, lambda com, box: close_to(com[2], -lz_m, scale))
        physical_group(gmsh, 2, top, "top")
        physical_group(gmsh, 2, bottom, "bottom")
        physical_group(
            gmsh,
            2,
            faces_where(
                gmsh,
                lambda com, box: (
                    not (close_to(com[2], 0.0, scale) or close_to(com[2], -lz_m, scale))
                ),
            ),
            "side",
        )
        physical_group(gmsh, 3, [vol], "block")

    return run_gmsh(path, size_m, order, refine, build)


def beam(
    path: str | os.PathLike,
    length_m: float,
    width_m: float,
    height_m: float,
    size_m: float,
    *,
    patch_m: float | None = None,
    order: int = 1,
    refine: Refinement | None = None,
) -> Path:
    """Beam x in [0, length], y in [-width/2, width/2], z in [-height, 0] (top face at z = 0).
    Groups: ``top``, ``bottom``, ``side`` (y = +-width/2), ``end_a`` (x = 0), ``end_b``
    (x = length), ``mid_top`` (the top face within patch_m/2 of mid-length, default patch_m =
    width: a patch of ``top``, in both groups), volume ``beam``. Returns the path written."""
    check_positive(length_m=length_m, width_m=width_m, height_m=height_m)
    patch = width_m if patch_m is None else patch_m
    check_positive(patch_m=patch)
    if patch >= length_m:
        raise InputError(f"beam: patch_m must be < length_m = {length_m!r} m, got {patch!r}")
    x0, x1, scale = (length_m - patch) / 2, (length_m + patch) / 2, length_m

    def build(gmsh) -> None:
        occ = gmsh.model.occ
        parts = [
            occ.addBox(a, -width_m / 2, -height_m, b - a, width_m, height_m)
            for a, b in ((0.0, x0), (x0, x1), (x1, length_m))
        ]
        occ.fragment([(3, parts[0])], [(3, p) for p in parts[1:]])
        occ.synchronize()
        top = faces_where(
            gmsh, lambda com, box: close_to(box[2], 0.0, scale) and close_to(box[5], 0.0, scale)
        )
        physical_group(gmsh, 2, top, "top")
        physical_group(
            gmsh,
            2,
            [t for t in top if x0 < gmsh.model.occ.getCenterOfMass(2, t)[0] < x1],
            "mid_top",
        )
        physical_group(
            gmsh,
            2,
            faces_where(
                gmsh,
                lambda com, box: (
                    close_to(box[2], -height_m, scale) and close_to(box[5], -height_m, scale)
                ),
            ),
            "bottom",
        )
        physical_group(
            gmsh,
            2,
            faces_where(gmsh, lambda com, box: close_to(abs(com[1]), width_m / 2, scale)),
            "side",
        )
        physical_group(
            gmsh, 2, faces_where(gmsh, lambda com, box: close_to(box[3], 0.0, scale)), "end_a"
        )
        physical_group(
            gmsh, 2, faces_where(gmsh, lambda com, box: close_to(box[0], length_m, scale)), "end_b"
        )
        physical_group(gmsh, 3, [t for _, t in gmsh.model.getEntities(3)], "beam")

    return run_gmsh(path, size_m, order, refine, build)


def _check_arm(length_m, width_m, thickness_m, hub_radius_m, hole_radius_m, leg_m) -> None:
    """One-line InputErrors for an arm's dimensions (arm)."""
    check_positive(
        length_m=length_m,
        width_m=width_m,
        thickness_m=thickness_m,
        hub_radius_m=hub_radius_m,
        hole_radius_m=hole_radius_m,
    )
    if not hole_radius_m < hub_radius_m < length_m or width_m / 2 <= hole_radius_m:
        raise InputError(
            f"arm: expected hole_radius_m < hub_radius_m < length_m and "
            f"hole_radius_m < width_m / 2, got {hole_radius_m!r}, {hub_radius_m!r}, "
            f"{length_m!r}, {width_m!r}"
        )
    if leg_m < 0:
        raise InputError(f"arm: leg_m must be >= 0 m, got {leg_m!r}")


def arm(
    path: str | os.PathLike,
    length_m: float,
    width_m: float,
    thickness_m: float,
    hub_radius_m: float,
    hole_radius_m: float,
    size_m: float,
    *,
    leg_m: float = 0.0,
    order: int = 1,
    refine: Refinement | None = None,
) -> Path:
    """Arm with a pivot hub: a plate of thickness_m (z in [0, thickness]) made of a hub disk
    of hub_radius_m about the origin with a hole of hole_radius_m (the pivot), a bar x in
    [0, length], y in [-width/2, width/2], and with leg_m > 0 a leg at the bar's end, x in
    [length - width, length], y from width/2 down to -width/2 - leg (an L). Groups: ``hub``
    (the hole's cylindrical face: where a revolute joint acts), ``tip`` (the free end face:
    x = length for a straight arm, y = -width/2 - leg for an L), ``top`` (z = thickness),
    ``bottom`` (z = 0), volume ``arm``. Returns the path written."""
    _check_arm(length_m, width_m, thickness_m, hub_radius_m, hole_radius_m, leg_m)
    scale = length_m + leg_m
    tip_y = -width_m / 2 - leg_m

    def build(gmsh) -> None:
        occ = gmsh.model.occ
        shapes = [
            (2, occ.addDisk(0.0, 0.0, 0.0, hub_radius_m, hub_radius_m)),
            (2, occ.addRectangle(0.0, -width_m / 2, 0.0, length_m, width_m)),
        ]
        if leg_m > 0:
            shapes.append(
                (2, occ.addRectangle(length_m - width_m, tip_y, 0.0, width_m, width_m + leg_m))
            )
        plate, _ = occ.fuse(shapes[:1], shapes[1:])
        hole = occ.addDisk(0.0, 0.0, 0.0, hole_radius_m, hole_radius_m)
        plate, _ = occ.cut(plate, [(2, hole)])
        occ.extrude(plate, 0.0, 0.0, thickness_m)
        occ.synchronize()
        rim = hole_radius_m + 1e-4 * scale
        physical_group(
            gmsh,
            2,
            faces_where(gmsh, lambda com, box: max(map(abs, box[:2] + box[3:5])) <= rim),
            "hub",
        )
        if leg_m > 0:
            tip = faces_where(gmsh, lambda com, box: close_to(box[4], tip_y, scale))
        else:
            tip = faces_where(gmsh, lambda com, box: close_to(box[0], length_m, scale))
        physical_group(gmsh, 2, tip, "tip")
        physical_group(
            gmsh,
            2,
            faces_where(
                gmsh,
                lambda com, box: (
                    close_to(box[2], thickness_m, scale) and close_to(box[5], thickness_m, scale)
                ),
            ),
            "top",
        )
        physical_group(
            gmsh, 2, faces_where(gmsh, lambda com, box: close_to(box[5], 0.0, scale)), "bottom"
        )
        physical_group(gmsh, 3, [t for _, t in gmsh.model.getEntities(3)], "arm")

    return run_gmsh(path, size_m, order, refine, build)


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
    from flexmvm.mesh.link import SLIDER_CRANK_MESHES  # link imports this module
    from flexmvm.mesh.plate_part import PLATE_MESHES  # plate_part imports this module too

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
