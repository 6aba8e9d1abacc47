"""A gmsh session for one part: start gmsh, build the geometry and its physical groups, mesh
(with an optional local Refinement), write MSH 4.1, stop; and the small geometry queries the
parts share (faces by centre and box, physical groups, tolerant comparison). Used by
mesh/parts.py and mesh/link.py. gmsh is imported when a part is meshed; without it an
InputError says so in one line."""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from flexmvm.errors import InputError, MeshError


@dataclass(frozen=True)
class Refinement:
    """Local refinement: element size fine_m [m] within radius_m [m] of point_m (body frame),
    growing linearly to the part's size_m over a further grow_m [m]."""

    point_m: tuple[float, float, float]
    fine_m: float
    radius_m: float
    grow_m: float


@dataclass(frozen=True)
class DistanceRefinement:
    """Local refinement about a shape: element size fine_m [m] where ``distance`` (a gmsh
    MathEval expression of x, y, z [m], the distance to the shape: a circle, a segment) is
    below radius_m [m], growing linearly to the part's size_m over a further grow_m [m]
    (mesh/cam.py: the cam's rim, the strip the contact travels over on its follower)."""

    distance: str
    fine_m: float
    radius_m: float
    grow_m: float


def _size_field(gmsh, size_m: float, refine: Refinement | DistanceRefinement) -> None:
    """The background size field of ``refine`` (a gmsh Threshold on the distance to its point
    or shape), the other size sources off."""
    check_positive(fine_m=refine.fine_m, radius_m=refine.radius_m, grow_m=refine.grow_m)
    if isinstance(refine, DistanceRefinement):
        distance = refine.distance
    else:
        x, y, z = refine.point_m
        distance = f"Sqrt((x-({x!r}))^2+(y-({y!r}))^2+(z-({z!r}))^2)"
    field = gmsh.model.mesh.field
    dist = field.add("MathEval")
    field.setString(dist, "F", distance)
    th = field.add("Threshold")
    field.setNumber(th, "InField", dist)
    field.setNumber(th, "SizeMin", refine.fine_m)
    field.setNumber(th, "SizeMax", size_m)
    field.setNumber(th, "DistMin", refine.radius_m)
    field.setNumber(th, "DistMax", refine.radius_m + refine.grow_m)
    field.setAsBackgroundMesh(th)
    for key in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
        gmsh.option.setNumber(f"Mesh.{key}", 0)


def _gmsh():
    """The gmsh module, or a one-line InputError if the optional dependency is missing."""
    try:
        import gmsh
    except ImportError:
        raise InputError(
            "meshing a part needs the optional dependency gmsh, which is not "
            "installed; expected `pip install gmsh` (or flexmvm[gmsh])"
        ) from None
    return gmsh


def check_positive(**values: float) -> None:
    for name, value in values.items():
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise InputError(f"part: {name} must be a finite number > 0, got {value!r}")


def _mesh_and_write(
    gmsh, path: Path, size_m: float, order: int, refine: Refinement | DistanceRefinement | None
) -> Path:
    """Size field, 3D mesh of the given order, MSH 4.1 (ASCII) written to ``path``."""
    if order not in (1, 2):
        raise InputError(f"part: order must be 1 (tet4) or 2 (tet10), got {order!r}")
    gmsh.option.setNumber("Mesh.MeshSizeMax", size_m)
    gmsh.option.setNumber("Mesh.MeshSizeMin", size_m if refine is None else refine.fine_m)
    if refine is not None:
        _size_field(gmsh, size_m, refine)
    gmsh.option.setNumber("Mesh.ElementOrder", order)
    gmsh.option.setNumber("Mesh.SecondOrderLinear", 0)
    gmsh.option.setNumber("Mesh.Optimize", 1)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.model.mesh.generate(3)
    path.parent.mkdir(parents=True, exist_ok=True)
    gmsh.write(str(path))
    return path


def run_gmsh(
    path: str | os.PathLike,
    size_m: float,
    order: int,
    refine: Refinement | DistanceRefinement | None,
    build: Callable,
) -> Path:
    """Start gmsh, build the geometry and its physical groups (``build(gmsh)``), mesh, write,
    stop gmsh. A gmsh failure becomes a one-line MeshError."""
    gmsh = _gmsh()
    check_positive(size_m=size_m)
    path = Path(path)
    started = not gmsh.isInitialized()
    if started:
        gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(path.stem)
        build(gmsh)
        return _mesh_and_write(gmsh, path, size_m, order, refine)
    except Exception as exc:
        if isinstance(exc, InputError):
            raise
        detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise MeshError(f"gmsh failed meshing {str(path)!r}: {detail}") from None
    finally:
        gmsh.model.remove()
        if started:
            gmsh.finalize()


def faces_where(gmsh, test: Callable[[tuple[float, ...], tuple[float, ...]], bool]) -> list[int]:
    """Surface tags whose (centre of mass, bounding box) satisfy ``test``."""
    out = []
    for dim, tag in gmsh.model.getEntities(2):
        com = gmsh.model.occ.getCenterOfMass(dim, tag)
        box = gmsh.model.getBoundingBox(dim, tag)
        if test(com, box):
            out.append(tag)
    return out


def physical_group(gmsh, dim: int, tags: list[int], name: str) -> None:
    if not tags:
        raise MeshError(f"part: physical group {name!r} found no entity (geometry changed?)")
    gmsh.model.addPhysicalGroup(dim, tags, name=name)


def close_to(a: float, b: float, scale: float) -> bool:
    """a == b up to 1e-4 of the part's size (OCC pads bounding boxes by its tolerance)."""
    return abs(a - b) <= 1e-4 * scale
