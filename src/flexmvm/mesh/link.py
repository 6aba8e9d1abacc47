"""The parts of the slider-crank (scenarios/slider_crank.toml), meshed with gmsh as the parts of
mesh/parts.py: a connecting rod (a slender bar pinned at its end faces), the crank (a steel
bar) and the slider (a small steel block). Units: metres, the part's own frame.

The rod is the flexible link of the benchmark of Simeon (1996; the IVP test set's "crank"
problem): steel, 300 x 8 x 8 mm, pins at the end-face centres. Its pins are the centroids of the
end faces' nodes (constraints.joints.NodeSetPoint), so no pin hole is meshed: a hole of a few
mm in an 8 mm bar would need elements of a fraction of a mm for the hole and change the rod's
bending stiffness near its ends, which the beam models of the literature do not have.
"""

from __future__ import annotations

import os
from pathlib import Path

from flexmvm.errors import InputError
from flexmvm.mesh.gmsh_session import (
    check_positive,
    close_to,
    faces_where,
    physical_group,
    run_gmsh,
)
from flexmvm.mesh.part_shapes import block

#: The rod of scenarios/slider_crank.toml: length, width (in the mechanism's plane), height [m].
ROD_LENGTH_M, ROD_WIDTH_M, ROD_HEIGHT_M = 0.300, 0.008, 0.008


def connecting_rod(
    path: str | os.PathLike,
    length_m: float,
    width_m: float,
    height_m: float,
    size_m: float,
    *,
    order: int = 2,
) -> Path:
    """Bar x in [0, length], y in [-width/2, width/2], z in [-height/2, height/2] (end A's
    centre at the origin), cut at mid-span (x = length/2) so that nodes lie on the mid-span
    section's edges, e.g. (length/2, -width/2, height/2), where a probe reads the deflection.
    Groups: ``end_a`` (x = 0), ``end_b`` (x = length): where the pins act; ``ends``: both (a
    reduced rod's retained nodes); ``mid``: the mid-span section (inside the bar: the rod's
    reference support, away from the pins); volume ``rod``.
    Returns the path written."""
    check_positive(length_m=length_m, width_m=width_m, height_m=height_m)
    if max(width_m, height_m) >= length_m:
        raise InputError(
            f"connecting_rod: expected a slender bar, width and height < length = "
            f"{length_m!r} m, got {width_m!r}, {height_m!r}"
        )
    half = length_m / 2

    def build(gmsh) -> None:
        occ = gmsh.model.occ
        a = occ.addBox(0.0, -width_m / 2, -height_m / 2, half, width_m, height_m)
        b = occ.addBox(half, -width_m / 2, -height_m / 2, half, width_m, height_m)
        occ.fragment([(3, a)], [(3, b)])
        occ.synchronize()
        end_a = faces_where(gmsh, lambda com, box: close_to(box[3], 0.0, length_m))
        end_b = faces_where(gmsh, lambda com, box: close_to(box[0], length_m, length_m))
        physical_group(gmsh, 2, end_a, "end_a")
        physical_group(gmsh, 2, end_b, "end_b")
        physical_group(gmsh, 2, end_a + end_b, "ends")
        mid = faces_where(
            gmsh,
            lambda com, box: close_to(box[0], half, length_m) and close_to(box[3], half, length_m),
        )
        physical_group(gmsh, 2, mid, "mid")
        physical_group(gmsh, 3, [t for _, t in gmsh.model.getEntities(3)], "rod")

    return run_gmsh(path, size_m, order, None, build)


def slider_crank_rod(path: str | os.PathLike, size_m: float = 4.0e-3) -> Path:
    """The rod of scenarios/slider_crank.toml in tet10: size_m 4 mm (two quadratic
    tetrahedra through the 8 mm section, nodes 2 mm apart); the convergence check
    (docs/slider_crank.md) also runs it at 8 mm and 2.67 mm."""
    return connecting_rod(path, ROD_LENGTH_M, ROD_WIDTH_M, ROD_HEIGHT_M, size_m)


def slider_crank_crank(path: str | os.PathLike) -> Path:
    """The crank of scenarios/slider_crank.toml: a balanced steel bar 400 x 30 x 10 mm
    (``block``: x, y centred on the origin, z in [-0.01, 0]; the pin 150 mm out on +x), tet4,
    10 mm elements. Its motion is driven, so its inertia does not enter the rod's motion."""
    return block(path, 0.400, 0.030, 0.010, 0.010)


def slider_crank_slider(path: str | os.PathLike) -> Path:
    """The slider of scenarios/slider_crank.toml: a steel block 30 x 20 x 16 mm (``block``),
    75.5 g in steel of 7870 kg/m^3 (Simeon's slider: 0.075552 kg), tet4, 10 mm elements."""
    return block(path, 0.030, 0.020, 0.016, 0.010)


#: The meshes of scenarios/slider_crank.toml (file name, how it is made), regenerated with the
#: other shipped meshes by ``python -m flexmvm.mesh.parts`` (parts.write_scenario_meshes).
SLIDER_CRANK_MESHES = (
    ("rod_300x8x8.msh", slider_crank_rod),
    ("crank_400x30x10.msh", slider_crank_crank),
    ("slider_30x20x16.msh", slider_crank_slider),
)

__all__ = [
    "ROD_HEIGHT_M",
    "ROD_LENGTH_M",
    "ROD_WIDTH_M",
    "SLIDER_CRANK_MESHES",
    "connecting_rod",
    "slider_crank_crank",
    "slider_crank_rod",
    "slider_crank_slider",
]
