"""Meshes as users bring them from other tools (issue 52, item 4): an Abaqus .inp read with its
sets merged across repeated cards, its node sets and its *SURFACE cards (flexmvm.mesh.abaqus), a
Nastran .bdf and a VTU (flexmvm.mesh.io). The .inp files are written here by hand, as a
user's exporter writes them; the .bdf and .vtu by meshio. Set sizes are counts: exact."""

from __future__ import annotations

from pathlib import Path

import meshio
import numpy as np
import pytest

import flexmvm as fm
from flexmvm.errors import InputError, MeshError
from flexmvm.mesh import read_mesh
from flexmvm.mesh.io import MeshWarning

SPHERE = Path(__file__).resolve().parents[1] / "scenarios" / "meshes" / "sphere_r10_cap.msh"

N = 4  # hex8 elements per side of the block's top; two layers through its depth


def _label(i: int, j: int, k: int) -> int:
    """Node label (1-based) of grid point (i, j, k) of the block."""
    return 1 + i + (N + 1) * (j + (N + 1) * k)


def _block_lines(size=(0.04, 0.04, 0.02)) -> tuple[list[str], dict[int, list[int]]]:
    """*NODE card of a hex8 block x, y in [-20, 20] mm, z in [-20, 0] mm, and its elements
    (label -> node labels): layer k = 0 (bottom, labels 1..16), k = 1 (top, 17..32)."""
    xs = np.linspace(-size[0] / 2, size[0] / 2, N + 1)
    zs = np.linspace(-size[2], 0.0, 3)
    lines = ["*Heading", "** hand-written hex8 block", "*NODE"]
    for k in range(3):
        for j in range(N + 1):
            for i in range(N + 1):
                lines.append(f"{_label(i, j, k)}, {xs[i]:.17g}, {xs[j]:.17g}, {zs[k]:.17g}")
    elems, e = {}, 1
    for k in range(2):
        for j in range(N):
            for i in range(N):
                bottom = [_label(i, j, k), _label(i + 1, j, k), _label(i + 1, j + 1, k)]
                bottom.append(_label(i, j + 1, k))
                elems[e] = bottom + [n + (N + 1) ** 2 for n in bottom]
                e += 1
    return lines, elems


def _side_cards(elems: dict[int, list[int]]) -> list[str]:
    """``*ELSET, ELSET=side`` once per side face of the block (as gmsh writes one card per
    entity): the elements on x = -20, x = +20, y = -20, y = +20 mm (24 in all, 8 per card)."""
    out = []
    for pick in (
        lambda i, j: i == 0,
        lambda i, j: i == N - 1,
        lambda i, j: j == 0,
        lambda i, j: j == N - 1,
    ):
        ids = [e for e in elems if pick((e - 1) % N, (e - 1) // N % N)]
        out += ["*ELSET, ELSET=side", ", ".join(map(str, ids))]
    return out


def _block_inp(path, extra: list[str] = ()) -> None:
    """The block with two *ELEMENT cards (one per layer, both ELSET=EALL), the side set on
    four repeated cards, node sets (GENERATE, a list, a set of sets, NSET= on *NODE not
    used), an element-based *SURFACE on the top faces (S2 of the top layer: nodes 5-8-7-6)
    and a node-based one, keywords in mixed case with a continued keyword line."""
    lines, elems = _block_lines()
    for layer, card in (
        (0, "*ELEMENT, TYPE=C3D8, ELSET=EALL"),
        (1, "*Element, type=C3D8R, elset=EALL"),
    ):
        lines.append(card)
        for e in range(1 + 16 * layer, 17 + 16 * layer):
            lines.append(", ".join(map(str, [e, *elems[e]])))
    lines += _side_cards(elems)
    top = [_label(i, j, 2) for j in range(N + 1) for i in range(N + 1)]
    lines += [
        "*NSET, NSET=bottom, GENERATE",
        f"1, {(N + 1) ** 2}, 1",
        "*Nset, nset=TOP_N",
        ", ".join(map(str, top[:13])) + ",",
        ", ".join(map(str, top[13:])),
        "*ELSET, ELSET=ETOP, GENERATE",
        "17, 32, 1",
        "*Surface, name=TOPS,",
        " type=ELEMENT",
        "ETOP, S2",
        "*SURFACE, NAME=TOPN, TYPE=NODE",
        "TOP_N",
        "*SURFACE, NAME=BOT",
        "1, S1",
        "2, s1",
        "*SURFACE, NAME=ALL",
        "EALL",
        *extra,
    ]
    path.write_text("\n".join(lines) + "\n")


def _normals_z(mesh, name: str) -> np.ndarray:
    """z component of the right-hand normals of a facet set's quads (outward: + on top)."""
    x = mesh.nodes[mesh.facet_set(name).quads]
    return np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])[:, 2]


