"""The cell-type registry (mesh/cells): one spec per CellType, consistent in itself, and the
modules that used to keep tables keyed by cell type ask it instead (issue 50, item 1)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from flexmvm.fe.assembly import local_permutation
from flexmvm.mesh.cells import CELLS, CellType, spec_named

#: Volume of each reference cell: [0, 1]^3, the unit simplex, triangle x [0, 1]
_REF_VOLUME = {
    CellType.HEX8: 1.0,
    CellType.HEX27: 1.0,
    CellType.TET4: 1 / 6,
    CellType.TET10: 1 / 6,
    CellType.WEDGE6: 1 / 2,
}

_SRC = Path(__file__).resolve().parents[1] / "src" / "flexmvm"


@pytest.mark.parametrize("cell_type", list(CellType), ids=lambda c: c.value)
def test_every_cell_type_has_a_consistent_spec(cell_type):
    """Shape gradients sum to zero (partition of unity), the quadrature integrates the
    reference volume, faces are outward, mid-side and face-centre nodes sit where they say.
    Tolerances 1e-12: round-off of sums of O(1) terms."""
    spec = CELLS[cell_type]
    assert spec.cell_type is cell_type and spec_named(cell_type.value) is spec
    ref = spec.reference_nodes
    assert ref.shape == (cell_type.n_nodes, 3) and spec.n_nodes == cell_type.n_nodes
    pts = np.random.default_rng(0).random((5, 3)) * 0.3
    assert np.abs(spec.shape_gradients(pts).sum(axis=1)).max() < 1e-12
    _, w = spec.quadrature()
    assert abs(w.sum() - _REF_VOLUME[cell_type]) < 1e-12
    centre = spec.corners.mean(axis=0)
    for face in spec.faces:
        p = ref[list(face)]
        n = np.cross(p[1] - p[0], p[-1] - p[0])
        assert n @ (p.mean(axis=0) - centre) > 0, face
    for a, b, m in spec.edge_nodes:
        assert np.array_equal(ref[m], (ref[a] + ref[b]) / 2)
    for corners, c in spec.face_nodes:
        assert np.array_equal(ref[c], ref[list(corners)].mean(axis=0))
    # the fe stage's element maps onto the spec's nodes (MeshError otherwise)
    assert sorted(local_permutation(cell_type)) == list(range(spec.n_nodes))


def test_no_table_keyed_by_cell_type_outside_the_registry():
    """The mesh, results and point-location modules name no CellType member: they ask
    the registry. The fe stage keeps one table, the scikit-fem part of each cell type
    (fe/assembly.py _SKFEM: scikit-fem is not imported below that stage)."""
    files = [
        "mesh/mesh.py",
        "mesh/integrity.py",
        "mesh/quality.py",
        "mesh/subfacets.py",
        "mesh/connectivity.py",
        "mesh/point_location.py",
        "mesh/abaqus.py",
        "results/fields.py",
        "results/vtu.py",
    ]
    named = {f: re.findall(r"CellType\.[A-Z]", (_SRC / f).read_text()) for f in files}
    assert not any(named.values()), named
    skfem = re.findall(r"CellType\.[A-Z]", (_SRC / "fe/assembly.py").read_text())
    assert len(skfem) == len(CellType)
