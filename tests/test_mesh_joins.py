"""Meshes whose parts do not join (issue 48): coincident nodes not merged, parts sharing no
node, an interface left on the skin; refused at read in one line, or merged on request
(read_mesh(merge_nodes=True), a body's ``merge_nodes = true``). The meshes are made with gmsh
here: two unit boxes meshed as two volumes WITHOUT fragment/Coherence, so that their common
face is meshed twice (the same surface mesh on both sides: every interface node duplicated)."""

from __future__ import annotations

import glob
import warnings
from pathlib import Path

import numpy as np
import pytest
from _cantilever import ROD

from flexmvm.assembly.build import build_scenario
from flexmvm.assembly.build_cache import SetupCache
from flexmvm.assembly.cache_keys import MergedFile, mesh_key, mesh_source
from flexmvm.errors import MeshError
from flexmvm.mesh.connectivity import connectivity_report
from flexmvm.mesh.integrity import check_faces
from flexmvm.mesh.io import MeshWarning, read_mesh
from flexmvm.mesh.quality import mesh_volume
from flexmvm.mesh.rod import EndShape, RodSpec, rod_mesh
from flexmvm.scenarios.load import scenario_from_dict
from flexmvm.scenarios.problems import ScenarioError

gmsh = pytest.importorskip("gmsh")

ROOT = Path(__file__).resolve().parents[1]
SIZE = 0.25  # element size [m] of the tet boxes: a few hundred tets, meshed in ~0.1 s
DIV = 4  # hex8 per edge of the hex boxes: 64 per box, 25 interface nodes


def _two_boxes(path: Path, second_at=(1.0, 0.0, 0.0), fragment: bool = False, hexes=True):
    """Boxes [0,1]^3 and [0,1]^3 + second_at as two volumes; ``fragment``: joined by gmsh
    (shared interface nodes), else meshed apart. ``hexes``: transfinite hex8, DIV per edge
    (both copies of the interface meshed alike: every interface node duplicated), else tets
    of size SIZE (gmsh meshes the two copies differently: they match on some nodes only).
    Groups: ``top`` (z = 1 faces), ``left`` (x = 0), ``solid``. Returns (path, nodes of the file)."""
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("two")
        occ = gmsh.model.occ
        a = occ.addBox(0, 0, 0, 1, 1, 1)
        b = occ.addBox(*second_at, 1, 1, 1)
        if fragment:
            occ.fragment([(3, a)], [(3, b)])
        occ.synchronize()
        vols = [t for _, t in gmsh.model.getEntities(3)]
        tops = [
            t
            for _, t in gmsh.model.getEntities(2)
            if abs(occ.getCenterOfMass(2, t)[2] - 1.0) < 1e-9
        ]
        gmsh.model.addPhysicalGroup(3, vols, name="solid")
        gmsh.model.addPhysicalGroup(2, tops, name="top")
        left = [t for _, t in gmsh.model.getEntities(2) if abs(occ.getCenterOfMass(2, t)[0]) < 1e-9]
        gmsh.model.addPhysicalGroup(2, left, name="left")
        gmsh.option.setNumber("Mesh.MeshSizeMax", SIZE)
        if hexes:
            for _, c in gmsh.model.getEntities(1):
                gmsh.model.mesh.setTransfiniteCurve(c, DIV + 1)
            for _, f in gmsh.model.getEntities(2):
                gmsh.model.mesh.setTransfiniteSurface(f)
                gmsh.model.mesh.setRecombine(2, f)
            for v in vols:
                gmsh.model.mesh.setTransfiniteVolume(v)
        gmsh.model.mesh.generate(3)
        n = len(gmsh.model.mesh.getNodes()[0])
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path, n


def _interface_nodes(path: Path) -> int:
    """Nodes of the file on the plane x = 1 (both copies), halved: the interface's nodes."""
    import meshio

    x = meshio.read(path).points[:, 0]
    return int(np.sum(np.abs(x - 1.0) < 1e-12)) // 2


def test_unmerged_volumes_refused_with_the_count(tmp_path):
    """Two boxes meshed apart: every interface node is there twice; read_mesh refuses the
    file in one line naming the pairs (exactly the interface's nodes: a count, no tolerance),
    the two parts and the way out."""
    path, _ = _two_boxes(tmp_path / "apart.msh")
    n_iface = _interface_nodes(path)
    assert n_iface > 10
    with pytest.raises(MeshError) as err:
        read_mesh(path)
    msg = str(err.value)
    assert "\n" not in msg
    assert f"{n_iface} coincident node pairs not merged" in msg
    assert "2 parts sharing no node" in msg
    assert "merge_nodes = true" in msg


def test_merge_nodes_gives_the_fragment_mesh(tmp_path):
    """merge_nodes=True: one MeshWarning with the count; the merged mesh has the node count,
    volume (2 m^3 to round-off) and top facets of the same boxes joined by gmsh's fragment
    (gmsh meshes the shared face alike both ways: equal counts, no tolerance)."""
    apart, n_file = _two_boxes(tmp_path / "apart.msh")
    joined, _ = _two_boxes(tmp_path / "joined.msh", fragment=True)
    n_iface = _interface_nodes(apart)
    ref = read_mesh(joined)
    with pytest.warns(MeshWarning, match=rf"{n_iface} coincident node pairs merged"):
        m = read_mesh(apart, merge_nodes=True)
    assert m.n_nodes == n_file - n_iface == ref.n_nodes
    assert m.n_cells == ref.n_cells
    assert mesh_volume(m) == pytest.approx(2.0, rel=1e-12)
    assert m.facet_set("top").n_facets == ref.facet_set("top").n_facets
    assert m.facet_set("surface").n_facets == ref.facet_set("surface").n_facets
    assert connectivity_report(m.nodes, list(m.cells), _skin(m)).joined


