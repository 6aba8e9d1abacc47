"""Mesh files through meshio: read volume meshes (with gmsh surface groups), write atomically.

Node sets survive a write/read round trip as point-data masks named ``node_set:<name>``;
facet sets are not written (VTU has no named surfaces); gmsh physical surface groups are read.
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path

import meshio
import numpy as np

from flexmvm.errors import InputError, MeshError
from flexmvm.mesh.mesh import CellBlock, CellType, FacetSet, Mesh
from flexmvm.mesh.quality import check_quality

# The mode a plain open() gives a new file (0o666 minus the umask, read once at import).
_UMASK = os.umask(0)
os.umask(_UMASK)
_FILE_MODE = 0o666 & ~_UMASK

NODE_SET_PREFIX = "node_set:"

_VOLUME_TYPES = {ct.value: ct for ct in CellType}
_SURFACE_CORNERS = {"triangle": 3, "triangle6": 3, "quad": 4, "quad8": 4, "quad9": 4}
_LOWER_DIM_PREFIXES = ("vertex", "line", "triangle", "quad", "polygon")

# Corner faces of each volume type (node-local ids), oriented outward for a valid cell.
_FACES: dict[CellType, list[list[int]]] = {
    CellType.TET4: [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    CellType.HEX8: [
        [0, 3, 2, 1],
        [4, 5, 6, 7],
        [0, 1, 5, 4],
        [1, 2, 6, 5],
        [2, 3, 7, 6],
        [0, 4, 7, 3],
    ],
    CellType.WEDGE6: [[0, 2, 1], [3, 4, 5], [0, 1, 4, 3], [1, 2, 5, 4], [0, 3, 5, 2]],
}
_FACES[CellType.TET10] = _FACES[CellType.TET4]
_FACES[CellType.HEX27] = _FACES[CellType.HEX8]


def _read(path: Path) -> meshio.Mesh:
    if not path.is_file():
        raise MeshError(f"mesh file {str(path)!r} does not exist; expected a readable mesh file")
    log = io.StringIO()
    try:
        with contextlib.redirect_stdout(log), contextlib.redirect_stderr(log):
            return meshio.read(path)
    except (Exception, SystemExit) as exc:  # meshio may even sys.exit() on a bad file
        text = log.getvalue() if isinstance(exc, SystemExit) else str(exc)
        lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
        detail = " ".join(lines)[:300] if lines else type(exc).__name__
        raise MeshError(f"cannot read mesh file {str(path)!r}: {detail}") from exc


def _volume_blocks(m: meshio.Mesh, path: Path) -> list[CellBlock]:
    """Volume cells grouped by type (meshio may split a type over several blocks)."""
    by_type: dict[CellType, list[np.ndarray]] = {}
    for block in m.cells:
        if block.type in _VOLUME_TYPES:
            by_type.setdefault(_VOLUME_TYPES[block.type], []).append(np.asarray(block.data))
        elif not block.type.startswith(_LOWER_DIM_PREFIXES):
            raise MeshError(
                f"mesh file {str(path)!r} has unsupported cell type {block.type!r}; expected "
                f"{', '.join(_VOLUME_TYPES)}"
            )
    if not by_type:
        found = ", ".join(sorted({b.type for b in m.cells})) or "none"
        raise MeshError(f"mesh file {str(path)!r} has no volume cells (found: {found})")
    return [CellBlock(ct, np.concatenate(parts)) for ct, parts in by_type.items()]


def _surface_groups(m: meshio.Mesh) -> dict[str, list[np.ndarray]]:
    """gmsh physical surface groups: name -> corner-node facets (file numbering)."""
    tags = m.cell_data.get("gmsh:physical")
    if tags is None:
        return {}
    names = {int(v[0]): k for k, v in m.field_data.items() if len(v) >= 2 and int(v[1]) == 2}
    groups: dict[str, list[np.ndarray]] = {}
    for block, block_tags in zip(m.cells, tags):
        n_corner = _SURFACE_CORNERS.get(block.type)
        if n_corner is None:
            continue
        data = np.asarray(block.data)[:, :n_corner]
        block_tags = np.asarray(block_tags)
        for tag, name in names.items():
            sel = block_tags == tag
            if np.any(sel):
                groups.setdefault(name, []).append(data[sel])
    return groups


def _face_table(nodes: np.ndarray, blocks: list[CellBlock]) -> tuple[np.ndarray, np.ndarray]:
    """All cell faces as sorted keys (F, 4), -1 padded, and the owning cell centroids (F, 3)."""
    keys, cents = [], []
    for block in blocks:
        conn = block.connectivity
        centroid = nodes[conn].mean(axis=1)
        for face in _FACES[block.cell_type]:
            k = np.full((len(conn), 4), -1, dtype=np.int64)
            k[:, : len(face)] = conn[:, face]
            keys.append(np.sort(k, axis=1))
            cents.append(centroid)
    return np.vstack(keys), np.vstack(cents)


def _orient_outward(
    nodes: np.ndarray, facets: np.ndarray, keys: np.ndarray, cents: np.ndarray, name: str
) -> np.ndarray:
    """Facets (n, 3|4) reordered so their right-hand normals point out of their owning cell."""
    k = np.full((len(facets), 4), -1, dtype=np.int64)
    k[:, : facets.shape[1]] = facets
    k = np.sort(k, axis=1)
    _, inv = np.unique(np.vstack([keys, k]), axis=0, return_inverse=True)
    inv = inv.ravel()
    owner = np.full(inv.max() + 1, -1, dtype=np.int64)
    owner[inv[: len(keys)]] = np.arange(len(keys))
    match = owner[inv[len(keys) :]]
    if np.any(match < 0):
        raise MeshError(
            f"surface {name!r}: {int(np.sum(match < 0))} facet(s) are not faces of any volume "
            "cell; expected boundary facets of the volume mesh"
        )
    p = nodes[facets]
    if facets.shape[1] == 4:
        normal = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
    else:
        normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    outward = np.einsum("ij,ij->i", normal, p.mean(axis=1) - cents[match]) > 0
    return np.where(outward[:, None], facets, facets[:, ::-1])


def read_mesh(path: str | os.PathLike, node_sets: Mapping[str, np.ndarray] | None = None) -> Mesh:
    """Read a volume mesh with meshio and check its quality.

    Volume cells: tetra, tetra10, hexahedron, hexahedron27, wedge. Lower-dimensional cells are
    ignored, except gmsh physical surface groups (triangle/quad cells with ``gmsh:physical``
    cell data named in field_data), which become facet sets (oriented outward) and node sets of
    the same name. Point-data masks ``node_set:<name>`` (see write_mesh) become node sets.
    node_sets: extra name -> node ids in the file's numbering. Nodes used by no volume cell are
    dropped and the rest renumbered in order. Raises MeshError (one line) if the file is
    missing or unreadable, has no volume cells or an unsupported volume type, or a bad cell.
    """
    path = Path(path)
    m = _read(path)
    blocks = _volume_blocks(m, path)
    n_points = len(m.points)
    for b in blocks:
        c = b.connectivity
        if c.size and (c.min() < 0 or c.max() >= n_points):
            bad = int(c.min()) if c.min() < 0 else int(c.max())
            raise MeshError(f"mesh file {str(path)!r}: {b.cell_type.value} cells refer to node "
                            f"{bad}; expected node ids 0..{n_points - 1}")
    used = np.unique(np.concatenate([b.connectivity.ravel() for b in blocks]))
    new_id = np.full(len(m.points), -1, dtype=np.int64)
    new_id[used] = np.arange(len(used))
    nodes = np.asarray(m.points, dtype=float)[used]
    if nodes.shape[1] == 2:
        nodes = np.column_stack([nodes, np.zeros(len(nodes))])
    blocks = [CellBlock(b.cell_type, new_id[b.connectivity]) for b in blocks]
    keys, cents = _face_table(nodes, blocks)
    facet_sets: dict[str, FacetSet] = {}
    for name, parts in _surface_groups(m).items():
        by_kind = {3: [], 4: []}
        for facets in parts:
            mapped = new_id[facets]
            if np.any(mapped < 0):
                raise MeshError(f"surface {name!r} uses nodes of no volume cell in {str(path)!r}")
            by_kind[mapped.shape[1]].append(_orient_outward(nodes, mapped, keys, cents, name))
        facet_sets[name] = FacetSet(
            quads=np.vstack(by_kind[4] or [np.zeros((0, 4), dtype=np.int64)]),
            tris=np.vstack(by_kind[3] or [np.zeros((0, 3), dtype=np.int64)]),
        )
    sets = {name: fs.nodes for name, fs in facet_sets.items()}
    for key, values in m.point_data.items():
        if key.startswith(NODE_SET_PREFIX):
            sets[key[len(NODE_SET_PREFIX) :]] = new_id[np.flatnonzero(np.asarray(values) != 0)]
    for name, ids in (node_sets or {}).items():
        ids = np.asarray(ids, dtype=np.int64)
        if ids.size and (ids.min() < 0 or ids.max() >= n_points):
            raise MeshError(f"node set {name!r} refers to nodes outside {str(path)!r} "
                            f"(0..{n_points - 1})")
        sets[name] = new_id[ids]
    sets = {k: v[v >= 0] for k, v in sets.items()}
    mesh = Mesh(nodes=nodes, cells=tuple(blocks), node_sets=sets, facet_sets=facet_sets)
    check_quality(mesh)
    return mesh


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
        raise MeshError(f"cannot write mesh file {str(path)!r}: directory {str(path.parent)!r} "
                        f"is not writable ({exc.strerror or type(exc).__name__})") from None
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
