"""Whether a volume mesh is one joined body: coincident nodes not merged, parts that share no
node, skin facets lying on each other.

A block meshed as two volumes whose interface nodes are duplicated instead of merged (gmsh
without Coherence/fragment, an exported assembly) passes every cell check (quality, faces)
and runs: its two halves are simply not connected, and the contact force is wrong (issue 48:
100.0 N against 183.3 N for the same mesh merged). Three signs of it, each cheap:

(a) coincident nodes: two nodes closer than COINCIDENT_RELATIVE x the smallest corner-edge
    length of the cells at either node (scipy.spatial.cKDTree pairs);
(b) components: cells joined through shared nodes form more than one connected part
    (scipy.sparse.csgraph.connected_components);
(c) touching skin: a skin facet whose centroid lies on another skin facet (within
    COINCIDENT_RELATIVE of that facet's size, inside it, normals opposite): an interface left
    on the skin, whether its nodes match (a) or not (a non-conforming interface).

``merge_coincident`` merges the pairs of (a) (each group of coincident nodes becomes its
lowest id; the rest renumbered in order).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from flexmvm.errors import MeshError
from flexmvm.mesh.groups import FILE_NUMBERING
from flexmvm.mesh.integrity import check_faces
from flexmvm.mesh.mesh import CellBlock, Mesh
from flexmvm.mesh.quality import check_quality

#: Nodes (or a facet centroid and a facet) closer than this fraction of the local smallest
#: edge length are taken to coincide: far below any edge of a valid cell (a cell's own nodes
#: are at least half its shortest edge apart), far above round-off of coordinates in a file.
COINCIDENT_RELATIVE = 1e-6


@dataclass(frozen=True)
class Joins:
    """What connectivity_report found: ``pairs`` (P, 2) coincident node pairs (i < j),
    ``component_sizes`` the node count of each connected part (one entry for a joined body),
    ``touching_facets`` the number of skin facets lying on another skin facet."""

    pairs: np.ndarray
    component_sizes: tuple[int, ...]
    touching_facets: int

    @property
    def joined(self) -> bool:
        return not len(self.pairs) and len(self.component_sizes) == 1 and not self.touching_facets


def node_sizes(nodes: np.ndarray, blocks: list[CellBlock]) -> np.ndarray:
    """Smallest corner-edge length [m] of the cells at each node, (n,); inf at a node of no
    cell."""
    h = np.full(len(nodes), np.inf)
    for block in blocks:
        conn = block.connectivity
        if not len(conn):
            continue
        a, b = np.array(block.cell_type.spec.edges).T
        cell_h = np.linalg.norm(nodes[conn[:, a]] - nodes[conn[:, b]], axis=2).min(axis=1)
        np.minimum.at(h, conn, cell_h[:, None])
    return h


def coincident_pairs(nodes: np.ndarray, blocks: list[CellBlock]) -> np.ndarray:
    """Node pairs (P, 2), i < j, closer than COINCIDENT_RELATIVE x the smaller of their nodes'
    sizes (node_sizes); empty (0, 2) for a mesh with every position once."""
    h = node_sizes(nodes, blocks)
    finite = np.isfinite(h)
    if not finite.any():
        return np.zeros((0, 2), dtype=np.int64)
    tol = COINCIDENT_RELATIVE * h
    pairs = cKDTree(nodes).query_pairs(float(tol[finite].max()), output_type="ndarray")
    if not len(pairs):
        return np.zeros((0, 2), dtype=np.int64)
    d = np.linalg.norm(nodes[pairs[:, 0]] - nodes[pairs[:, 1]], axis=1)
    keep = d <= np.minimum(tol[pairs[:, 0]], tol[pairs[:, 1]])
    return np.sort(pairs[keep].astype(np.int64), axis=1)


def component_sizes(n_nodes: int, blocks: list[CellBlock]) -> tuple[int, ...]:
    """Node counts of the parts of cells joined through shared nodes, largest first (nodes of
    no cell left out)."""
    rows, cols = [], []
    for block in blocks:
        conn = block.connectivity
        rows.append(np.repeat(conn[:, :1], conn.shape[1] - 1, axis=1).ravel())
        cols.append(conn[:, 1:].ravel())
    r, c = np.concatenate(rows), np.concatenate(cols)
    graph = sp.coo_matrix((np.ones(len(r), dtype=np.int8), (r, c)), shape=(n_nodes, n_nodes))
    _, labels = connected_components(graph, directed=False)
    used = np.unique(np.concatenate([b.connectivity.ravel() for b in blocks]))
    counts = np.bincount(labels[used])
    return tuple(int(k) for k in sorted(counts[counts > 0], reverse=True))


def _triangles(boundary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Boundary faces (B, 4), -1 padded, as triangles (T, 3) with the face index (T,)."""
    quad = boundary[:, 3] >= 0
    tris = [boundary[~quad, :3], boundary[quad][:, [0, 1, 2]], boundary[quad][:, [0, 2, 3]]]
    owner = [np.flatnonzero(~quad), np.flatnonzero(quad), np.flatnonzero(quad)]
    return np.vstack(tris), np.concatenate(owner)


