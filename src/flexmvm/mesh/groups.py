"""Named groups of a mesh file as meshio reads them: gmsh physical groups, Abaqus/MED sets.

A group is a name and the cells it holds, block by block of the meshio mesh. Two sources,
the first found is used:

- ``cell_sets`` (gmsh MSH 4 through meshio, Abaqus ELSET, MED families): name -> per-block
  arrays of cell indices. An element in two groups is listed in both (in MSH 4 an entity
  carries all its physical tags; the cell data ``gmsh:physical`` keeps only the first, which
  is why reading it alone loses one of a surface's two physical groups).
- ``gmsh:physical`` cell data with ``field_data`` names (gmsh MSH 2): one tag per cell; MSH 2
  writes an element once per physical group it is in, so each copy carries one of its tags.

Abaqus .inp files are read by flexmvm.mesh.abaqus, whose sets replace meshio's (merged across
repeated cards). A node set of a file (``point_sets``, Abaqus *SURFACE TYPE=NODE, VTU masks) is
also a surface where it covers skin faces (skin_within). A name in ``field_data`` (gmsh's physical names) with no cell in the file is an empty group,
kept so that asking for it says "empty" rather than "unknown". ``point_sets`` (Abaqus NSET)
are node sets as they are.
"""

from __future__ import annotations

from dataclasses import dataclass

import meshio
import numpy as np

from flexmvm.mesh.integrity import skin
from flexmvm.mesh.mesh import FacetSet
from flexmvm.mesh.subfacets import QuadraticFaces

#: Point-data masks of this prefix are node sets (mesh/io.write_mesh writes them).
NODE_SET_PREFIX = "node_set:"

_DIM_BY_PREFIX = (("vertex", 0), ("line", 1), ("triangle", 2), ("quad", 2), ("polygon", 2))


def cell_dim(cell_type: str) -> int:
    """Topological dimension of a meshio cell type (3 for every volume type)."""
    for prefix, dim in _DIM_BY_PREFIX:
        if cell_type.startswith(prefix):
            return dim
    return 3


@dataclass(frozen=True)
class Group:
    """A named group: dim (0..3, of its cells; -1 if empty and of unknown dimension) and
    members, (meshio block index, cell indices in that block) pairs (none when empty)."""

    name: str
    dim: int
    members: tuple[tuple[int, np.ndarray], ...]

    @property
    def empty(self) -> bool:
        return not any(len(idx) for _, idx in self.members)


def _gmsh_names(m: meshio.Mesh) -> dict[str, tuple[int, int]]:
    """gmsh physical names: name -> (tag, dim)."""
    return {
        k: (int(v[0]), int(v[1]))
        for k, v in m.field_data.items()
        if np.ndim(v) == 1 and len(v) >= 2
    }


def _from_cell_sets(m: meshio.Mesh) -> dict[str, list[tuple[int, np.ndarray]]]:
    out: dict[str, list[tuple[int, np.ndarray]]] = {}
    for name, per_block in m.cell_sets.items():
        if name.startswith("gmsh:"):
            continue
        members = out.setdefault(name, [])
        for k, idx in enumerate(per_block):
            if idx is not None and k < len(m.cells) and len(idx):
                members.append((k, np.asarray(idx, dtype=np.int64)))
    return out


def _from_physical_tags(m: meshio.Mesh) -> dict[str, list[tuple[int, np.ndarray]]]:
    tags = m.cell_data.get("gmsh:physical")
    out: dict[str, list[tuple[int, np.ndarray]]] = {}
    if tags is None or len(tags) != len(m.cells):  # MSH 4 through meshio: untagged blocks
        return out  # are left out (its cell_sets serve)
    for name, (tag, dim) in _gmsh_names(m).items():
        members = out.setdefault(name, [])
        for k, (block, block_tags) in enumerate(zip(m.cells, tags)):
            if cell_dim(block.type) != dim:
                continue
            idx = np.flatnonzero(np.asarray(block_tags) == tag)
            if idx.size:
                members.append((k, idx))
    return out


def read_groups(m: meshio.Mesh) -> list[Group]:
    """The named cell groups of a meshio mesh, in name order (see the module docstring).

    A group whose cells span several dimensions keeps the highest dimension's cells only
    (gmsh groups have one dimension; other formats rarely mix)."""
    named = _from_cell_sets(m)
    if not any(named.values()):
        named = _from_physical_tags(m) | {k: v for k, v in named.items() if v}
    gmsh = _gmsh_names(m)
    for name in gmsh:
        named.setdefault(name, [])
    groups = []
    for name in sorted(named):
        members = named[name]
        dims = {cell_dim(m.cells[k].type) for k, _ in members}
        dim = max(dims) if dims else gmsh.get(name, (0, -1))[1]
        kept = tuple((k, idx) for k, idx in members if cell_dim(m.cells[k].type) == dim)
        groups.append(Group(name, dim, kept))
    return groups


def group_nodes(m: meshio.Mesh, group: Group, corners: int | None = None) -> np.ndarray:
    """Sorted node ids (file numbering) of a group's cells; ``corners``: only the first
    ``corners`` nodes of each cell (the corners of a quadratic facet)."""
    parts = [np.asarray(m.cells[k].data)[idx][:, :corners].ravel() for k, idx in group.members]
    return np.unique(np.concatenate(parts)) if parts else np.zeros(0, dtype=np.int64)


#: How error messages number a file's elements and nodes (file_cell_numbers; node k of
#: meshio's points is node k + 1): meshio keeps neither gmsh's element tags nor its node
#: tags, and gmsh numbers both 1, 2, ... in file order unless renumbering was turned off.
FILE_NUMBERING = "numbered as in the file: 1-based, in file order over all its elements/nodes"


