"""Plain mesh data: nodes, cell blocks, named node and facet sets.

Node coordinates are in metres, in the body's own (undeformed, body-frame) coordinates.
Cell connectivity follows meshio/VTK node ordering. Degrees of freedom elsewhere in flexmvm
are numbered node-major: DOF ``3*k + d`` is component ``d`` (x, y, z) of node ``k``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from flexmvm.errors import MeshError
from flexmvm.mesh.cells import CellType


@dataclass(frozen=True)
class CellBlock:
    """Cells of one type: connectivity (n_cells, nodes_per_cell), meshio/VTK ordering."""

    cell_type: CellType
    connectivity: np.ndarray

    def __post_init__(self) -> None:
        conn = np.asarray(self.connectivity, dtype=np.int64)
        if conn.ndim != 2 or conn.shape[1] != self.cell_type.n_nodes:
            raise MeshError(
                f"{self.cell_type.value} connectivity must have shape (n, {self.cell_type.n_nodes}), "
                f"got {conn.shape}"
            )
        object.__setattr__(self, "connectivity", conn)


@dataclass(frozen=True)
class FacetSet:
    """Boundary facets of a surface, oriented with outward normals (right-hand rule).

    quads (n_q, 4) and tris (n_t, 3) hold node ids; linear facets only (the faces of
    quadratic cells as linear sub-facets through all their nodes: mesh/subfacets.py).
    """

    quads: np.ndarray = field(default_factory=lambda: np.zeros((0, 4), dtype=np.int64))
    tris: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), dtype=np.int64))

    def __post_init__(self) -> None:
        object.__setattr__(self, "quads", np.asarray(self.quads, dtype=np.int64).reshape(-1, 4))
        object.__setattr__(self, "tris", np.asarray(self.tris, dtype=np.int64).reshape(-1, 3))

    @property
    def nodes(self) -> np.ndarray:
        """Sorted unique node ids of the surface."""
        return np.unique(np.concatenate([self.quads.ravel(), self.tris.ravel()]))

    @property
    def n_facets(self) -> int:
        return len(self.quads) + len(self.tris)


@dataclass(frozen=True)
class Mesh:
    """A volume mesh with named node sets and facet sets.

    nodes: (n, 3) float [m]; cells: one CellBlock per cell type; node_sets: name -> sorted
    node ids; facet_sets: name -> FacetSet.
    """

    nodes: np.ndarray
    cells: tuple[CellBlock, ...]
    node_sets: Mapping[str, np.ndarray] = field(default_factory=dict)
    facet_sets: Mapping[str, FacetSet] = field(default_factory=dict)

    def __post_init__(self) -> None:
        nodes = np.asarray(self.nodes, dtype=np.float64)
        if nodes.ndim != 2 or nodes.shape[1] != 3 or len(nodes) == 0:
            raise MeshError(f"mesh nodes must have shape (n, 3) with n > 0, got {nodes.shape}")
        if not np.all(np.isfinite(nodes)):
            raise MeshError("mesh nodes contain NaN or infinite coordinates")
        if not self.cells:
            raise MeshError("mesh has no volume cells")
        n = len(nodes)
        for block in self.cells:
            c = block.connectivity
            if c.size and (c.min() < 0 or c.max() >= n):
                bad = int(c.min()) if c.min() < 0 else int(c.max())
                raise MeshError(
                    f"{block.cell_type.value} connectivity refers to node {bad}, "
                    f"mesh has {n} nodes (ids 0..{n - 1})"
                )
        sets = {}
        for name, ids in self.node_sets.items():
            ids = np.unique(np.asarray(ids, dtype=np.int64))
            if ids.size and (ids.min() < 0 or ids.max() >= n):
                raise MeshError(f"node set {name!r} refers to nodes outside the mesh (0..{n - 1})")
            sets[name] = ids
        object.__setattr__(self, "nodes", nodes)
        object.__setattr__(self, "node_sets", MappingProxyType(sets))
        object.__setattr__(self, "facet_sets", MappingProxyType(dict(self.facet_sets)))

    @property
    def n_nodes(self) -> int:
        return len(self.nodes)

    @property
    def n_dof(self) -> int:
        return 3 * len(self.nodes)

    @property
    def n_cells(self) -> int:
        return sum(len(b.connectivity) for b in self.cells)

    def node_set(self, name: str) -> np.ndarray:
        """Node ids of a named set; MeshError naming the known sets if absent, or saying it
        is empty (a mesh file's group with no node in the mesh)."""
        try:
            ids = self.node_sets[name]
        except KeyError:
            raise MeshError(
                f"unknown node set {name!r}; known: {', '.join(sorted(self.node_sets)) or 'none'}"
            ) from None
        if ids.size == 0:
            raise MeshError(
                f"node set {name!r} is empty (a group with no node in the mesh); "
                "expected at least one node"
            )
        return ids

    def facet_set(self, name: str) -> FacetSet:
        """Facets of a named surface; MeshError naming the known surfaces if absent, or
        saying it is empty (a mesh file's physical surface with no facet)."""
        try:
            fs = self.facet_sets[name]
        except KeyError:
            raise MeshError(
                f"unknown surface {name!r}; known: {', '.join(sorted(self.facet_sets)) or 'none'}"
            ) from None
        if fs.n_facets == 0:
            raise MeshError(
                f"surface {name!r} is empty (a group with no facet in the mesh); "
                "expected at least one facet"
            )
        return fs
