"""The volume cell types: the one CellType enum and the registry CELLS of their specs.

Each cell type is one object (a CellSpec) holding everything the mesh, results and FE stages
need about it: node count, meshio name, VTK cell id and node order, reference coordinates of
its nodes, outward corner faces and corner edges, the mid-side and face-centre nodes of its
quadratic faces (sub-facets, mesh/subfacets.py), its shape-function gradients and the
quadrature rule of its quality check (mesh/quality.py). Code asks ``cell_type.spec`` (or
``CELLS[cell_type]``, ``spec_named(meshio name)``) instead of keeping a table keyed by cell
type. The scikit-fem element and quadrature of a cell type are the fe stage's (fe/assembly.py
``_SKFEM``, keyed by the same CellType): scikit-fem is not imported below that stage.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum

import numpy as np


class CellType(Enum):
    """Volume cell types, named as meshio names them; each has a CellSpec (CELLS)."""

    HEX8 = "hexahedron"
    WEDGE6 = "wedge"
    TET4 = "tetra"
    TET10 = "tetra10"
    HEX27 = "hexahedron27"

    @property
    def spec(self) -> CellSpec:
        """This cell type's registered spec (CELLS)."""
        return CELLS[self]

    @property
    def n_nodes(self) -> int:
        return CELLS[self].n_nodes


@dataclass(frozen=True, eq=False)
class CellSpec:
    """Everything about one volume cell type (module doc).

    reference_nodes (n_nodes, 3): parametric coordinates of the nodes in meshio/VTK order
    ([0, 1]^3 hexahedra, unit simplex tetrahedra, triangle x [0, 1] wedge); the first
    ``n_corners`` are the corners. faces: corner faces (local ids), outward for a valid cell.
    edges: corner edges. edge_nodes: (corner, corner, mid-side node) of a quadratic cell;
    face_nodes: (the face's four corners, centre node). vtk_order: meshio -> VTK node order
    where they differ (meshio._vtk_common.meshio_to_vtk_order), None where equal.
    abaqus_faces: corner nodes of the faces S1, S2, ... of the Abaqus element read as this
    type (mesh/abaqus.py's sources), () where an input file's surface on it is not read.
    shape_gradients(points (n, 3)) -> (n, n_nodes, 3) parametric gradients; quadrature() ->
    points (q, 3), weights (q,) integrating the Jacobian determinant exactly (the volume and
    the quality check's points).
    """

    cell_type: CellType
    vtk_id: int
    reference_nodes: np.ndarray
    n_corners: int
    faces: tuple[tuple[int, ...], ...]
    edges: tuple[tuple[int, int], ...]
    shape_gradients: Callable[[np.ndarray], np.ndarray]
    quadrature: Callable[[], tuple[np.ndarray, np.ndarray]]
    edge_nodes: tuple[tuple[int, int, int], ...] = ()
    face_nodes: tuple[tuple[tuple[int, int, int, int], int], ...] = ()
    vtk_order: tuple[int, ...] | None = None
    abaqus_faces: tuple[tuple[int, ...], ...] = ()

    def __post_init__(self) -> None:
        ref = np.asarray(self.reference_nodes, dtype=float)
        ref.setflags(write=False)
        object.__setattr__(self, "reference_nodes", ref)

    @property
    def name(self) -> str:
        """The meshio name (the CellType's value)."""
        return self.cell_type.value

    @property
    def n_nodes(self) -> int:
        return len(self.reference_nodes)

    @property
    def corners(self) -> np.ndarray:
        """Parametric coordinates (n_corners, 3) of the corner nodes."""
        return self.reference_nodes[: self.n_corners]


#: The registered cell types (mesh/cells/__init__.py registers the built-in ones).
CELLS: dict[CellType, CellSpec] = {}


def register_cell(spec: CellSpec) -> CellSpec:
    """Add a cell type's spec to CELLS (its CellType member must exist); returns it."""
    CELLS[spec.cell_type] = spec
    return spec


def spec_named(name: str) -> CellSpec | None:
    """The spec of the cell type with meshio name ``name``, None if there is none."""
    for spec in CELLS.values():
        if spec.name == name:
            return spec
    return None


__all__ = ["CELLS", "CellSpec", "CellType", "register_cell", "spec_named"]