def touching_facets(nodes: np.ndarray, boundary: np.ndarray) -> int:
    """Number of skin faces (boundary: (B, 4) outward, -1 padded) whose centroid lies on
    another skin face with the opposite normal: within COINCIDENT_RELATIVE x that face's
    shortest edge of its plane and inside it (barycentric, same tolerance)."""
    if not len(boundary):
        return 0
    tri, owner = _triangles(boundary)
    p = nodes[tri]  # (T, 3, 3)
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    n = np.cross(e1, e2)
    area2 = np.linalg.norm(n, axis=1)
    n = n / np.maximum(area2, np.finfo(float).tiny)[:, None]
    quad = boundary[:, 3] >= 0
    corners = np.where(boundary >= 0, boundary, boundary[:, :1])
    centroid = np.where(
        quad[:, None], nodes[corners].mean(axis=1), nodes[corners[:, :3]].mean(axis=1)
    )
    edge = np.minimum(
        np.linalg.norm(e1, axis=1),
        np.minimum(np.linalg.norm(e2, axis=1), np.linalg.norm(p[:, 2] - p[:, 1], axis=1)),
    )
    reach = np.maximum(np.linalg.norm(e1, axis=1), np.linalg.norm(e2, axis=1))
    tree = cKDTree(centroid)
    hits = tree.query_ball_point(p[:, 0], reach * (1 + 1e-9))
    t_idx = np.repeat(np.arange(len(tri)), [len(h) for h in hits])
    f_idx = np.fromiter((j for h in hits for j in h), dtype=np.int64, count=len(t_idx))
    other = owner[t_idx] != f_idx
    t_idx, f_idx = t_idx[other], f_idx[other]
    tol = COINCIDENT_RELATIVE * edge[t_idx]
    rel = centroid[f_idx] - p[t_idx, 0]
    on_plane = np.abs(np.einsum("ij,ij->i", rel, n[t_idx])) <= tol
    fq = boundary[f_idx]
    fcorn = np.where(fq >= 0, fq, fq[:, :1])
    fp = nodes[fcorn]
    fn = np.cross(fp[:, 1] - fp[:, 0], fp[:, 2] - fp[:, 0])
    opposite = np.einsum("ij,ij->i", fn, n[t_idx]) < 0
    # barycentric coordinates of the centroid in the triangle
    d00 = np.einsum("ij,ij->i", e1[t_idx], e1[t_idx])
    d01 = np.einsum("ij,ij->i", e1[t_idx], e2[t_idx])
    d11 = np.einsum("ij,ij->i", e2[t_idx], e2[t_idx])
    d20 = np.einsum("ij,ij->i", rel, e1[t_idx])
    d21 = np.einsum("ij,ij->i", rel, e2[t_idx])
    den = np.maximum(d00 * d11 - d01 * d01, np.finfo(float).tiny)
    v = (d11 * d20 - d01 * d21) / den
    w = (d00 * d21 - d01 * d20) / den
    eps = COINCIDENT_RELATIVE
    inside = (v >= -eps) & (w >= -eps) & (v + w <= 1 + eps)
    return len(np.unique(f_idx[on_plane & opposite & inside]))


def connectivity_report(nodes: np.ndarray, blocks: list[CellBlock], boundary: np.ndarray) -> Joins:
    """Joins of a mesh: coincident pairs (a), parts (b), touching skin facets (c); boundary
    (B, 4) the skin faces of integrity.check_faces."""
    return Joins(
        pairs=coincident_pairs(nodes, blocks),
        component_sizes=component_sizes(len(nodes), blocks),
        touching_facets=touching_facets(nodes, boundary),
    )


def merge_coincident(
    nodes: np.ndarray, blocks: list[CellBlock], pairs: np.ndarray
) -> tuple[np.ndarray, list[CellBlock], np.ndarray]:
    """The mesh with each group of coincident nodes (pairs (P, 2), joined transitively) made
    one node, its lowest id: kept nodes (m, 3) in their order, the blocks renumbered, and the
    map old id -> new id (n,)."""
    n = len(nodes)
    graph = sp.coo_matrix((np.ones(len(pairs), dtype=np.int8), (pairs[:, 0], pairs[:, 1])), (n, n))
    _, labels = connected_components(graph, directed=False)
    first = np.full(labels.max() + 1, n, dtype=np.int64)
    np.minimum.at(first, labels, np.arange(n))
    rep = first[labels]
    kept = np.flatnonzero(rep == np.arange(n))
    new_of_kept = np.full(n, -1, dtype=np.int64)
    new_of_kept[kept] = np.arange(len(kept))
    old_to_new = new_of_kept[rep]
    return (
        nodes[kept],
        [CellBlock(b.cell_type, old_to_new[b.connectivity]) for b in blocks],
        old_to_new,
    )