def test_repeated_elset_is_the_union(tmp_path):
    """``side`` on four *ELSET cards of 8 elements each holds all 24 side elements, whose
    nodes are the block's 75 less the 3 on the vertical axis x = y = 0 (in no side element),
    not the last card's 8 elements (meshio's reading, issue 52: a clamp on one face of four);
    ``EALL``, named on both *ELEMENT cards, holds all 32 elements (75 nodes)."""
    path = tmp_path / "block.inp"
    _block_inp(path)
    mesh = read_mesh(path)
    axis = np.flatnonzero(np.all(np.abs(mesh.nodes[:, :2]) < 1e-12, axis=1))
    assert len(axis) == 3
    assert mesh.node_set("side").tolist() == np.setdiff1d(np.arange(75), axis).tolist()
    assert len(mesh.node_set("EALL")) == 75


def test_node_sets_and_surfaces(tmp_path):
    """Node sets: ``bottom`` (GENERATE 1..25) the 25 nodes at z = -20 mm, ``TOP_N`` (a list
    on a continued data line) the 25 at z = 0. Surfaces, each outward: the element-based
    ``TOPS`` (S2 of the 16 top elements) and the node-based ``TOPN`` are the 16 top facets,
    ``BOT`` (S1 of elements 1 and 2, face id in either case) 2 bottom facets; the node sets
    ``TOP_N`` and ``bottom`` are surfaces too (the skin facets of their nodes: 16 each); the
    skin ``surface`` has 4 x 16 = 64 facets, as ``ALL`` (all elements named without a face:
    their faces on the skin). Counts: exact."""
    path = tmp_path / "block.inp"
    _block_inp(path)
    mesh = read_mesh(path)
    z = mesh.nodes[:, 2]
    assert mesh.node_set("bottom").tolist() == np.flatnonzero(z == -0.02).tolist()
    assert mesh.node_set("TOP_N").tolist() == np.flatnonzero(z == 0.0).tolist()
    for name, n, sign in (("TOPS", 16, 1), ("TOPN", 16, 1), ("TOP_N", 16, 1), ("BOT", 2, -1)):
        assert mesh.facet_set(name).n_facets == n, name
        assert np.all(sign * _normals_z(mesh, name) > 0), name
    assert mesh.facet_set("bottom").n_facets == 16
    assert mesh.facet_set("surface").n_facets == mesh.facet_set("ALL").n_facets == 64
    assert mesh.node_set("TOPS").tolist() == mesh.node_set("TOP_N").tolist()


def test_nset_named_like_an_elset(tmp_path):
    """An NSET and an ELSET of one name (separate name spaces in Abaqus, whose *BOUNDARY
    reads the NSET): the node set is the NSET's nodes (the 25 on the bottom), not the 72
    nodes of the side elements; both NSET cards of that name count (union of 5 + 20)."""
    path = tmp_path / "block.inp"
    _block_inp(path, ["*NSET, NSET=side, GENERATE", "1, 5", "*NSET, NSET=SIDE, GENERATE", "6, 25"])
    mesh = read_mesh(path)
    assert mesh.node_set("side").tolist() == mesh.node_set("bottom").tolist()
    assert mesh.facet_set("side").n_facets == 16  # the NSET covers the bottom's 16 faces


