"""Mesh files through meshio: read volume meshes (with their named groups), write atomically.

Node sets survive a write/read round trip as point-data masks named ``node_set:<name>``;
facet sets are not written (VTU has no named surfaces); gmsh physical groups and other
formats' cell sets are read (flexmvm.mesh.groups), the outer skin is always ``surface``.
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
import warnings
from collections.abc import Mapping
from pathlib import Path

import meshio
import numpy as np

from flexmvm.errors import InputError, MeshError
from flexmvm.mesh.abaqus import (
    InpSets,
    geometry_text,
    read_cards,
    read_inp_sets,
    surface_rows,
)
from flexmvm.mesh.connectivity import joined_cells
from flexmvm.mesh.groups import (
    FILE_NUMBERING,
    NODE_SET_PREFIX,
    Group,
    add_file_sets,
    cell_dim,
    file_cell_numbers,
    group_nodes,
    read_groups,
)
from flexmvm.mesh.integrity import duplicate_cells, face_table, skin
from flexmvm.mesh.mesh import CellBlock, CellType, FacetSet, Mesh
from flexmvm.mesh.subfacets import QuadraticFaces

# The mode a plain open() gives a new file (0o666 minus the umask, read once at import).
_UMASK = os.umask(0)
os.umask(_UMASK)
_FILE_MODE = 0o666 & ~_UMASK

_VOLUME_TYPES = {ct.value: ct for ct in CellType}
_SURFACE_CORNERS = {"triangle": 3, "triangle6": 3, "quad": 4, "quad8": 4, "quad9": 4}

#: Name of the facet set and node set of the outer skin that read_mesh always adds.
SKIN = "surface"

#: meshio's Nastran suffixes, and what read_mesh says of such a file (a MeshWarning): meshio
#: reads its GRID points and elements only (property ids are no names), so no set but the skin.
NASTRAN_SUFFIXES = (".bdf", ".nas", ".fem")
NASTRAN_NOTE = (
    f"a Nastran file gives no named sets, only the skin {SKIN!r}; select nodes by a region "
    "(box, ball, node_ids) or bring the mesh as .inp or .msh with its sets"
)


class MeshWarning(UserWarning):
    """A mesh file was read with a change the user should know of (nodes dropped)."""


def _read(path: Path, inp_text: str | None = None) -> meshio.Mesh:
    """meshio's reading of ``path`` (of ``inp_text``, an .inp's geometry, if given)."""
    if not path.is_file():
        raise MeshError(f"mesh file {str(path)!r} does not exist; expected a readable mesh file")
    log = io.StringIO()
    try:
        with contextlib.redirect_stdout(log), contextlib.redirect_stderr(log):
            if inp_text is not None:
                return meshio.read(io.StringIO(inp_text), file_format="abaqus")
            return meshio.read(path)
    except (Exception, SystemExit) as exc:  # meshio may even sys.exit() on a bad file
        text = log.getvalue() if isinstance(exc, SystemExit) else str(exc)
        lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
        detail = " ".join(lines)[:300] if lines else type(exc).__name__
        raise MeshError(f"cannot read mesh file {str(path)!r}: {detail}") from exc


def _volume_blocks(m: meshio.Mesh, where: str) -> list[tuple[CellBlock, np.ndarray, np.ndarray]]:
    """Volume cells grouped by type (meshio may split a type over several blocks), each with
    the gmsh physical tag of every cell (-1 where the file gives none) and its element number
    in the file (numbering.file_cell_numbers: 1-based over all the file's elements)."""
    tags = m.cell_data.get("gmsh:physical")
    if tags is not None and len(tags) != len(m.cells):  # meshio leaves untagged blocks out
        tags = None
    numbers = file_cell_numbers(m)
    by_type: dict[CellType, list[tuple[np.ndarray, np.ndarray, np.ndarray]]] = {}
    for k, block in enumerate(m.cells):
        if block.type in _VOLUME_TYPES:
            data = np.asarray(block.data)
            tag = (
                np.asarray(tags[k], dtype=np.int64)
                if tags is not None
                else np.full(len(data), -1, dtype=np.int64)
            )
            by_type.setdefault(_VOLUME_TYPES[block.type], []).append((data, tag, numbers[k]))
        elif cell_dim(block.type) == 3:
            raise MeshError(
                f"{where} has unsupported cell type {block.type!r}; expected "
                f"{', '.join(_VOLUME_TYPES)}"
            )
    if not by_type:
        found = ", ".join(sorted({b.type for b in m.cells})) or "none"
        raise MeshError(f"{where} has no volume cells (found: {found})")
    return [
        (
            CellBlock(ct, np.concatenate([d for d, _, _ in parts])),
            np.concatenate([t for _, t, _ in parts]),
            np.concatenate([n for _, _, n in parts]),
        )
        for ct, parts in by_type.items()
    ]


def _drop_group_copies(
    blocks: list[tuple[CellBlock, np.ndarray, np.ndarray]], where: str
) -> tuple[list[CellBlock], np.ndarray]:
    """The cells with every element once, and the file number of each kept cell (running
    order over the blocks).

    gmsh's MSH 2 format writes an element once per physical volume it belongs to, so a mesh
    whose volume groups overlap holds copies of one element, each with another physical tag:
    the element is kept once (its copies are the same element; each group still names it).
    Any other repetition of a node set is refused: copies with no physical tag or the same tag
    (a mesh written twice, a merge gone wrong) would double the cell's stiffness and mass, and
    copies whose node order differs (another orientation or midside numbering) leave no way to
    tell which one is meant. MeshError (one line) names both elements and their nodes as the
    file numbers them (groups.FILE_NUMBERING).
    """
    out, numbers = [], []
    for block, tags, number in blocks:
        keep = np.ones(len(block.connectivity), dtype=bool)
        for cell_type, ids in duplicate_cells([block]):
            conn, t = block.connectivity[ids], tags[ids]
            a, b = int(number[ids[0]]), int(number[ids[1]])
            same_order = bool(np.all(conn == conn[0]))
            if not same_order:
                raise MeshError(
                    f"{where}: {cell_type.value} elements {a} and {b} have the same nodes in a "
                    f"different order ({(conn[0] + 1).tolist()} vs {(conn[1] + 1).tolist()}; "
                    f"{FILE_NUMBERING}); expected each element once"
                )
            if np.any(t < 0) or len(np.unique(t)) != len(t):
                why = (
                    "no physical group" if np.any(t < 0) else f"both in physical group {int(t[0])}"
                )
                raise MeshError(
                    f"{where}: {cell_type.value} element {a} is written {len(ids)} times (also "
                    f"element {b}; {why}; {FILE_NUMBERING}); expected each element once (a "
                    f"repeated cell doubles its stiffness and mass)"
                )
            keep[ids[1:]] = False
        out.append(CellBlock(block.cell_type, block.connectivity[keep]))
        numbers.append(number[keep])
    return out, np.concatenate(numbers)


def _orient_outward(
    facets: np.ndarray, faces: tuple[np.ndarray, np.ndarray], name: str, where: str
) -> np.ndarray:
    """Facets (n, 3|4) in the outward order of the cell face they match (integrity.face_table's
    keys and faces); MeshError if a facet is no cell face."""
    keys, oriented = faces
    k = np.full((len(facets), 4), -1, dtype=np.int64)
    k[:, : facets.shape[1]] = facets
    k = np.unique(np.sort(k, axis=1), axis=0)
    _, inv = np.unique(np.vstack([keys, k]), axis=0, return_inverse=True)
    inv = inv.ravel()
    owner = np.full(inv.max() + 1, -1, dtype=np.int64)
    owner[inv[: len(keys)]] = np.arange(len(keys))
    match = owner[inv[len(keys) :]]
    if np.any(match < 0):
        raise MeshError(
            f"{where}: surface {name!r}: {int(np.sum(match < 0))} facet(s) are not faces of any "
            "volume cell; expected boundary facets of the volume mesh"
        )
    return oriented[match, : facets.shape[1]]


def _facet_set(
    m: meshio.Mesh, group: Group, new_id: np.ndarray, faces, quadratic: QuadraticFaces, where: str
) -> FacetSet:
    """A dim-2 group's facets (renumbered), once each, outward; the faces of quadratic cells
    as linear sub-facets through all their nodes (mesh/subfacets.py)."""
    by_kind: dict[int, list[np.ndarray]] = {3: [], 4: []}
    for k, idx in group.members:
        n_corner = _SURFACE_CORNERS.get(m.cells[k].type)
        if n_corner is None:
            raise MeshError(
                f"{where}: surface {group.name!r} has {m.cells[k].type!r} cells; "
                f"expected {', '.join(_SURFACE_CORNERS)}"
            )
        mapped = new_id[np.asarray(m.cells[k].data)[idx][:, :n_corner]]
        if np.any(mapped < 0):
            raise MeshError(f"{where}: surface {group.name!r} uses nodes of no volume cell")
        by_kind[n_corner].append(mapped)
    out = {
        n: (
            _orient_outward(np.vstack(parts), faces, group.name, where)
            if parts
            else np.zeros((0, n), dtype=np.int64)
        )
        for n, parts in by_kind.items()
    }
    return quadratic.split(FacetSet(quads=out[4], tris=out[3]))


def _named_sets(
    m: meshio.Mesh, new_id: np.ndarray, faces, quadratic: QuadraticFaces, where: str
) -> tuple[dict[str, np.ndarray], dict[str, FacetSet]]:
    """Node sets and facet sets of the file's groups (groups.read_groups): a surface group
    gives a facet set and the node set of its facets' nodes (mid-side nodes included), a
    group of volume, line or point cells the node set of its nodes, an empty group an empty
    set of each kind."""
    node_sets: dict[str, np.ndarray] = {}
    facet_sets: dict[str, FacetSet] = {}
    for group in read_groups(m):
        if group.dim == 2 or group.empty:
            fs = _facet_set(m, group, new_id, faces, quadratic, where)
            facet_sets[group.name] = fs
            node_sets[group.name] = fs.nodes
        else:
            ids = new_id[group_nodes(m, group)]
            node_sets[group.name] = ids[ids >= 0]
    return node_sets, facet_sets


def _renumbered(
    m: meshio.Mesh, blocks: list[CellBlock], where: str
) -> tuple[np.ndarray, list[CellBlock], np.ndarray]:
    """Nodes used by a volume cell (in file order), the blocks renumbered to them, and the map
    file id -> new id (-1: unused). The unused nodes are stated in a MeshWarning."""
    n_points = len(m.points)
    for b in blocks:
        c = b.connectivity
        if c.size and (c.min() < 0 or c.max() >= n_points):
            bad = int(c.min()) if c.min() < 0 else int(c.max())
            raise MeshError(
                f"{where}: {b.cell_type.value} cells refer to node {bad}; expected "
                f"node ids 0..{n_points - 1}"
            )
    used = np.unique(np.concatenate([b.connectivity.ravel() for b in blocks]))
    if len(used) < n_points:
        unused = np.setdiff1d(np.arange(n_points), used)
        listed = ", ".join(map(str, unused[:5].tolist())) + (", ..." if len(unused) > 5 else "")
        warnings.warn(
            f"{where}: {len(unused)} node(s) used by no volume cell dropped "
            f"(file ids {listed}); the rest renumbered in file order",
            MeshWarning,
            stacklevel=3,
        )
    new_id = np.full(n_points, -1, dtype=np.int64)
    new_id[used] = np.arange(len(used))
    nodes = np.asarray(m.points, dtype=float)[used]
    if nodes.shape[1] == 2:
        nodes = np.column_stack([nodes, np.zeros(len(nodes))])
    return nodes, [CellBlock(b.cell_type, new_id[b.connectivity]) for b in blocks], new_id


def _read_file(path: Path, where: str) -> tuple[meshio.Mesh, InpSets | None]:
    """meshio's reading of ``path``; for an .inp its nodes and elements, with its sets and
    surfaces read by mesh/abaqus.py (meshio's cell and point sets replaced by them). A
    MeshWarning for a *SURFACE type skipped, and for a Nastran file (NASTRAN_NOTE)."""
    inp = None
    if path.suffix.lower() == ".inp" and path.is_file():
        cards = read_cards(path, where)
        m = _read(path, geometry_text(cards))
        inp = read_inp_sets(cards, m, where)
        m.cell_sets, m.point_sets = inp.cell_sets(m), dict(inp.node_sets)
        for text in inp.skipped:
            warnings.warn(f"{where}: {text}", MeshWarning, stacklevel=3)
    else:
        m = _read(path)
    if path.suffix.lower() in NASTRAN_SUFFIXES:
        warnings.warn(f"{where}: {NASTRAN_NOTE}", MeshWarning, stacklevel=3)
    return m, inp


def read_mesh(
    path: str | os.PathLike,
    node_sets: Mapping[str, np.ndarray] | None = None,
    *,
    merge_nodes: bool = False,
) -> Mesh:
    """Read a volume mesh with meshio and check it: quality, duplicates, faces, skin.

    Volume cells: tetra, tetra10, hexahedron, hexahedron27, wedge. Named groups (gmsh physical
    groups, other formats' cell sets: flexmvm.mesh.groups) become sets by name: a surface group
    a facet set (oriented outward) and the node set of its nodes, a volume, line or point
    group the node set of its nodes; an element in two groups is in both; an empty group gives
    an empty set (Mesh.node_set/facet_set say "empty"). meshio point sets and point-data masks
    ``node_set:<name>`` (see write_mesh) become node sets, and surfaces too where they cover
    skin faces (the faces whose corners are all in the set). An Abaqus .inp's sets and
    *SURFACE cards are read by mesh/abaqus.py (a set on repeated cards is their union: a set
    read twice never shrinks; an NSET is the node set of its name, an ELSET of the same name
    gives its elements' nodes otherwise). A Nastran file names no set (a MeshWarning says so);
    VTU cell data are field values, not groups. node_sets: extra
    name -> node ids in the file's numbering. The outer skin (faces of one cell) is always the facet set and node
    set ``surface``; a file group of that name must be that skin. The faces of quadratic cells
    (tetra10, hexahedron27) become linear sub-facets through all their nodes, mid-side nodes
    included (mesh/subfacets.py): 4 triangles per 6-node triangle, 4 quads per 9-node quad.

    Checks, each a one-line MeshError naming the file: missing or unreadable file, no volume
    cells or an unsupported volume type, a node id out of range, an element written twice
    (_drop_group_copies: kept once when the copies belong to different gmsh physical volumes,
    refused otherwise), an inverted or degenerate cell (quality.check_quality: an inconsistently
    oriented cell is refused, not repaired: which nodes to swap is a guess), a face shared by
    more than two cells or by two cells on the same side of it (integrity.check_faces), a mesh
    that is not one joined body (mesh/connectivity.py: coincident nodes not merged, parts that
    share no node, skin facets lying on each other). Elements and nodes are named as the file
    numbers them (groups.FILE_NUMBERING). Nodes used by no volume cell are dropped, the rest
    renumbered in order, and a MeshWarning says how many. ``merge_nodes``: merge coincident
    nodes instead of refusing them (cells renumbered, sets kept; a MeshWarning gives the count).
    """
    path = Path(path)
    where = f"mesh file {str(path)!r}"
    m, inp = _read_file(path, where)
    blocks, cell_no = _drop_group_copies(_volume_blocks(m, where), where)
    nodes, blocks, new_id = _renumbered(m, blocks, where)
    nodes, blocks, new_id, boundary, merged = joined_cells(
        nodes, blocks, new_id, cell_no, where, merge_nodes
    )
    if merged:
        warnings.warn(
            f"{where}: {merged} coincident node pairs merged (merge_nodes); "
            f"{len(nodes)} nodes remain",
            MeshWarning,
            stacklevel=2,
        )
    keys, faces, _, _ = face_table(nodes, blocks)
    quadratic = QuadraticFaces(blocks)
    sets, facet_sets = _named_sets(m, new_id, (keys, faces), quadratic, where)
    surface = quadratic.split(skin(boundary))
    if SKIN in facet_sets and not _same_facets(facet_sets[SKIN], surface):
        raise MeshError(
            f"{where}: group {SKIN!r} is not the outer skin; expected the name "
            f"{SKIN!r} for the whole boundary only (rename the group)"
        )
    facet_sets[SKIN], sets[SKIN] = surface, surface.nodes
    rows = surface_rows(m, inp, new_id, boundary, where) if inp is not None else {}
    add_file_sets(m, rows, (new_id, boundary, quadratic), sets, facet_sets)
    for name, ids in (node_sets or {}).items():
        ids = np.asarray(ids, dtype=np.int64)
        if ids.size and (ids.min() < 0 or ids.max() >= len(m.points)):
            raise MeshError(
                f"node set {name!r} refers to nodes outside {str(path)!r} (0..{len(m.points) - 1})"
            )
        sets[name] = new_id[ids]
    sets = {k: v[v >= 0] for k, v in sets.items()}
    return Mesh(nodes=nodes, cells=tuple(blocks), node_sets=sets, facet_sets=facet_sets)


def _same_facets(a: FacetSet, b: FacetSet) -> bool:
    """Whether two facet sets hold the same facets (as node sets, whatever their order)."""

    def keys(fs: FacetSet) -> np.ndarray:
        k = np.full((fs.n_facets, 4), -1, dtype=np.int64)
        k[: len(fs.quads)] = fs.quads
        k[len(fs.quads) :, :3] = fs.tris
        return np.unique(np.sort(k, axis=1), axis=0)

    ka, kb = keys(a), keys(b)
    return ka.shape == kb.shape and bool(np.all(ka == kb))


def _cell_data_blocks(mesh: Mesh, cell_data: Mapping[str, np.ndarray]) -> dict[str, list]:
    """Split name -> (n_cells, ...) arrays (cells in block order) into meshio's per-block lists."""
    splits = np.cumsum([len(b.connectivity) for b in mesh.cells])[:-1]
    out = {}
    for name, values in cell_data.items():
        values = np.asarray(values)
        if len(values) != mesh.n_cells:
            raise InputError(
                f"cell data {name!r} has {len(values)} rows; expected {mesh.n_cells} (one per cell)"
            )
        out[name] = np.split(values, splits)
    return out


def write_mesh(
    path: str | os.PathLike,
    mesh: Mesh,
    point_data: Mapping[str, np.ndarray] | None = None,
    cell_data: Mapping[str, np.ndarray] | None = None,
) -> None:
    """Write a mesh with meshio (format from the suffix, e.g. .vtu for ParaView), atomically.

    point_data: name -> (n_nodes, ...) array; cell_data: name -> (n_cells, ...) array with cells
    in block order. Node sets are added as uint8 point-data masks ``node_set:<name>``. The file
    is written to a temporary file in the same directory and renamed over ``path``. Raises
    InputError for data of the wrong length, MeshError if meshio cannot write the file.
    """
    path = Path(path)
    pdata = {}
    for name, values in (point_data or {}).items():
        values = np.asarray(values)
        if len(values) != mesh.n_nodes:
            raise InputError(
                f"point data {name!r} has {len(values)} rows; expected {mesh.n_nodes} (one per node)"
            )
        pdata[name] = values
    for name, ids in mesh.node_sets.items():
        mask = np.zeros(mesh.n_nodes, dtype=np.uint8)
        mask[ids] = 1
        pdata[NODE_SET_PREFIX + name] = mask
    out = meshio.Mesh(
        mesh.nodes,
        [(b.cell_type.value, b.connectivity) for b in mesh.cells],
        point_data=pdata,
        cell_data=_cell_data_blocks(mesh, cell_data or {}),
    )
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=path.suffix)
    except OSError as exc:
        raise MeshError(
            f"cannot write mesh file {str(path)!r}: directory {str(path.parent)!r} "
            f"is not writable ({exc.strerror or type(exc).__name__})"
        ) from None
    try:
        os.fchmod(fd, _FILE_MODE)  # as open() would have created it, not mkstemp's 0o600
    finally:
        os.close(fd)
    try:
        meshio.write(tmp, out)
        os.replace(tmp, path)
    except Exception as exc:
        Path(tmp).unlink(missing_ok=True)
        detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise MeshError(f"cannot write mesh file {str(path)!r}: {detail}") from exc
