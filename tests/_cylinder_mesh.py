"""A quarter of a thick-walled cylinder's slice as curved HEX27 cells (axis z), built here
independently of the library's mesh generators: exact radii and angles at every node."""

from __future__ import annotations

import numpy as np
from test_fe import _HEX27

from flexmvm.mesh.mesh import CellBlock, CellType, Mesh


def quarter_annulus(a, b, thickness, n_r, n_theta, grading=1.0) -> Mesh:
    """Sector a <= r <= b, 0 <= theta <= pi/2, 0 <= z <= thickness: n_r x n_theta x 1 HEX27
    cells (radial element sizes in geometric ratio ``grading``, finest at the bore)."""
    w = grading ** np.arange(n_r)
    edges = a + (b - a) * np.concatenate([[0.0], np.cumsum(w) / w.sum()])
    r_nodes = np.empty(2 * n_r + 1)
    r_nodes[0::2] = edges
    r_nodes[1::2] = 0.5 * (edges[:-1] + edges[1:])
    i, j, k = np.meshgrid(
        np.arange(2 * n_r + 1), np.arange(2 * n_theta + 1), np.arange(3), indexing="ij"
    )
    r = r_nodes[i]
    th = j / (2 * n_theta) * (np.pi / 2)
    nodes = np.stack([r * np.cos(th), r * np.sin(th), k / 2 * thickness], -1).reshape(-1, 3)
    ids = np.arange(nodes.shape[0]).reshape(i.shape)
    base = np.stack(
        np.meshgrid(2 * np.arange(n_r), 2 * np.arange(n_theta), [0], indexing="ij"), -1
    ).reshape(-1, 3)
    conn = np.stack([ids[tuple((base + np.asarray(o)).T)] for o in _HEX27], axis=1)
    return Mesh(nodes, (CellBlock(CellType.HEX27, conn),))
