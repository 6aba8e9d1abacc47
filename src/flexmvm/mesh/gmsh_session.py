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


def _mesh_and_write(gmsh, path: Path, size_m: float, order: int, refine: Refinement | None) -> Path:
    """Size field, 3D mesh of the given order, MSH 4.1 (ASCII) written to ``path``."""
    if order not in (1, 2):
        raise InputError(f"part: order must be 1 (tet4) or 2 (tet10), got {order!r}")
    gmsh.option.setNumber("Mesh.MeshSizeMax", size_m)
    gmsh.option.setNumber("Mesh.MeshSizeMin", size_m if refine is None else refine.fine_m)
    if refine is not None:
        check_positive(fine_m=refine.fine_m, radius_m=refine.radius_m, grow_m=refine.grow_m)
        x, y, z = refine.point_m
        dist = gmsh.model.mesh.field.add("MathEval")
        gmsh.model.mesh.field.setString(
            dist, "F", f"Sqrt((x-({x!r}))^2+(y-({y!r}))^2+(z-({z!r}))^2)"
        )
        th = gmsh.model.mesh.field.add("Threshold")
        gmsh.model.mesh.field.setNumber(th, "InField", dist)
        gmsh.model.mesh.field.setNumber(th, "SizeMin", refine.fine_m)
        gmsh.model.mesh.field.setNumber(th, "SizeMax", size_m)
        gmsh.model.mesh.field.setNumber(th, "DistMin", refine.radius_m)
        gmsh.model.mesh.field.setNumber(th, "DistMax", refine.radius_m + refine.grow_m)
        gmsh.model.mesh.field.setAsBackgroundMesh(th)
        for key in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
            gmsh.option.setNumber(f"Mesh.{key}", 0)
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
    path: str | os.PathLike, size_m: float, order: int, refine: Refinement | None, build: Callable
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
