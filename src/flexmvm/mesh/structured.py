"""Structured HEX27 meshes of boxes, written without gmsh: the beams of the spin-up showcase
(scenarios/spin_up.toml), where a slender rectangular beam (Kane, Ryan and Banerjee 1987: 10 m
long, 77.5 x 5.2 mm) wants one quadratic cell through each side and a few along its length.

The box spans x in [0, length], y in [-width/2, width/2], z in [-thickness/2, thickness/2]:
its root face is x = 0, centred on the x axis (a spin axis through the origin is a hub of
radius 0). Node sets: ``root`` (x = 0), ``tip`` (x = length), ``tip_centre`` (the node at
(length, 0, 0), which exists with an odd number of nodes across each side: always, for HEX27).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from flexmvm.errors import InputError
from flexmvm.mesh.io import write_mesh
from flexmvm.mesh.mesh import CellBlock, CellType, Mesh

#: The meshio/VTK hexahedron27 local nodes on the doubled lattice (offsets 0, 1, 2 per axis):
#: corners, the bottom, top and vertical edges' midpoints, the face centres x = 0, x = 1,
#: y = 0, y = 1, z = 0, z = 1, the centre (the VTK cell's definition).
HEX27_OFFSETS = np.array(
    [
        [0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0], [0, 0, 2], [2, 0, 2], [2, 2, 2], [0, 2, 2],
        [1, 0, 0], [2, 1, 0], [1, 2, 0], [0, 1, 0], [1, 0, 2], [2, 1, 2], [1, 2, 2], [0, 1, 2],
        [0, 0, 1], [2, 0, 1], [2, 2, 1], [0, 2, 1],
        [0, 1, 1], [2, 1, 1], [1, 0, 1], [1, 2, 1], [1, 1, 0], [1, 1, 2], [1, 1, 1],
    ]
)  # fmt: skip

#: The spin-up beam of Kane, Ryan and Banerjee 1987 (J. Guidance 10(2), 139-151): L = 10 m,
#: A = 4e-4 m^2, I = 2e-7 m^4 about the axis normal to the plane of rotation, so a rectangle
#: of depth sqrt(12 I / A) in the plane (y) and A / depth across it (z) [m].
KANE_LENGTH_M = 10.0
KANE_DEPTH_M = math.sqrt(12.0 * 2e-7 / 4e-4)
KANE_THICKNESS_M = 4e-4 / KANE_DEPTH_M


def hex27_beam(length_m: float, width_m: float, thickness_m: float, cells_x: int) -> Mesh:
    """The box above as cells_x x 1 x 1 HEX27 cells (module doc). Raises InputError for a
    non-positive size or fewer than one cell."""
    if not (min(length_m, width_m, thickness_m) > 0.0 and cells_x >= 1):
        raise InputError(
            f"hex27 beam: sizes must be > 0 m and cells_x >= 1, got {length_m!r}, {width_m!r}, "
            f"{thickness_m!r}, {cells_x!r}"
        )
    shape = (2 * cells_x + 1, 3, 3)
    ids = np.arange(np.prod(shape)).reshape(shape)
    ijk = np.stack(np.meshgrid(*[np.arange(s) for s in shape], indexing="ij"), -1).reshape(-1, 3)
    nodes = ijk / (np.array(shape) - 1.0) * [length_m, width_m, thickness_m]
    nodes -= [0.0, width_m / 2.0, thickness_m / 2.0]
    base = np.column_stack([2 * np.arange(cells_x), np.zeros(cells_x, int), np.zeros(cells_x, int)])
    conn = np.stack([ids[tuple((base + o).T)] for o in HEX27_OFFSETS], axis=1)
    x = nodes[:, 0]
    sets = {
        "root": np.flatnonzero(ijk[:, 0] == 0),
        "tip": np.flatnonzero(ijk[:, 0] == shape[0] - 1),
        "tip_centre": np.flatnonzero((ijk[:, 0] == shape[0] - 1) & np.all(ijk[:, 1:] == 1, 1)),
    }
    assert np.isclose(x[sets["tip_centre"]], length_m).all()
    return Mesh(nodes, (CellBlock(CellType.HEX27, conn),), node_sets=sets)


def spin_up_beam_part(path: str | os.PathLike, cells_x: int = 20) -> Path:
    """Write Kane's spin-up beam (KANE_*: 10 m x 77.5 mm x 5.16 mm, cells_x HEX27 cells along
    it) to ``path`` (a .vtu keeps the node sets); returns the path."""
    path = Path(path)
    write_mesh(path, hex27_beam(KANE_LENGTH_M, KANE_DEPTH_M, KANE_THICKNESS_M, cells_x))
    return path


__all__ = [
    "KANE_DEPTH_M",
    "KANE_LENGTH_M",
    "KANE_THICKNESS_M",
    "hex27_beam",
    "spin_up_beam_part",
]