#: How to join what the checks found, by scenario key or read_mesh argument.
MERGE_HINT = (
    "merge them in the mesher (gmsh: Coherence or BooleanFragments), or set merge_nodes = true "
    "in the body's [[bodies]] table (read_mesh(..., merge_nodes=True))"
)


def refusal(joins: Joins, where: str) -> str | None:
    """The one-line MeshError message for a mesh that is not one joined body, or None."""
    parts = len(joins.component_sizes)
    split = (
        f"{parts} parts sharing no node (nodes {', '.join(map(str, joins.component_sizes))})"
        if parts > 1
        else "one part"
    )
    touch = f"{joins.touching_facets} skin facets lying on other skin facets"
    if len(joins.pairs):
        return (
            f"{where}: {len(joins.pairs)} coincident node pairs not merged (two volumes meshed "
            f"without Coherence/fragment: {split}, {touch}); {MERGE_HINT}"
        )
    if parts > 1 and joins.touching_facets:
        return (
            f"{where}: {split}, touching on {touch} (an interface meshed with nodes that do "
            f"not match); expected one joined body: mesh the volumes together (gmsh: "
            f"BooleanFragments) so that they share the interface's nodes"
        )
    if parts > 1:
        return (
            f"{where}: {split} and not touching; expected one connected body: make each "
            f"part a body of its own (its own mesh file)"
        )
    if joins.touching_facets:
        return (
            f"{where}: {touch} (an internal interface or crack left open: its sides share "
            f"no node); expected skin facets on the outer boundary only: mesh the volumes "
            f"together (gmsh: BooleanFragments) so that they share the interface's nodes"
        )
    return None


def _file_node_numbers(new_id: np.ndarray, n_nodes: int) -> np.ndarray:
    """The file number (1-based) of each node: the lowest file id mapped to it, plus one."""
    used = np.flatnonzero(new_id >= 0)
    out = np.full(n_nodes, np.iinfo(np.int64).max, dtype=np.int64)
    np.minimum.at(out, new_id[used], used + 1)
    return out


def joined_cells(
    nodes: np.ndarray,
    blocks: list[CellBlock],
    new_id: np.ndarray,
    cell_no: np.ndarray,
    where: str,
    merge_nodes: bool,
) -> tuple[np.ndarray, list[CellBlock], np.ndarray, np.ndarray, int]:
    """Quality (quality.check_quality), faces (integrity.check_faces) and joins of a file's
    renumbered cells, each a one-line MeshError naming cells and nodes as the file numbers
    them (cell_no (C,): file number of each cell in running order; new_id: file id -> id).
    With ``merge_nodes`` coincident nodes are merged (merge_coincident) and the cells checked
    again. Returns nodes, blocks, new_id, the skin faces (B, 4) and the pairs merged (0: none).
    """
    merged = 0
    while True:
        node_no = _file_node_numbers(new_id, len(nodes))
        offsets = np.cumsum([0] + [len(b.connectivity) for b in blocks])

        def name(k: int, c: int, blocks=blocks, offsets=offsets) -> str:
            n = int(cell_no[offsets[k] + c])
            return f"{blocks[k].cell_type.value} element {n} ({FILE_NUMBERING})"

        try:
            check_quality(Mesh(nodes=nodes, cells=tuple(blocks)), cell_name=name)
        except MeshError as exc:
            raise MeshError(f"{where}: {exc}") from None
        boundary = check_faces(nodes, blocks, where, (cell_no, node_no, FILE_NUMBERING))
        joins = connectivity_report(nodes, blocks, boundary)
        if len(joins.pairs) and merge_nodes and not merged:
            merged = len(joins.pairs)
            nodes, blocks, old_to_new = merge_coincident(nodes, blocks, joins.pairs)
            new_id = np.where(new_id >= 0, old_to_new[np.maximum(new_id, 0)], -1)
            continue
        problem = refusal(joins, where)
        if problem is not None:
            raise MeshError(problem)
        return nodes, blocks, new_id, boundary, merged


__all__ = [
    "COINCIDENT_RELATIVE",
    "MERGE_HINT",
    "Joins",
    "coincident_pairs",
    "component_sizes",
    "connectivity_report",
    "joined_cells",
    "merge_coincident",
    "node_sizes",
    "refusal",
    "touching_facets",
]