@pytest.mark.parametrize("etype", ["C3D4", "C3D10"])
def test_tet_face_numbers(tmp_path, etype):
    """S1..S4 of one tetrahedron are its faces 1-2-3, 1-4-2, 2-4-3, 3-4-1 (Abaqus Analysis
    User's Guide 6.14, sect. 28.1.4); a C3D10 face also holds its three mid-side nodes
    (subfacets: 4 triangles through 6 nodes). The C3D10's element line is continued."""
    pts = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    conn = [1, 2, 3, 4]
    if etype == "C3D10":
        edges = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]
        pts += [tuple((np.add(pts[a], pts[b]) / 2).tolist()) for a, b in edges]
        conn += list(range(5, 11))
    lines = ["*NODE", *(f"{k + 1}, {x}, {y}, {z}" for k, (x, y, z) in enumerate(pts))]
    row = [str(v) for v in (1, *conn)]  # an element's line continued after 8 fields
    lines += [f"*ELEMENT, TYPE={etype}", ", ".join(row[:8]) + ","] + [", ".join(row[8:])] * (
        len(row) > 8
    )
    for f in range(1, 5):
        lines += [f"*SURFACE, NAME=F{f}", f"1, S{f}"]
    path = tmp_path / "tet.inp"
    path.write_text("\n".join(lines) + "\n")
    mesh = read_mesh(path)
    corners = {1: [1, 2, 3], 2: [1, 2, 4], 3: [2, 3, 4], 4: [1, 3, 4]}
    mid = {(1, 2): 5, (2, 3): 6, (1, 3): 7, (1, 4): 8, (2, 4): 9, (3, 4): 10}
    centroid = np.mean(pts[:4], axis=0)
    for f, c in corners.items():
        fs = mesh.facet_set(f"F{f}")
        want = c + ([mid[(a, b)] for a, b in mid if a in c and b in c] if etype == "C3D10" else [])
        assert (fs.nodes + 1).tolist() == sorted(want), f
        assert fs.n_facets == (4 if etype == "C3D10" else 1)
        x = mesh.nodes[fs.tris]
        out = np.einsum(
            "ij,ij->i", np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), x[:, 0] - centroid
        )
        assert np.all(out > 0), f


@pytest.mark.parametrize(
    ("etype", "pts", "faces"),
    [
        (
            "C3D6",
            [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1)],
            {1: [1, 2, 3], 2: [4, 5, 6], 3: [1, 2, 4, 5], 4: [2, 3, 5, 6], 5: [1, 3, 4, 6]},
        ),
        (
            "C3D8",
            [
                (0, 0, 0),
                (1, 0, 0),
                (1, 1, 0),
                (0, 1, 0),
                (0, 0, 1),
                (1, 0, 1),
                (1, 1, 1),
                (0, 1, 1),
            ],
            {1: [1, 2, 3, 4], 2: [5, 6, 7, 8], 3: [1, 2, 5, 6], 4: [2, 3, 6, 7], 5: [3, 4, 7, 8]}
            | {6: [1, 4, 5, 8]},
        ),
    ],
)
def test_wedge_and_hex_face_numbers(tmp_path, etype, pts, faces):
    """S1..S5 of a C3D6 are its faces 1-2-3, 4-6-5, 1-4-5-2, 2-5-6-3, 3-6-4-1 and S1..S6 of a
    C3D8 its faces 1-2-3-4, 5-8-7-6, 1-5-6-2, 2-6-7-3, 3-7-8-4, 4-8-5-1 (Abaqus Analysis
    User's Guide 6.14, sect. 28.1.4), each one facet, oriented outward."""
    lines = ["*NODE", *(f"{k + 1}, {x}, {y}, {z}" for k, (x, y, z) in enumerate(pts))]
    lines += [f"*ELEMENT, TYPE={etype}", ", ".join(map(str, [1, *range(1, len(pts) + 1)]))]
    for f in faces:
        lines += [f"*SURFACE, NAME=F{f}", f"1, S{f}"]
    path = tmp_path / "one.inp"
    path.write_text("\n".join(lines) + "\n")
    mesh = read_mesh(path)
    centroid = np.mean(pts, axis=0)
    for f, want in faces.items():
        fs = mesh.facet_set(f"F{f}")
        assert (fs.nodes + 1).tolist() == want and fs.n_facets == 1, f
        x = mesh.nodes[fs.quads[0] if len(fs.quads) else fs.tris[0]]
        assert np.cross(x[1] - x[0], x[2] - x[0]) @ (x.mean(axis=0) - centroid) > 0, f


