"""The parts of scenarios/cam_follower.toml (issue 53 item 4): a crowned eccentric cam and the
flat-faced flexible follower it presses, meshed with gmsh (mesh/gmsh_session.py).

The cam: a disc of radius R with a spherical rim (a sphere of radius R cut to a slab of
thickness ``thickness_m``: a crowned cam, so that it touches a flat face at a point), turning
about a bore of radius ``bore_radius_m`` whose axis (along y) lies ``eccentricity_m`` below the
disc's centre. Frame: the disc's centre at the origin, y the turning axis' direction, the bore's
axis through (0, y, -e). Groups: ``rim`` (the spherical face: where it touches), ``bore`` (the
bore's face: where the revolute joint holds it), ``side`` (the two flat faces), volume ``cam``.
tet4 (a rigid body: only its rim's nodes and its inertia are used), fine within a band about
the rim's equator (the circle of radius R at y = 0, which every contact point lies on).

The follower: a bar x in [0, L], y in [-w/2, w/2], z in [-t, 0] (the flat face on top, z = 0;
``parts.beam``'s frame), clamped at x = 0. Its top face has a strip of its own, x in
``path_x_m``, |y| <= ``path_half_width_m``: the node set ``path`` the contact travels over (the
moving region's path, kind ``mvm-moving``), refined to ``fine_m`` within ``fine_m`` of the
strip's centre line and growing to ``size_m``. Groups: ``top`` (z = 0, the strip included),
``path`` (the strip), ``bottom``, ``side`` (y = +-w/2), ``end_a`` (x = 0), ``end_b`` (x = L),
volume ``follower``. tet10.

``python -m flexmvm.mesh.cam [DIR]`` writes the shipped meshes (CAM_MESHES) to DIR
(scenarios/meshes by default).
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from flexmvm.errors import InputError
from flexmvm.mesh.gmsh_session import (
    DistanceRefinement,
    check_positive,
    close_to,
    faces_where,
    physical_group,
    run_gmsh,
)


@dataclass(frozen=True)
class CamShape:
    """The crowned eccentric cam [m] (module doc)."""

    radius_m: float = 0.020
    thickness_m: float = 0.006
    eccentricity_m: float = 0.003
    bore_radius_m: float = 0.002


@dataclass(frozen=True)
class FollowerShape:
    """The follower bar [m] (module doc) and the strip the contact travels over."""

    length_m: float = 0.300
    width_m: float = 0.020
    thickness_m: float = 0.006
    path_x_m: tuple[float, float] = (0.2445, 0.2555)
    path_half_width_m: float = 0.4e-3


#: The shipped shapes: the cam turns about x = 250 mm of the follower, its centre 3 mm off the
#: axis, so the contact travels x in [247, 253] mm (+- the face's tilt under load, < 1 mm).
CAM = CamShape()
FOLLOWER = FollowerShape()


def cam_part(
    path: str | os.PathLike,
    shape: CamShape = CAM,
    size_m: float = 4.0e-3,
    fine_m: float = 0.6e-3,
    order: int = 2,
) -> Path:
    """Write the cam (module doc) to ``path``: tet10 (order 2: its rim's facets quadratic,
    on the sphere to ~h^4 / R^3 instead of the flat facets' h^2 / 8 R), ``fine_m`` within
    0.5 mm of the rim's equator and of the bore's face, growing to ``size_m`` over 6 mm;
    returns the path."""
    r, half, e, rb = (
        shape.radius_m,
        shape.thickness_m / 2,
        shape.eccentricity_m,
        shape.bore_radius_m,
    )
    check_positive(radius_m=r, thickness_m=half, eccentricity_m=e, bore_radius_m=rb)
    if not (e + rb < r and half < r):
        raise InputError(
            f"cam: expected eccentricity + bore radius < radius and thickness < 2 radius, got "
            f"e {e!r}, bore {rb!r}, R {r!r}, thickness {shape.thickness_m!r} m"
        )

    def build(gmsh) -> None:
        occ = gmsh.model.occ
        ball = occ.addSphere(0.0, 0.0, 0.0, r)
        slab = occ.addBox(-r, -half, -r, 2 * r, 2 * half, 2 * r)
        disc, _ = occ.intersect([(3, ball)], [(3, slab)])
        bore = occ.addCylinder(0.0, -2 * half, -e, 0.0, 4 * half, 0.0, rb)
        occ.cut(disc, [(3, bore)])
        occ.synchronize()
        # curved quadratic cells: untangled by gmsh's elastic optimiser (none inverted)
        gmsh.option.setNumber("Mesh.HighOrderOptimize", 2)
        kind = {t: gmsh.model.getType(2, t) for _, t in gmsh.model.getEntities(2)}
        physical_group(gmsh, 2, [t for t, k in kind.items() if k == "Sphere"], "rim")
        physical_group(gmsh, 2, [t for t, k in kind.items() if k == "Cylinder"], "bore")
        physical_group(gmsh, 2, [t for t, k in kind.items() if k == "Plane"], "side")
        physical_group(gmsh, 3, [t for _, t in gmsh.model.getEntities(3)], "cam")

    # the distance to the rim's equator or to the bore's face: the bore fine too, so that its
    # nodes' centroid (where the revolute joint holds the cam) lies on its axis
    rim = f"Sqrt((Sqrt(x^2+z^2)-({r!r}))^2+y^2)"
    bore = f"Abs(Sqrt(x^2+(z+({e!r}))^2)-({rb!r}))"
    return run_gmsh(
        path, size_m, order, DistanceRefinement(f"Min({rim},{bore})", fine_m, 0.5e-3, 6.0e-3), build
    )


def follower_part(
    path: str | os.PathLike,
    shape: FollowerShape = FOLLOWER,
    size_m: float = 4.0e-3,
    fine_m: float = 0.3e-3,
    order: int = 2,
) -> Path:
    """Write the follower (module doc) to ``path``: ``fine_m`` within 1.5 path half widths of
    the path strip's centre line (y = z = 0, x in path_x_m), growing to ``size_m`` over
    ``size_m``; returns the path."""
    length, w, t = shape.length_m, shape.width_m, shape.thickness_m
    (x0, x1), ys = shape.path_x_m, shape.path_half_width_m
    check_positive(length_m=length, width_m=w, thickness_m=t, path_half_width_m=ys)
    if not (0.0 < x0 < x1 < length and ys < w / 2):
        raise InputError(
            f"follower: expected 0 < path_x_m[0] < path_x_m[1] < length and path half width "
            f"< width / 2, got path_x_m {shape.path_x_m!r}, {ys!r} m, length {length!r}, "
            f"width {w!r} m"
        )

    def build(gmsh) -> None:
        occ = gmsh.model.occ
        bar = occ.addBox(0.0, -w / 2, -t, length, w, t)
        strip = occ.addBox(x0, -ys, -t, x1 - x0, 2 * ys, t)
        occ.fragment([(3, bar)], [(3, strip)])
        occ.synchronize()
        _follower_groups(gmsh, shape)

    line = f"Sqrt(Max(Max(({x0!r})-x,x-({x1!r})),0)^2+y^2+z^2)"
    refine = DistanceRefinement(line, fine_m, 1.5 * ys, size_m)
    return run_gmsh(path, size_m, order, refine, build)


def _follower_groups(gmsh, shape: FollowerShape) -> None:
    """The follower's physical groups (module doc)."""
    length, w, t = shape.length_m, shape.width_m, shape.thickness_m
    (x0, x1), ys = shape.path_x_m, shape.path_half_width_m

    def flat(box, axis: int, value: float) -> bool:
        return close_to(box[axis], value, length) and close_to(box[axis + 3], value, length)

    top = faces_where(gmsh, lambda com, box: flat(box, 2, 0.0))
    strip = faces_where(
        gmsh,
        lambda com, box: (
            flat(box, 2, 0.0) and x0 < com[0] < x1 and abs(com[1]) < ys and box[4] - box[1] < 3 * ys
        ),
    )
    physical_group(gmsh, 2, top, "top")
    physical_group(gmsh, 2, strip, "path")
    physical_group(gmsh, 2, faces_where(gmsh, lambda com, box: flat(box, 2, -t)), "bottom")
    side = faces_where(gmsh, lambda com, box: flat(box, 1, -w / 2) or flat(box, 1, w / 2))
    physical_group(gmsh, 2, side, "side")
    physical_group(gmsh, 2, faces_where(gmsh, lambda com, box: flat(box, 0, 0.0)), "end_a")
    physical_group(gmsh, 2, faces_where(gmsh, lambda com, box: flat(box, 0, length)), "end_b")
    physical_group(gmsh, 3, [tag for _, tag in gmsh.model.getEntities(3)], "follower")


#: The shipped meshes of scenarios/cam_follower.toml: file name and how it is made.
CAM_MESHES: tuple[tuple[str, Callable[[Path], Path]], ...] = (
    ("cam_r20_e3.msh", cam_part),
    ("follower_300x20x6.msh", follower_part),
)


def main(argv: list[str] | None = None) -> int:
    """``python -m flexmvm.mesh.cam [DIR]``: write CAM_MESHES to DIR (default
    scenarios/meshes); one line per file, or one error line and status 2."""
    args = sys.argv[1:] if argv is None else argv
    directory = Path(args[0]) if args else Path("scenarios") / "meshes"
    try:
        for name, make in CAM_MESHES:
            written = make(directory / name)
            print(f"wrote {written} ({written.stat().st_size / 1e6:.2f} MB)")
    except InputError as exc:
        print(f"flexmvm.mesh.cam: error: {exc}", file=sys.stderr)
        return 2
    return 0


__all__ = [
    "CAM",
    "CAM_MESHES",
    "FOLLOWER",
    "CamShape",
    "FollowerShape",
    "cam_part",
    "follower_part",
    "main",
]


if __name__ == "__main__":
    sys.exit(main())
