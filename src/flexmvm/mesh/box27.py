"""Structured HEX27 meshes of a beam with the node sets a simply supported beam needs, written
without gmsh: the beam of the moving-load check (scenarios/moving_load.toml; Fryba's moving
force, flexmvm.theory.moving_load), where one quadratic cell through each side of the section
bends as an Euler-Bernoulli beam (a quadratic displacement holds pure bending exactly).

The beam spans x in [0, length], y in [-width/2, width/2], z in [-height, 0] (top face at
z = 0, as mesh.parts.beam). Node sets (names as mesh.parts.beam where they mean the same):
``end_a`` (x = 0), ``end_b`` (x = length), ``top`` (z = 0), ``bottom`` (z = -height),
``end_a_axis`` and ``end_b_axis`` (the end faces' lines on the beam's axis height z =
-height/2, across y), ``end_a_bottom`` and ``end_b_bottom`` (their bottom edges: line
supports), ``mid_axis`` (the node at (length/2, 0, -height/2): an even cells_x and
odd lattice counts across keep it a node). The skin ``surface`` is added by read_mesh.

``python -m flexmvm.mesh.box27 [DIR]`` writes the shipped moving-load beam
(MOVING_LOAD_BEAM) into DIR (default scenarios/meshes).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

from flexmvm.errors import InputError
from flexmvm.mesh.io import write_mesh
from flexmvm.mesh.mesh import CellBlock, CellType, Mesh
from flexmvm.mesh.structured import HEX27_OFFSETS

#: The shipped beam of scenarios/moving_load.toml: 1 m x 20 mm x 20 mm, 40 x 1 x 1 cells
#: (file name, length, width, height [m], cells along x, y, z).
MOVING_LOAD_BEAM = ("beam_1000x20x20_hex27.vtu", 1.0, 0.02, 0.02, (40, 1, 1))


def hex27_box_beam(
    length_m: float, width_m: float, height_m: float, cells: tuple[int, int, int]
) -> Mesh:
    """The beam above as cells[0] x cells[1] x cells[2] HEX27 cells (module doc). InputError
    for a non-positive size, fewer than one cell along an axis or an odd cells[0]."""
    nx, ny, nz = (int(c) for c in cells)
    if not (min(length_m, width_m, height_m) > 0.0 and min(nx, ny, nz) >= 1 and nx % 2 == 0):
        raise InputError(
            f"hex27 box beam: expected sizes > 0 m and cells >= 1 with an even count along x, "
            f"got {length_m!r}, {width_m!r}, {height_m!r} m, cells {cells!r}"
        )
    shape = (2 * nx + 1, 2 * ny + 1, 2 * nz + 1)
    ids = np.arange(np.prod(shape)).reshape(shape)
    ijk = np.stack(np.meshgrid(*[np.arange(s) for s in shape], indexing="ij"), -1).reshape(-1, 3)
    nodes = ijk / (np.array(shape) - 1.0) * [length_m, width_m, height_m]
    nodes -= [0.0, width_m / 2.0, height_m]
    cx, cy, cz = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    base = 2 * np.column_stack([cx.ravel(), cy.ravel(), cz.ravel()])
    conn = np.stack([ids[tuple((base + o).T)] for o in HEX27_OFFSETS], axis=1)
    i, j, k = ijk.T
    last_i, mid_k = shape[0] - 1, shape[2] // 2
    sets = {
        "end_a": np.flatnonzero(i == 0),
        "end_b": np.flatnonzero(i == last_i),
        "top": np.flatnonzero(k == shape[2] - 1),
        "bottom": np.flatnonzero(k == 0),
        "end_a_axis": np.flatnonzero((i == 0) & (k == mid_k)),
        "end_b_axis": np.flatnonzero((i == last_i) & (k == mid_k)),
        "end_a_bottom": np.flatnonzero((i == 0) & (k == 0)),
        "end_b_bottom": np.flatnonzero((i == last_i) & (k == 0)),
        "mid_axis": np.flatnonzero((i == last_i // 2) & (j == shape[1] // 2) & (k == mid_k)),
    }
    return Mesh(nodes, (CellBlock(CellType.HEX27, conn),), node_sets=sets)


def write_box_beam(
    path: str | os.PathLike,
    length_m: float,
    width_m: float,
    height_m: float,
    cells: tuple[int, int, int],
) -> Path:
    """Write hex27_box_beam(...) to ``path`` (a .vtu keeps the node sets); returns the path."""
    path = Path(path)
    write_mesh(path, hex27_box_beam(length_m, width_m, height_m, cells))
    return path


def main(argv: list[str] | None = None) -> int:
    """``python -m flexmvm.mesh.box27 [DIR]``: write MOVING_LOAD_BEAM into DIR."""
    args = sys.argv[1:] if argv is None else argv
    directory = Path(args[0]) if args else Path("scenarios") / "meshes"
    name, length_m, width_m, height_m, cells = MOVING_LOAD_BEAM
    print(write_box_beam(directory / name, length_m, width_m, height_m, cells))
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())


__all__ = ["MOVING_LOAD_BEAM", "hex27_box_beam", "write_box_beam"]