def _skin(m):
    return check_faces(m.nodes, list(m.cells), "test")


def test_separate_parts_refused(tmp_path):
    """Two boxes 0.5 m apart: two parts, not touching; merging changes nothing."""
    path, _ = _two_boxes(tmp_path / "far.msh", second_at=(1.5, 0.0, 0.0))
    for merge in (False, True):
        with pytest.raises(MeshError, match=r"2 parts sharing no node .* and not touching"):
            read_mesh(path, merge_nodes=merge)


def test_nonconforming_interface_refused(tmp_path):
    """Tets: gmsh meshes the two copies of the interface differently, they share some node
    positions only. Refused naming the pairs; merged, the rest of the interface still lies on
    the skin (a crack), refused naming the touching facets: merging cannot join it."""
    path, _ = _two_boxes(tmp_path / "nonconf.msh", hexes=False)
    n_iface = _interface_nodes(path)
    with pytest.raises(MeshError, match=r"\d+ coincident node pairs not merged") as err:
        read_mesh(path)
    assert f"{n_iface} coincident" not in str(err.value)  # fewer than the interface's nodes
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeshWarning)
        with pytest.raises(MeshError, match=r": \d+ skin facets lying on other skin facets"):
            read_mesh(path, merge_nodes=True)


def test_shipped_and_generated_meshes_are_joined():
    """The shipped meshes and a generated rod pass the joins unchanged (no pair, one part, no
    touching facet)."""
    files = sorted(glob.glob(str(ROOT / "scenarios" / "meshes" / "*")))
    files.append(str(ROOT / "docs" / "validation" / "meshes" / "block_200um.msh"))
    assert len(files) >= 9
    for f in files:
        m = read_mesh(f)
        assert connectivity_report(m.nodes, list(m.cells), _skin(m)).joined, f
    rod = rod_mesh(RodSpec(length_m=0.1, end_a=EndShape.HEMISPHERE)).mesh
    assert connectivity_report(rod.nodes, list(rod.cells), _skin(rod)).joined


def _cantilever(path: Path, merge: bool | None):
    """The two boxes as a full-FE aluminium body clamped on ``left``, started in its sag
    under gravity (placement.sagged: a static solve at build)."""
    body = {
        "name": "beam",
        "material": "aluminium",
        "mesh_file": str(path),
        "model": {"kind": "full", "reference": "left"},
        "placement": {"sagged": True},
    }
    if merge is not None:
        body["merge_nodes"] = merge
    return scenario_from_dict(
        {
            "name": "two_boxes",
            "gravity_mps2": [0.0, 0.0, -9.81],
            "time": {"t_end_s": 1e-4, "dt_s": 1e-5, "output_dt_s": 1e-5},
            "bodies": [body],
            "supports": [{"type": "clamp", "body": "beam", "node_set": "left"}],
        }
    )


def _tip_sag(sc) -> float:
    """Vertical displacement [m] of the node at (2, 0.5, 0.5) in the built (sagged) state."""
    built = build_scenario(sc, SetupCache())
    body, state, mesh = built.system.bodies[0], built.states[0], built.info[0].mesh
    tip = int(np.argmin(np.linalg.norm(mesh.nodes - [2.0, 0.5, 0.5], axis=1)))
    return float(body.local_displacements(np.array([tip]), state.q)[0][2])


def test_scenario_merge_nodes_builds_the_joined_body(tmp_path):
    """A body's ``merge_nodes = true``: its mesh key (and so every cache entry) is another
    than the file's as read; it builds, and the sag of the clamped two-box cantilever's free
    end equals that of the same boxes joined by gmsh's fragment to round-off (rel 1e-9: the
    same mesh up to node order). Without the key the build is refused in one line; a dump
    without it holds no ``merge_nodes`` (study keys hash dumps); a rod body refuses it."""
    apart, _ = _two_boxes(tmp_path / "apart.msh")
    joined, _ = _two_boxes(tmp_path / "joined.msh", fragment=True)
    merged_sc = _cantilever(apart, True)
    assert isinstance(mesh_key(merged_sc.bodies[0]), MergedFile)
    source = mesh_source(mesh_key(merged_sc.bodies[0]))
    assert source["merge_nodes"] is True
    assert source != mesh_source(mesh_key(_cantilever(apart, None).bodies[0]))
    with pytest.warns(MeshWarning, match="25 coincident node pairs merged"):
        w_merged = _tip_sag(merged_sc)
    w_joined = _tip_sag(_cantilever(joined, None))
    assert w_joined < 0
    assert w_merged == pytest.approx(w_joined, rel=1e-9)
    with pytest.raises(MeshError, match="25 coincident node pairs not merged"):
        build_scenario(_cantilever(apart, False), SetupCache())
    assert "merge_nodes" not in _cantilever(apart, False).model_dump(mode="json")["bodies"][0]
    with pytest.raises(ScenarioError, match="merge_nodes"):
        scenario_from_dict(
            {
                "name": "rod",
                "time": {"t_end_s": 1e-4, "dt_s": 1e-5, "output_dt_s": 1e-5},
                "bodies": [{"name": "r", "material": "aluminium", "rod": ROD, "merge_nodes": True}],
            }
        )
