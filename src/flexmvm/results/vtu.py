"""VTK XML unstructured-grid files (.vtu) of one mesh with changing point data.

A ParaView time series writes the same points and cells in every file and only the point data
changes (results/writers.py: the points are the undeformed body, the displacement a field).
:class:`VtuSeries` compresses and encodes the points and cells once and, per file, only the
point data: zlib-compressed blocks of 32 KiB with a UInt32 header (VTK file format 0.1;
readable by ParaView, VTK and meshio), raw in an <AppendedData> section rather than base64
inline (VTK's own writers' default; a quarter fewer bytes: the seed striker's file at
t = 0.2 ms, float32 fields, 357 kB -> 268 kB), node ids Int32 while they fit, the grid at
zlib level 9 (compressed once per series). Point data at zlib level 1 (seed rod,
hexahedron27, 8,591 nodes: displacement 3.2 ms instead of 9.8 ms at meshio's level 6,
152.5 kB instead of 151.7 kB; velocities do not compress at either level): the fields
compress little whatever the effort.

Cell node order is meshio's (flexmvm.mesh.mesh.CellBlock), which is VTK's except for the
linear wedge (meshio follows gmsh there; written permuted, as meshio does).
"""

from __future__ import annotations

import os
import sys
import zlib
from collections.abc import Mapping, Sequence

import numpy as np

from flexmvm.errors import InputError
from flexmvm.mesh.cells import CELLS, spec_named
from flexmvm.results.atomic import write_bytes_atomic

__all__ = ["GRID_ZLIB_LEVEL", "ZLIB_LEVEL", "VtuSeries"]

ZLIB_LEVEL = 1
GRID_ZLIB_LEVEL = 9  # the points and cells, compressed once for all the files of a series
_BLOCK = 32768  # bytes per compressed block (VTK's and meshio's default)

_NUMPY_TO_VTK = {
    np.dtype(np.float64): "Float64",
    np.dtype(np.float32): "Float32",
    np.dtype(np.int64): "Int64",
    np.dtype(np.int32): "Int32",
    np.dtype(np.uint8): "UInt8",
}


def _compressed(data: np.ndarray, level: int) -> bytes:
    """One DataArray's appended bytes: UInt32 header [n blocks, block size, last block size,
    compressed sizes...] and the zlib blocks (VTK's vtkZLibDataCompressor layout)."""
    raw = np.ascontiguousarray(data).tobytes()
    blocks = [zlib.compress(raw[i : i + _BLOCK], level) for i in range(0, len(raw), _BLOCK)]
    last = len(raw) - (len(blocks) - 1) * _BLOCK if blocks else 0
    header = np.array([len(blocks), _BLOCK, last] + [len(b) for b in blocks], dtype=np.uint32)
    return header.tobytes() + b"".join(blocks)


def _data_array(name: str, data: np.ndarray, offset: int) -> str:
    """The DataArray tag of `data`, its bytes at `offset` of the appended data."""
    data = np.asarray(data)
    vtk_type = _NUMPY_TO_VTK.get(data.dtype)
    if vtk_type is None:
        raise InputError(f"VTU array {name!r}: unsupported dtype {data.dtype}")
    comps = f' NumberOfComponents="{data.shape[1]}"' if data.ndim == 2 else ""
    return (
        f'<DataArray type="{vtk_type}" Name="{name}"{comps} format="appended" offset="{offset}"/>\n'
    )


class _Appended:
    """DataArray tags and their raw appended bytes, offsets counted from `start`."""

    def __init__(self, level: int, start: int = 0):
        self.level, self.offset = level, start
        self.parts: list[bytes] = []

    def tag(self, name: str, data: np.ndarray) -> str:
        text = _data_array(name, data, self.offset)
        chunk = _compressed(data, self.level)
        self.parts.append(chunk)
        self.offset += len(chunk)
        return text