def test_sets_and_node_cards_meshio_misreads(tmp_path):
    """Two *NODE cards (meshio keeps the last only), a set naming other sets, GENERATE without
    its step and on two lines (meshio refuses both): read whole. A *SURFACE of another TYPE
    is skipped with a one-line MeshWarning."""
    path = tmp_path / "block.inp"
    _block_inp(
        path,
        ["*NSET, NSET=both", "bottom, TOP_N", "*ELSET, ELSET=corners, GENERATE", "1, 4", "13, 16"]
        + ["*SURFACE, NAME=RIGID, TYPE=SEGMENTS", "START, 0, 0"],
    )
    text = path.read_text().replace(f"\n{_label(0, 0, 1)}, ", f"\n*NODE\n{_label(0, 0, 1)}, ", 1)
    path.write_text(text)
    with pytest.warns(MeshWarning, match=r"\*SURFACE 'RIGID' of TYPE=SEGMENTS not read"):
        mesh = read_mesh(path)
    assert mesh.n_nodes == 75 and mesh.n_cells == 32
    assert len(mesh.node_set("both")) == 50
    assert len(mesh.node_set("corners")) == 2 * (2 * 5) * 2  # rows y = -20, +20 mm, layer 1


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        (["*ELSET, ELSET=bad", "1, 99"], r"\*ELSET 'bad' names element 99, which no \*ELEMENT"),
        (["*NSET, NSET=bad", "TOPZ"], r"\*NSET 'bad' names 'TOPZ', which no earlier \*NSET"),
        (["*SURFACE, NAME=bad", "EZ, S2"], r"\*SURFACE 'bad' names 'EZ', which no earlier \*ELSET"),
        (["*SURFACE, NAME=bad", "1, S7"], r"\*SURFACE 'bad': face S7 of a hexahedron .*S1..S6"),
        (["*SURFACE, NAME=bad", "1, S2"], r"\*SURFACE 'bad': 1 face\(s\) inside the body"),
        (["*NSET, NSET=bad, GENERATE", "1, x"], r"GENERATE: line .*first, last\[, step\]"),
    ],
)
def test_bad_cards_are_one_line(tmp_path, extra, match):
    """A label or set the file does not define, a face the element lacks or inside the body,
    a GENERATE line that is no range: one-line MeshErrors naming the file and the card."""
    path = tmp_path / "block.inp"
    _block_inp(path, extra)
    with pytest.raises(MeshError, match=match) as err:
        read_mesh(path)
    assert "block.inp" in str(err.value) and "\n" not in str(err.value)


def _scenario(inp: Path, slave: str, clamp: str) -> dict:
    """A rigid steel sphere (R 10 mm, 0.5 m/s) onto the middle of the block's top, the block
    clamped on a node set, full FE, 10 us in steps of 0.5 us."""
    return {
        "name": "inp_block",
        "time": {"t_end_s": 10e-6, "dt_s": 0.5e-6, "output_dt_s": 1e-6},
        "bodies": [
            {
                "name": "ball",
                "mesh_file": str(SPHERE),
                "model": {"kind": "rigid"},
                "material": {"E_pa": 210e9, "nu": 0.3, "rho_kg_m3": 7850.0},
                "placement": {"position_m": [0.0, 0.0, 0.010], "velocity_mps": [0.0, 0.0, -0.5]},
            },
            {
                "name": "block",
                "mesh_file": str(inp),
                "material": "aluminium",
                "model": {"kind": "full"},
            },
        ],
        "supports": [{"type": "clamp", "body": "block", "node_set": clamp}],
        "contacts": [{"slave": f"block.{slave}", "master": "ball.front", "law": "position"}],
    }


def test_sphere_onto_a_surface_card(tmp_path):
    """A *SURFACE card is a contact surface and an NSET a clamp: the sphere's pole meets the
    top's centre node at t = 0 and the contact acts (its force > 1 N; measured 1.89 kN, the
    impact of the coarse face's node mass at 0.5 m/s within the first steps, far above
    Hertz's ~100 N at 5 um: the test asks only that contact acts, zero would mean none). The
    node-based *SURFACE of the same facets gives the same run (force equal to 1e-12: the same
    facets, the same arithmetic). A surface or node set the file lacks: one-line InputError
    naming the mesh file and listing its sets (a node set that covers no skin face said to
    be one, a name in another case than the file's pointed at)."""
    path = tmp_path / "block.inp"
    _block_inp(path)
    res = fm.run(fm.scenario_from_dict(_scenario(path, "TOPS", "bottom")))
    assert res.summary["status"] == "completed"
    assert res.summary["max_contact_force_interval_mean_N"] > 1.0, res.summary
    by_nodes = fm.run(fm.scenario_from_dict(_scenario(path, "TOPN", "bottom")))
    assert by_nodes.summary["max_contact_force_interval_mean_N"] == pytest.approx(
        res.summary["max_contact_force_interval_mean_N"], rel=1e-12
    )
    with pytest.raises(
        InputError, match=r"unknown surface 'TOPX'; known: .*TOPS.*; mesh file '.*block.inp'$"
    ):
        fm.run(fm.scenario_from_dict(_scenario(path, "TOPX", "bottom")))
    with pytest.raises(InputError, match=r"known: .*\(did you mean 'TOPS'\? names are matched"):
        fm.run(fm.scenario_from_dict(_scenario(path, "tops", "bottom")))
    one = tmp_path / "one.inp"
    _block_inp(one, ["*NSET, NSET=one", "1"])
    with pytest.raises(InputError, match=r"'one' is a node set covering no skin face") as err:
        fm.run(fm.scenario_from_dict(_scenario(one, "one", "bottom")))
    assert "\n" not in str(err.value)
    with pytest.raises(
        InputError, match=r"supports\[0\].node_set: unknown node set 'BOTX'; known: .*bottom"
    ):
        fm.run(fm.scenario_from_dict(_scenario(path, "TOPS", "BOTX")))


