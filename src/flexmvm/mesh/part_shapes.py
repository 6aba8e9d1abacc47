"""The shapes gmsh meshes: sphere, block, beam, arm with a pivot hub, as MSH 4.1 files.

Every part is a tetrahedral mesh (tet4, or tet10 with ``order = 2``) with physical groups
named after its natural faces, which read_mesh turns into facet and node sets (and the skin
``surface``, always added by read_mesh). The element size is ``size_m`` everywhere, or, with a
``Refinement``, ``fine_m`` within ``radius_m`` of a point, growing linearly to ``size_m`` at
``radius_m + grow_m`` (a gmsh Threshold field on the distance to the point): the contact zone
fine, the rest coarse, so that a full-FE body stays small. Units: metres. Coordinates are the
part's own (body) frame, stated per part. gmsh is an optional dependency, imported when a part
is meshed; without it an InputError says so in one line. The parts of the shipped scenarios
are made of these shapes in mesh/parts.py, mesh/link.py and mesh/plate_part.py.
"""

from __future__ import annotations

import math
import os
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


__all__ = ["Refinement", "arm", "beam", "block", "sphere"]
