"""Integrity of a volume mesh as a reader receives it: duplicated cells, faces shared the wrong
way, the outer skin.

A mesh file can hold every cell with a positive Jacobian (mesh/quality.py) and still be wrong
for the FE model: a cell written twice doubles its stiffness and mass (gmsh's MSH 2 format
writes an element once per physical volume it belongs to; tests/test_cli_failures.py has the
issue's case, a hexahedron27 of a rod written twice), and two cells folded onto each other
overlap. Both are seen on the faces: every interior face of a conforming mesh belongs to
exactly two cells lying on opposite sides of it (their outward face normals opposite), every
boundary face to one. The faces met once are the outer skin, the facet set ``surface``.

Faces are the corner faces of each cell type, numbered so that their right-hand normal points
out of a cell with a positive Jacobian (meshio/VTK node order; quality.py checks the sign).
"""

from __future__ import annotations

import numpy as np

from flexmvm.errors import MeshError
from flexmvm.mesh.mesh import CellBlock, CellType, FacetSet


def face_table(
    nodes: np.ndarray, blocks: list[CellBlock]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every corner face of every cell, outward for a valid cell.

    Returns keys (F, 4) (sorted node ids, -1 padded for triangles: equal keys are the same
    face), faces (F, 4) (the face's nodes in outward order, -1 padded), centroids (F, 3) [m]
    of the owning cells, and cell (F,) the owning cell's running index over the blocks.
    """
    keys, faces, cents, owner = [], [], [], []
    offset = 0
    for block in blocks:
        conn = block.connectivity
        centroid = nodes[conn].mean(axis=1)
        for face_nodes in block.cell_type.spec.faces:
            face = list(face_nodes)
            f = np.full((len(conn), 4), -1, dtype=np.int64)
            f[:, : len(face)] = conn[:, face]
            faces.append(f)
            keys.append(np.sort(f, axis=1))
            cents.append(centroid)
            owner.append(offset + np.arange(len(conn)))
        offset += len(conn)
    return np.vstack(keys), np.vstack(faces), np.vstack(cents), np.concatenate(owner)


def _normals(nodes: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Right-hand normals (F, 3) of -1 padded faces: triangles, or quads by their diagonals."""
    quad = faces[:, 3] >= 0
    p = nodes[np.where(faces >= 0, faces, faces[:, :1])]
    tri_n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    quad_n = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
    return np.where(quad[:, None], quad_n, tri_n)


def duplicate_cells(blocks: list[CellBlock]) -> list[tuple[CellType, np.ndarray]]:
    """Groups of cells with the same node set: (cell type, cell indices within the block),
    one entry per group of two or more; empty for a mesh with every cell once."""
    out = []
    for block in blocks:
        keys = np.sort(block.connectivity, axis=1)
        _, inv, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
        inv = inv.ravel()
        for g in np.flatnonzero(counts > 1):
            out.append((block.cell_type, np.flatnonzero(inv == g)))
    return out


def check_faces(
    nodes: np.ndarray,
    blocks: list[CellBlock],
    where: str,
    numbers: tuple[np.ndarray, np.ndarray, str] | None = None,
) -> np.ndarray:
    """MeshError (one line, prefixed by ``where``) unless every face is met once (skin) or
    twice by cells on opposite sides (outward normals with a negative dot product).

    Call after the quality check (positive Jacobians: outward face order is outward) and after
    duplicates are refused or dropped. ``numbers``: (cell numbers (C,) by running cell index,
    node numbers (n,), how they are numbered) to name cells and nodes as a file does; without
    it, running ids over the blocks and node ids. Returns the boundary faces (B, 4), outward,
    -1 padded.
    """
    keys, faces, _, cell = face_table(nodes, blocks)
    if numbers is None:
        cell_no, node_no = np.arange(cell.max() + 1), np.arange(len(nodes))
        how = "running ids over the blocks"
    else:
        cell_no, node_no, how = numbers
    _, inv, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    if np.any(counts > 2):
        g = int(np.flatnonzero(counts > 2)[0])
        owners = cell_no[cell[inv == g]].tolist()
        key = keys[inv == g][0]
        raise MeshError(
            f"{where}: face {node_no[key[key >= 0]].tolist()} belongs to {int(counts[g])} "
            f"cells ({owners}; {how}); expected at most 2 (overlapping or non-manifold cells)"
        )
    order = np.argsort(inv, kind="stable")
    pairs = order[np.repeat(counts == 2, counts)].reshape(-1, 2)  # faces sorted by key
    if len(pairs):
        n = _normals(nodes, faces[pairs.ravel()]).reshape(-1, 2, 3)
        bad = np.flatnonzero(np.einsum("ij,ij->i", n[:, 0], n[:, 1]) >= 0)
        if bad.size:
            a, b = cell_no[cell[pairs[bad[0]]]]
            raise MeshError(
                f"{where}: cells {int(a)} and {int(b)} ({how}) "
                f"lie on the same side of their shared face; expected neighbours on "
                f"opposite sides ({bad.size} such face(s): folded or overlapping "
                f"cells)"
            )
    return faces[order[np.repeat(counts == 1, counts)]]


def skin(boundary: np.ndarray) -> FacetSet:
    """The outer skin as a FacetSet from check_faces' boundary faces (outward, -1 padded)."""
    quad = boundary[:, 3] >= 0
    return FacetSet(quads=boundary[quad], tris=boundary[~quad, :3])


__all__ = ["check_faces", "duplicate_cells", "face_table", "skin"]