def _meshio_block() -> meshio.Mesh:
    """The hex8 block as a meshio mesh (for .bdf and .vtu)."""
    lines, elems = _block_lines()
    pts = np.array([[float(v) for v in ln.split(",")[1:]] for ln in lines[3:]])
    return meshio.Mesh(pts, [("hexahedron", np.array(list(elems.values())) - 1)])


def _side_quads() -> list[np.ndarray]:
    """Quads (node ids, 0-based) of the block's four side faces, one array per face (as gmsh
    meshes one surface entity per face): 4 x 2 quads each."""
    out = []
    for fixed in ((0, None), (N, None), (None, 0), (None, N)):
        quads = []
        for a in range(N):
            for k in range(2):
                ij = [(a, k), (a + 1, k), (a + 1, k + 1), (a, k + 1)]
                quads.append(
                    [
                        _label(*((fixed[0], t, z) if fixed[0] is not None else (t, fixed[1], z)))
                        - 1
                        for t, z in ij
                    ]
                )
        out.append(np.array(quads))
    return out


def test_meshio_written_inp_keeps_every_block_of_a_set(tmp_path):
    """The issue's own file: meshio writes a physical surface ``side`` of four gmsh entities
    (four quad blocks) as four ``*ELSET, ELSET=side`` cards; read back, ``side`` is the 32
    quads of all four faces (main kept the last card: 8), and its node set the 48 nodes
    on the sides (16 around each of the 3 levels)."""
    m = _meshio_block()
    quads = _side_quads()
    m.cells = [m.cells[0], *(meshio.CellBlock("quad", q) for q in quads)]
    m.cell_sets = {"side": [np.zeros(0, dtype=int), *(np.arange(len(q)) for q in quads)]}
    path = tmp_path / "meshio.inp"
    meshio.write(path, m)
    assert path.read_text().count("*ELSET, ELSET=side") == 4
    mesh = read_mesh(path)
    assert mesh.facet_set("side").n_facets == 32
    x, y = mesh.nodes[:, 0], mesh.nodes[:, 1]
    on_side = np.isclose(np.abs(x), 0.02) | np.isclose(np.abs(y), 0.02)
    assert mesh.node_set("side").tolist() == np.flatnonzero(on_side).tolist()
    assert len(mesh.node_set("side")) == 48


def test_nastran_bdf_gives_the_skin_only(tmp_path):
    """meshio reads a .bdf's grid points and elements; the bulk data names no set (property
    ids are not names), so the mesh has the skin ``surface`` only: a one-line MeshWarning says
    so, and asking for another set lists it."""
    path = tmp_path / "block.bdf"
    meshio.write(path, _meshio_block())
    with pytest.warns(MeshWarning, match=r"block.bdf': a Nastran file gives no named sets, only"):
        mesh = read_mesh(path)
    assert mesh.n_cells == 32 and list(mesh.facet_sets) == ["surface"]
    assert list(mesh.node_sets) == ["surface"]
    with pytest.raises(MeshError, match="unknown surface 'top'; known: surface$"):
        mesh.facet_set("top")


def test_vtu_masks_are_node_sets_and_surfaces(tmp_path):
    """A VTU's point-data masks ``node_set:<name>`` are node sets and, where they cover skin
    facets, surfaces (``top``: 25 nodes, 16 facets); a single node (``apex``) stays a node set
    only; cell-data arrays (here ``material``) are field values, not groups."""
    m = _meshio_block()
    top = (m.points[:, 2] == 0.0).astype(np.uint8)
    apex = np.zeros(len(m.points), dtype=np.uint8)
    apex[0] = 1
    m.point_data = {"node_set:top": top, "node_set:apex": apex}
    m.cell_data = {"material": [np.ones(32, dtype=np.int32)]}
    path = tmp_path / "block.vtu"
    meshio.write(path, m)
    mesh = read_mesh(path)
    assert len(mesh.node_set("top")) == 25 and mesh.facet_set("top").n_facets == 16
    assert np.all(_normals_z(mesh, "top") > 0)
    assert mesh.node_set("apex").tolist() == [0] and "apex" not in mesh.facet_sets
    assert "material" not in mesh.node_sets and "material" not in mesh.facet_sets
