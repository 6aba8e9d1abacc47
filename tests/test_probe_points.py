"""Probes at any point of a body (issue "Results a user keeps", item 6): a point with no node
within reach is interpolated with the shape functions of the tet that holds it
(mesh/point_location.py), and each probe's ``axis`` chooses the velocity component its
comparisons use (x, y, z or the speed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import flexmvm as fm
from flexmvm.mesh.mesh import CellBlock, CellType, Mesh
from flexmvm.mesh.point_location import tet_weights
from flexmvm.runs.run import run_scenario

BLOCK = Path(__file__).parents[1] / "scenarios" / "sphere_block.toml"


def _tet10() -> Mesh:
    """One straight-edged tet10 (meshio order: corners, then edges 01 12 02 03 13 23)."""
    c = np.array([[0.0, 0, 0], [2e-3, 0, 0], [0, 1e-3, 0], [0, 0, 3e-3]])
    edges = [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)]
    nodes = np.vstack([c] + [0.5 * (c[i] + c[j]) for i, j in edges])
    return Mesh(nodes, (CellBlock(CellType.TET10, np.arange(10)[None, :]),))


def test_tet10_weights_reproduce_quadratic_fields():
    """A quadratic field sampled at the ten nodes is reproduced exactly (to 1e-15 of its
    size) at an interior point, a linear one too; the weights sum to 1; a point on a face
    is found, one outside is not."""
    mesh = _tet10()
    p = np.array([0.4e-3, 0.2e-3, 0.6e-3])
    nodes, w = tet_weights(mesh, p)
    X = mesh.nodes[nodes]

    def quad(x):
        return (
            3.0
            + 2e3 * x[..., 0]
            - 1e3 * x[..., 2]
            + 5e5 * x[..., 0] * x[..., 1]
            + 7e5 * x[..., 2] ** 2
        )

    assert abs(w.sum() - 1.0) < 1e-15
    np.testing.assert_allclose(w @ X, p, rtol=0, atol=1e-18)
    assert abs(w @ quad(X) - quad(p)) < 1e-15 * abs(quad(p))
    assert tet_weights(mesh, [1e-3, 0.5e-3, 0.0]) is not None  # on the face z = 0
    assert tet_weights(mesh, [2e-3, 1e-3, 3e-3]) is None


def test_a_probe_between_nodes_is_interpolated_and_keeps_its_axis():
    """sphere_block.toml with a probe inside a coarse tet of the block (no node within 5 %
    of the block's 30 mm height, which failed before as 'off the body'): its position at the
    start is the point (to 1e-12 m), its axis the one asked; the shipped probes keep theirs
    (axis x, dumped without the key)."""
    sc = fm.load_scenario(BLOCK).with_time(t_end_s=2e-6)
    data = sc.model_dump(mode="json")
    assert all("axis" not in p for p in data["probes"])
    point = [0.0137, -0.0091, -0.0213]
    data["probes"].append({"name": "inside", "body": "block", "point_m": point, "axis": "norm"})
    sc = fm.scenario_from_dict(data, base_dir=BLOCK.parent)
    run = run_scenario(sc, warn=False)
    probe = next(p for p in run.built.probes if p.name == "inside")
    assert len(probe.nodes) == 10 and probe.axis == "norm"
    A = run.built.states[1].A
    np.testing.assert_allclose(
        run.result.probe("inside").x[0], run.built.states[1].r + A @ point, rtol=0, atol=1e-12
    )
    _, _, curves = run.result.curves()
    np.testing.assert_array_equal(
        curves["inside"], np.linalg.norm(run.result.probe("inside").v, axis=1)
    )
    np.testing.assert_array_equal(
        curves["block_top_centre"], run.result.probe("block_top_centre").v[:, 0]
    )


def test_a_point_off_the_body_is_refused_in_one_line():
    sc = fm.load_scenario(BLOCK)
    data = sc.model_dump(mode="json")
    data["probes"].append({"name": "off", "body": "block", "point_m": [0.0, 0.0, 0.05]})
    with pytest.raises(fm.InputError, match="off the body") as info:
        from flexmvm.assembly.build import build_scenario

        build_scenario(fm.scenario_from_dict(data, base_dir=BLOCK.parent))
    assert "\n" not in str(info.value)
