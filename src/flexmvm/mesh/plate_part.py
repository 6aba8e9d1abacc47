"""The big part of scenarios/plate_impact.toml: a 100 x 100 x 4 mm plate, tet10, fine where
the ball strikes and coarse elsewhere, of > 200,000 DOF (issue 49: a reduced body must pay on
a part of that size). Units: metres; the part's frame is ``parts.block``'s (top face at z = 0,
centred at the origin; groups top, bottom, side, block)."""

from __future__ import annotations

import os
from pathlib import Path

from flexmvm.mesh.gmsh_session import Refinement
from flexmvm.mesh.part_shapes import block, sphere

#: Plate size [m]: 100 x 100 x 4 mm (lx, ly, lz).
PLATE_SIZE_M = (0.100, 0.100, 0.004)
#: Element size within 1 mm of the top face's centre [m]: the Hertz contact radius of the
#: R 5 mm steel ball at 1 m/s on it (~0.25 mm at ~230 N) spans a few node spacings (0.1 mm on
#: a tet10 face), growing to PLATE_FAR_M over 10 mm.
PLATE_FINE_M = 0.2e-3
#: Element size away from the contact [m]: 1.7 mm gives 273,789 DOF (91,263 nodes; 263,685
#: free of the clamp on the sides).
PLATE_FAR_M = 1.7e-3


def plate_part(
    path: str | os.PathLike, far_m: float = PLATE_FAR_M, fine_m: float = PLATE_FINE_M
) -> Path:
    """Write the plate (module doc) to ``path``: tet10, ``fine_m`` within 1 mm of the top
    face's centre growing to ``far_m`` at 11 mm (gmsh Threshold); returns the path. The
    defaults make the shipped plate_100x100x4.msh (~10 MB)."""
    lx, ly, lz = PLATE_SIZE_M
    refine = Refinement((0.0, 0.0, 0.0), fine_m, 1.0e-3, 10.0e-3)
    return block(path, lx, ly, lz, far_m, order=2, refine=refine)


def ball_part(path: str | os.PathLike) -> Path:
    """The ball that strikes the plate: a sphere R 5 mm (parts.sphere, tet4, 1.5 mm), its
    facets 0.1 mm within 0.5 mm of the -z pole that strikes (its front cap: the master
    surface), growing over 3 mm."""
    refine = Refinement((0.0, 0.0, -0.005), 0.1e-3, 0.5e-3, 3.0e-3)
    return sphere(path, 0.005, 1.5e-3, refine=refine)


#: The shipped meshes of scenarios/plate_impact.toml (parts.write_scenario_meshes): file
#: name and how it is made.
PLATE_MESHES = (("plate_100x100x4.msh", plate_part), ("sphere_r5.msh", ball_part))

__all__ = ["PLATE_FAR_M", "PLATE_FINE_M", "PLATE_MESHES", "PLATE_SIZE_M", "ball_part", "plate_part"]