def file_cell_numbers(m: meshio.Mesh) -> list[np.ndarray]:
    """Per meshio block, the file number of each cell: 1-based running index over all the
    file's cells (surface and line elements included), in block order, which is the file's
    order for gmsh MSH 2 and 4 (meshio keeps its element blocks in order)."""
    sizes = [len(b.data) for b in m.cells]
    start = np.concatenate([[1], 1 + np.cumsum(sizes)[:-1]]).astype(np.int64)
    return [s + np.arange(n, dtype=np.int64) for s, n in zip(start, sizes)]


def point_sets(m: meshio.Mesh) -> dict[str, np.ndarray]:
    """meshio point_sets (Abaqus NSET and the like): name -> node ids (file numbering)."""
    return {
        name: np.asarray(ids, dtype=np.int64).ravel()
        for name, ids in m.point_sets.items()
        if not name.startswith("gmsh:")
    }


def _row_keys(faces: np.ndarray) -> np.ndarray:
    """Sorted corner ids of faces (n, 3|4) as (n, 4) rows, -1 padded (equal rows: same face)."""
    k = np.full((len(faces), 4), -1, dtype=np.int64)
    k[:, : faces.shape[1]] = faces
    return np.sort(k, axis=1)


def skin_rows(boundary: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The row of the skin faces ``boundary`` (B, 4), -1 padded, that each face (n, 3|4) (corner
    ids in any order) is; -1 for a face not on the skin."""
    if not len(faces) or not len(boundary):
        return np.full(len(faces), -1, dtype=np.int64)
    keys = np.vstack([_row_keys(boundary), _row_keys(faces)])
    _, inv = np.unique(keys, axis=0, return_inverse=True)
    inv = inv.ravel()
    owner = np.full(inv.max() + 1, -1, dtype=np.int64)
    owner[inv[: len(boundary)]] = np.arange(len(boundary))
    return owner[inv[len(boundary) :]]


def skin_within(boundary: np.ndarray, ids: np.ndarray, n_nodes: int) -> np.ndarray:
    """Rows of the skin faces ``boundary`` (B, 4), -1 padded, whose corners are all in the node
    set ``ids``: a node set as a surface (a quadratic face counts by its corners)."""
    inside = np.zeros(n_nodes + 1, dtype=bool)  # the last entry stands for the -1 padding
    inside[np.asarray(ids, dtype=np.int64)] = True
    inside[-1] = True
    return np.flatnonzero(np.all(inside[boundary], axis=1))


def file_node_sets(m: meshio.Mesh, new_id: np.ndarray) -> dict[str, np.ndarray]:
    """The file's node sets in read_mesh's numbering: meshio point sets (Abaqus NSET) and the
    point-data masks ``node_set:<name>`` write_mesh writes; a name in both is their union."""
    out: dict[str, np.ndarray] = {}
    masks = {
        key[len(NODE_SET_PREFIX) :]: np.flatnonzero(np.asarray(values) != 0)
        for key, values in m.point_data.items()
        if key.startswith(NODE_SET_PREFIX)
    }
    for name, ids in [*point_sets(m).items(), *masks.items()]:
        ids = new_id[ids[(ids >= 0) & (ids < len(new_id))]]
        ids = ids[ids >= 0]
        out[name] = np.union1d(out[name], ids) if name in out else np.unique(ids)
    return out


def facet_union(a: FacetSet | None, b: FacetSet) -> FacetSet:
    """The facets of a and b, each once (a's orientation where both hold one)."""
    if a is None:
        return b
    out = []
    for x, y in ((a.quads, b.quads), (a.tris, b.tris)):
        both = np.vstack([x, y])
        _, first = np.unique(np.sort(both, axis=1), axis=0, return_index=True)
        out.append(both[np.sort(first)])
    return FacetSet(quads=out[0], tris=out[1])


def add_file_sets(
    m: meshio.Mesh,
    surfaces: dict[str, np.ndarray],
    skin_data: tuple[np.ndarray, np.ndarray, QuadraticFaces],
    sets: dict[str, np.ndarray],
    facet_sets: dict[str, FacetSet],
) -> None:
    """Add to ``sets`` and ``facet_sets`` (in place) the file's node sets (file_node_sets:
    point sets, VTU masks) and its surfaces: ``surfaces`` (name -> rows of the skin faces, an
    .inp's *SURFACE cards: abaqus.surface_rows) and every file node set that covers skin faces (groups.skin_within), unless a group of
    that name is a surface already. A file node set is the node set of its name as it is (an
    Abaqus NSET and ELSET of one name: the NSET's nodes, not the elements' nodes); a surface
    of a name that is also a surface group adds its facets to the group's, and their nodes to
    its node set. skin_data: (new_id, boundary (B, 4), QuadraticFaces)."""
    new_id, boundary, quadratic = skin_data
    file_sets = file_node_sets(m, new_id)
    sets.update(file_sets)
    rows = dict(surfaces)
    n_nodes = int(new_id.max()) + 1
    rows |= {
        name: skin_within(boundary, sets[name], n_nodes)
        for name in file_sets
        if name not in facet_sets and name not in rows
    }
    for name, r in rows.items():
        if name in facet_sets or len(r) or name not in file_sets:  # a *SURFACE, even empty
            fs = quadratic.split(skin(boundary[r]))
            facet_sets[name] = facet_union(facet_sets.get(name), fs)
            if name not in file_sets:
                sets[name] = np.union1d(sets.get(name, fs.nodes), fs.nodes)


__all__ = [
    "FILE_NUMBERING",
    "NODE_SET_PREFIX",
    "Group",
    "add_file_sets",
    "cell_dim",
    "facet_union",
    "file_cell_numbers",
    "file_node_sets",
    "group_nodes",
    "point_sets",
    "read_groups",
    "skin_rows",
    "skin_within",
]
