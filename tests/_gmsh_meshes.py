"""Small gmsh meshes for tests (tet4 or tet10, physical groups by name), written to a folder:
a sphere, a box (beam or block) refined toward one point of its top face. Kept beside
flexmvm.mesh.parts for tests/test_sphere_beam.py's case (a box centred on the origin, the
sphere's whole skin as master), whose numbers were measured on these meshes."""

from __future__ import annotations

import contextlib
from pathlib import Path


@contextlib.contextmanager
def _model(name: str, path: Path, order: int):
    """A gmsh session with model ``name``; on leaving, meshed in 3D at ``order`` and written
    to ``path``."""
    import gmsh

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(name)
        yield gmsh
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(order)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


def sphere(path: Path, radius: float, size: float, order: int = 1) -> Path:
    with _model("sphere", path, order) as gmsh:
        v = gmsh.model.occ.addSphere(0, 0, 0, radius)
        gmsh.model.occ.synchronize()
        skin = [s[1] for s in gmsh.model.getBoundary([(3, v)], oriented=False)]
        gmsh.model.addPhysicalGroup(3, [v], name="ball")
        gmsh.model.addPhysicalGroup(2, skin, name="skin")
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    return path


def box(
    path: Path, lx: float, ly: float, lz: float, fine: float, coarse: float, order: int = 1
) -> Path:
    """A box centred on the origin, physical surfaces top (z = lz/2) and ends (x = +-lx/2),
    refined to `fine` within 2 `fine` of the top face's centre."""
    with _model("box", path, order) as gmsh:
        v = gmsh.model.occ.addBox(-lx / 2, -ly / 2, -lz / 2, lx, ly, lz)
        gmsh.model.occ.synchronize()
        faces = [s[1] for s in gmsh.model.getBoundary([(3, v)], oriented=False)]
        com = {f: gmsh.model.occ.getCenterOfMass(2, f) for f in faces}
        gmsh.model.addPhysicalGroup(3, [v], name="solid")
        gmsh.model.addPhysicalGroup(
            2, [f for f in faces if abs(com[f][2] - lz / 2) < 1e-12], name="top"
        )
        gmsh.model.addPhysicalGroup(
            2, [f for f in faces if abs(abs(com[f][0]) - lx / 2) < 1e-12], name="ends"
        )
        p = gmsh.model.occ.addPoint(0, 0, lz / 2)
        gmsh.model.occ.synchronize()
        dist = gmsh.model.mesh.field.add("Distance")
        gmsh.model.mesh.field.setNumbers(dist, "PointsList", [p])
        th = gmsh.model.mesh.field.add("Threshold")
        gmsh.model.mesh.field.setNumber(th, "InField", dist)
        gmsh.model.mesh.field.setNumber(th, "SizeMin", fine)
        gmsh.model.mesh.field.setNumber(th, "SizeMax", coarse)
        gmsh.model.mesh.field.setNumber(th, "DistMin", 2 * fine)
        gmsh.model.mesh.field.setNumber(th, "DistMax", 8 * fine)
        gmsh.model.mesh.field.setAsBackgroundMesh(th)
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    return path