class VtuSeries:
    """Files of one unstructured grid (points (n, 3) [m], cells as (meshio type name,
    connectivity (c, k)) pairs) with their own point data each: ``write(path, point_data)``,
    atomically (results/atomic.py). Thread-safe: the encoded points and cells are made once
    and only read afterwards; zlib releases the GIL, so files can be written on threads."""

    def __init__(
        self, points: np.ndarray, cells: Sequence[tuple[str, np.ndarray]], level: int = ZLIB_LEVEL
    ):
        points = np.asarray(points)
        if points.dtype != np.float32:  # float32 points as given, anything else float64
            points = points.astype(np.float64)
        if points.ndim != 2 or points.shape[1] != 3:
            raise InputError(f"VTU points: expected shape (n, 3), got {points.shape}")
        self.n_points = len(points)
        self.level = level
        conn, offsets, types = [], [], []
        end = 0
        for name, c in cells:
            spec = spec_named(name)  # VTK cell id and node order: the cell type's (mesh/cells)
            if spec is None:
                raise InputError(
                    f"VTU: unsupported cell type {name!r}; "
                    f"expected one of {sorted(ct.value for ct in CELLS)}"
                )
            c = np.asarray(c, dtype=np.int64)
            if c.ndim != 2:
                raise InputError(
                    f"VTU {name} connectivity: expected (cells, nodes), got shape {c.shape}"
                )
            if c.size and (c.min() < 0 or c.max() >= self.n_points):
                raise InputError(
                    f"VTU {name} connectivity: node index outside 0...{self.n_points - 1}"
                )
            if spec.vtk_order is not None:
                c = c[:, list(spec.vtk_order)]
            conn.append(c.ravel())
            offsets.append(end + c.shape[1] * np.arange(1, len(c) + 1, dtype=np.int64))
            end += c.size
            types.append(np.full(len(c), spec.vtk_id, dtype=np.uint8))
        self.n_cells = sum(len(t) for t in types)
        cat = lambda xs, dt: np.concatenate(xs) if xs else np.zeros(0, dt)
        byte_order = "LittleEndian" if sys.byteorder == "little" else "BigEndian"
        app = _Appended(GRID_ZLIB_LEVEL)  # encoded once per series: the best zlib does
        # Int32 node ids and offsets (as VTK's own writers) while they fit: half the bytes
        index = np.int32 if max(end, self.n_points) < 2**31 else np.int64
        self._head = (
            '<?xml version="1.0"?>\n'
            f'<VTKFile type="UnstructuredGrid" version="0.1" byte_order="{byte_order}" '
            'compressor="vtkZLibDataCompressor">\n'
            "<UnstructuredGrid>\n"
            f'<Piece NumberOfPoints="{self.n_points}" NumberOfCells="{self.n_cells}">\n'
            "<Points>\n" + app.tag("Points", points) + "</Points>\n"
            "<Cells>\n"
            + app.tag("connectivity", cat(conn, np.int64).astype(index))
            + app.tag("offsets", cat(offsets, np.int64).astype(index))
            + app.tag("types", cat(types, np.uint8))
            + "</Cells>\n"
        ).encode()
        self._grid_bytes = b"".join(app.parts)  # the appended bytes of points and cells
        self._tail = b"</Piece>\n</UnstructuredGrid>\n"

    def write(
        self,
        path: str | os.PathLike[str],
        point_data: Mapping[str, np.ndarray],
        cell_data: Mapping[str, np.ndarray] | None = None,
    ) -> None:
        """Write one file: the grid, point_data {name: (n,) or (n, k) array} and cell_data
        {name: (n_cells,) or (n_cells, k) array, cells in the order given}."""
        app = _Appended(self.level, len(self._grid_bytes))
        body = self._section("PointData", "point", point_data, self.n_points, app)
        body += self._section("CellData", "cell", cell_data or {}, self.n_cells, app)
        write_bytes_atomic(
            path,
            self._head
            + body
            + self._tail
            + b'<AppendedData encoding="raw">\n_'
            + self._grid_bytes
            + b"".join(app.parts)
            + b"\n</AppendedData>\n</VTKFile>\n",
        )

    def _section(
        self, tag: str, kind: str, data_by_name: Mapping, rows: int, app: _Appended
    ) -> bytes:
        parts = []
        for name, data in data_by_name.items():
            data = np.asarray(data)
            if data.ndim not in (1, 2) or data.shape[0] != rows:
                raise InputError(
                    f"VTU {kind} data {name!r}: expected {rows} rows, got shape {data.shape}"
                )
            if any(c in name for c in '<>&"'):
                raise InputError(f'VTU {kind} data name {name!r}: no <, >, & or " allowed')
            parts.append(app.tag(name, data))
        return (f"<{tag}>\n" + "".join(parts) + f"</{tag}>\n").encode() if parts else b""
