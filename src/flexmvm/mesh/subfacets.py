"""Quadratic boundary faces as linear sub-facets through all their nodes, for contact.

A uniform pressure on a 6-node triangle (the face of a tetra10) has a consistent load of zero
at its corners and a third of the force at each mid-side node (Zienkiewicz & Taylor, *The
Finite Element Method*, vol. 1, sect. 8.8): contact carried by the corner nodes alone loads
the face where a pressure puts no load, and leaves the mid-side nodes free to pass through the
other body. Every face node must take part. The contact kernels work on linear facets
(3-node triangles, 4-node quads), so a quadratic face is split into linear sub-facets through
all its nodes, as the generated rods already do for their hexahedron27 faces (mesh/rod.py):

- 6-node triangle (tetra10) ``(a, b, c)`` with mid-side nodes ``ab, bc, ca``: four triangles
  ``(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)`` (the standard 1-to-4 split);
- 9-node quad (hexahedron27) ``(a, b, c, d)`` with mid-side nodes and centre ``o``: four quads
  ``(a, ab, o, da), (ab, b, bc, o), (o, bc, c, cd), (da, o, cd, d)`` (the 2 x 2 split).

Each sub-facet keeps the winding of its parent, so an outward face gives outward sub-facets.
For straight-sided cells the sub-facets tile the face exactly. An 8-node quad (hexahedron20)
does not arise: read_mesh refuses that volume type. Linear cells (tetra, hexahedron, wedge)
have no mid-side nodes and their faces are kept as they are.
"""

from __future__ import annotations

import numpy as np

from flexmvm.mesh.mesh import CellBlock, FacetSet


class _Lookup:
    """Node ids by unordered tuples of corner ids (rows of a table, matched row-wise)."""

    def __init__(self, keys: np.ndarray, values: np.ndarray) -> None:
        self.keys, self.values = np.sort(keys, axis=1), values

    def __call__(self, k: np.ndarray) -> np.ndarray:
        """Values of the rows of k (m, c) (corner ids in any order); -1 where absent."""
        if len(self.keys) == 0 or len(k) == 0:
            return np.full(len(k), -1, dtype=np.int64)
        _, inv = np.unique(np.vstack([self.keys, np.sort(k, axis=1)]), axis=0, return_inverse=True)
        inv = inv.ravel()
        owner = np.full(inv.max() + 1, -1, dtype=np.int64)
        owner[inv[: len(self.keys)]] = self.values
        return owner[inv[len(self.keys) :]]


class QuadraticFaces:
    """The mid-side and face-centre nodes of a mesh's quadratic cells, looked up by corners."""

    def __init__(self, blocks: list[CellBlock] | tuple[CellBlock, ...]) -> None:
        edges, mids, faces, centres = [], [], [], []
        for block in blocks:
            conn = block.connectivity
            for a, b, m in block.cell_type.spec.edge_nodes:
                edges.append(conn[:, [a, b]])
                mids.append(conn[:, m])
            for corners, c in block.cell_type.spec.face_nodes:
                faces.append(conn[:, list(corners)])
                centres.append(conn[:, c])
        self.quadratic = bool(edges)
        cat = lambda parts, w: np.vstack(parts) if parts else np.zeros((0, w), dtype=np.int64)
        self._mid = _Lookup(
            cat(edges, 2), np.concatenate(mids) if mids else np.zeros(0, dtype=np.int64)
        )
        self._centre = _Lookup(
            cat(faces, 4), np.concatenate(centres) if centres else np.zeros(0, dtype=np.int64)
        )

    def _mids(self, f: np.ndarray) -> list[np.ndarray]:
        """Mid-side node of each edge (f[:, i], f[:, i+1]) of facets f (n, c)."""
        c = f.shape[1]
        edges = np.vstack([np.column_stack([f[:, i], f[:, (i + 1) % c]]) for i in range(c)])
        return np.split(self._mid(edges), c)  # one search for all edges

    def split(self, facets: FacetSet) -> FacetSet:
        """Linear sub-facets (module doc) of corner facets whose edges all have a mid-side
        node (and, for quads, a centre node); other facets (of linear cells) unchanged."""
        if not self.quadratic:
            return facets
        tris, quads = facets.tris, facets.quads
        ab, bc, ca = self._mids(tris) if len(tris) else [np.zeros(0, np.int64)] * 3
        qt = (ab >= 0) & (bc >= 0) & (ca >= 0)
        a, b, c = tris[qt].T
        ab, bc, ca = ab[qt], bc[qt], ca[qt]
        sub_t = np.stack(
            [np.column_stack(s) for s in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))],
            axis=1,
        ).reshape(-1, 3)
        out_t = np.vstack([tris[~qt], sub_t])
        if len(quads):
            m1, m2, m3, m4 = self._mids(quads)
            o = self._centre(quads)
            qq = (m1 >= 0) & (m2 >= 0) & (m3 >= 0) & (m4 >= 0) & (o >= 0)
            a, b, c, d = quads[qq].T
            m1, m2, m3, m4, o = m1[qq], m2[qq], m3[qq], m4[qq], o[qq]
            sub_q = np.stack(
                [
                    np.column_stack(s)
                    for s in ((a, m1, o, m4), (m1, b, m2, o), (o, m2, c, m3), (m4, o, m3, d))
                ],
                axis=1,
            ).reshape(-1, 4)
            out_q = np.vstack([quads[~qq], sub_q])
        else:
            out_q = quads
        return FacetSet(quads=out_q, tris=out_t)


__all__ = ["QuadraticFaces"]
