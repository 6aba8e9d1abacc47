"""The named sets and surfaces of an Abaqus .inp file, read from its text (meshio keeps too few).

meshio reads an .inp's nodes and elements well, but its sets badly (issue 52): a second
``*ELSET, ELSET=side`` card replaces the first (meshio's own .inp writer writes one card per
block, so a gmsh surface of four entities became one: a clamp on ``side`` held one edge of a
plate instead of four, silently), a second *NODE card replaces the first, an ``*NSET`` naming
other sets is read empty, GENERATE is refused unless on one line of three fields, and
``*SURFACE`` cards are dropped. This module reads the keyword cards itself, hands meshio the
nodes and elements alone (geometry_text), and gives read_mesh:

- element sets (``*ELSET``, and ``ELSET=`` on an ``*ELEMENT`` card): the union of every card of
  that name; members are element labels, ranges (``GENERATE``: ``first, last[, step]`` per data
  line) or the names of element sets defined before;
- node sets (``*NSET``, and ``NSET=`` on a ``*NODE`` card): the same, with ``ELSET=name`` for the
  nodes of an element set;
- surfaces (``*SURFACE, NAME=...``): ``TYPE=ELEMENT`` (the default), data lines ``elset or
  label, Sn`` (face n of those elements) or ``elset or label`` alone (their faces on the skin),
  and ``TYPE=NODE``, data lines ``nset or label[, area]`` (the skin facets whose corners are all
  in it). Another TYPE (analytical, segments, cutting) is skipped with a MeshWarning
  (read_mesh's).

Keywords, parameters and names are case-insensitive, as Abaqus reads them: cards whose names
differ only in case are one set, known (in Mesh.node_set, Mesh.facet_set) by the first card's
spelling. A keyword line ending in a comma continues on the next line; comment lines start
with ``**``; ``*INCLUDE, INPUT=`` files are read where they stand. Parts and instances are not
told apart: a file of one part instanced once (gmsh's, meshio's, Abaqus/CAE's for one part) is
read as it is, an ``*INSTANCE``'s translation or rotation is not applied.

Face numbers, Abaqus Analysis User's Guide (6.14), sect. 28.1.4 "Three-dimensional solid
element library", *Element faces* (node numbers 1-based as there; meshio keeps Abaqus's node
order for these types, so the corners are the same local nodes):

- C3D4, C3D10 (tetrahedra): S1 1-2-3, S2 1-4-2, S3 2-4-3, S4 3-4-1;
- C3D8, C3D20 (hexahedra): S1 1-2-3-4, S2 5-8-7-6, S3 1-5-6-2, S4 2-6-7-3, S5 3-7-8-4,
  S6 4-8-5-1;
- C3D6 (wedge): S1 1-2-3, S2 4-6-5, S3 1-4-5-2, S4 2-5-6-3, S5 3-6-4-1.

A face is its corner nodes (a quadratic face's mid-side nodes join it in read_mesh, as for every
face: mesh/subfacets.py). read_mesh refuses the hexahedron20 (C3D20) volume type itself.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path

import meshio
import numpy as np

from flexmvm.errors import MeshError
from flexmvm.mesh.cells import CELLS, hex8
from flexmvm.mesh.groups import skin_rows, skin_within

#: Abaqus types read as no flexmvm cell type, by meshio name: their faces S1, S2, ... (C3D20:
#: the corners of C3D8's; read_mesh refuses the volume type, a surface on it is read)
_OTHER_FACES = {"hexahedron20": hex8.ABAQUS_FACES}


def _faces() -> dict[str, tuple[tuple[int, ...], ...]]:
    """Corner nodes (0-based) of the faces S1, S2, ... of each meshio volume type (module
    docstring): each cell type's ``abaqus_faces`` (mesh/cells), then _OTHER_FACES."""
    table = {s.name: s.abaqus_faces for s in CELLS.values() if s.abaqus_faces}
    return table | _OTHER_FACES


@dataclass(frozen=True)
class _Card:
    """A keyword card: keyword (upper case), parameters (upper-case keys; value None for a
    flag) and its data lines split at commas (empty fields dropped)."""

    keyword: str
    params: dict[str, str | None]
    rows: list[list[str]]


@dataclass(frozen=True)
class InpSets:
    """What an .inp names, in meshio's numbering of the file: node_sets name -> point indices
    (sorted); element_sets name -> cell indices running over meshio's blocks in order (sorted);
    face_surfaces name -> (F, 2) (running cell index, face 0-based; -1: every face of the cell
    on the skin); node_surfaces name -> point indices; skipped: what was not read, one line
    each (read_mesh warns of it)."""

    node_sets: dict[str, np.ndarray]
    element_sets: dict[str, np.ndarray]
    face_surfaces: dict[str, np.ndarray]
    node_surfaces: dict[str, np.ndarray]
    skipped: tuple[str, ...] = ()

    def cell_sets(self, m: meshio.Mesh) -> dict[str, list[np.ndarray]]:
        """The element sets as meshio's cell_sets: name -> per-block cell indices."""
        start = np.cumsum([0] + [len(b.data) for b in m.cells])
        return {
            name: [ids[(ids >= a) & (ids < b)] - a for a, b in itertools.pairwise(start)]
            for name, ids in self.element_sets.items()
        }


def _unquote(text: str) -> str:
    return text.strip().strip('"').strip()


def _params(text: str) -> tuple[str, dict[str, str | None]]:
    head, *rest = text.split(",")
    params: dict[str, str | None] = {}
    for word in rest:
        key, eq, value = word.partition("=")
        if key.strip():
            params[" ".join(key.split()).upper()] = _unquote(value) if eq else None
    return " ".join(head.lstrip("*").split()).upper(), params


def _logical_lines(path: Path, where: str, depth: int = 0) -> list[str]:
    """The file's lines without comments and blank lines, keyword lines joined across their
    continuations, *INCLUDE files read in place."""
    if depth > 10:
        raise MeshError(f"{where}: *INCLUDE nested more than 10 deep; expected no include loop")
    try:
        raw = path.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError as exc:
        raise MeshError(f"{where}: cannot read {str(path)!r} ({exc.strerror})") from None
    out: list[str] = []
    for line in raw:
        line = line.strip()
        if not line or line.startswith("**"):
            continue
        if out and out[-1].startswith("*") and out[-1].endswith(","):
            out[-1] += line
            continue
        keyword, params = _params(line) if line.startswith("*") else ("", {})
        if keyword == "INCLUDE" and params.get("INPUT"):
            out += _logical_lines(path.parent / str(params["INPUT"]), where, depth + 1)
        else:
            out.append(line)
    return out


def _cards(path: Path, where: str) -> list[_Card]:
    cards: list[_Card] = []
    for line in _logical_lines(path, where):
        if line.startswith("*"):
            keyword, params = _params(line)
            cards.append(_Card(keyword, params, []))
        elif cards:
            cards[-1].rows.append([f.strip() for f in line.split(",") if f.strip()])
    return cards


class _Reader:
    """The sets as the cards define them, checked against meshio's reading of the same file."""

    def __init__(self, m: meshio.Mesh, where: str) -> None:
        self.m, self.where = m, where
        self.node_labels: list[np.ndarray] = []
        self.elem_labels: list[np.ndarray] = []
        self.names: dict[tuple[str, str], str] = {}  # (kind, NAME) -> first spelling
        self.sets: dict[tuple[str, str], list[np.ndarray]] = {}
        self.faces: dict[str, list[np.ndarray]] = {}
        self.skipped: list[str] = []
        self.sorted: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}

    def error(self, text: str) -> MeshError:
        return MeshError(f"{self.where}: {text}")

    def add(self, kind: str, name: str, ids: np.ndarray) -> None:
        """Add members to the set ``kind`` (NSET, ELSET, NODE surface) ``name``: a union."""
        key = (kind, name.upper())
        self.names.setdefault(key, name)
        self.sets.setdefault(key, []).append(np.asarray(ids, dtype=np.int64))

    def members(self, kind: str, name: str) -> np.ndarray | None:
        parts = self.sets.get((kind, name.upper()))
        return None if parts is None else np.unique(np.concatenate(parts))

    def index(
        self, labels: list[np.ndarray], wanted: np.ndarray, what: str, ctx: str
    ) -> np.ndarray:
        """Running indices of ``wanted`` labels; MeshError naming the first label not defined."""
        key = (id(labels), len(labels))
        if key not in self.sorted:  # sorted once per *NODE/*ELEMENT card added
            all_labels = np.concatenate(labels) if labels else np.zeros(0, dtype=np.int64)
            order = np.argsort(all_labels, kind="stable")
            self.sorted[key] = (all_labels[order], order)
        ordered, order = self.sorted[key]
        pos = np.minimum(np.searchsorted(ordered, wanted), max(len(ordered) - 1, 0))
        ok = ordered[pos] == wanted if len(ordered) else np.zeros(len(wanted), dtype=bool)
        if not np.all(ok):
            bad = int(wanted[~ok][0])
            raise self.error(
                f"{ctx} names {what} {bad}, which no *{what.upper()} card defines; expected "
                f"{what} labels of the file (or names of sets defined before)"
            )
        return order[pos]

    def node(self, card: _Card) -> None:
        labels = np.array([int(r[0]) for r in card.rows if r], dtype=np.int64)
        start = sum(len(x) for x in self.node_labels)
        self.node_labels.append(labels)
        if card.params.get("NSET"):
            self.add("NSET", str(card.params["NSET"]), start + np.arange(len(labels)))

    def element(self, card: _Card) -> None:
        k = len(self.elem_labels)
        if k >= len(self.m.cells):
            raise self.error(f"*ELEMENT card {k + 1} has no block in meshio's reading")
        width = self.m.cells[k].data.shape[1] + 1
        ints = np.array([int(f) for r in card.rows for f in r], dtype=np.int64)
        if len(ints) % width:
            raise self.error(
                f"*ELEMENT card {k + 1} (TYPE={card.params.get('TYPE')}) holds {len(ints)} "
                f"numbers; expected a label and {width - 1} nodes per element"
            )
        start = sum(len(x) for x in self.elem_labels)
        self.elem_labels.append(ints[::width])
        if card.params.get("ELSET"):
            self.add("ELSET", str(card.params["ELSET"]), start + np.arange(len(ints) // width))

    def listed(self, kind: str, card: _Card, name: str, ctx: str = "") -> np.ndarray:
        """The members a *NSET/*ELSET card (or a *SURFACE line) lists: labels, GENERATE
        ranges, set names; ``ctx`` names the card in errors (default ``*kind 'name'``)."""
        labels, found = [], []
        ctx = ctx or f"*{kind} {name!r}"
        for row in card.rows:
            if "GENERATE" in card.params:
                try:
                    a, b, *step = (int(f) for f in row)
                except ValueError:
                    raise self.error(
                        f"{ctx}, GENERATE: line {row}; expected first, last[, step] labels"
                    ) from None
                labels.append(np.arange(a, b + 1, step[0] if step else 1))
                continue
            for f in row:
                if f.lstrip("-").isdigit():
                    labels.append(np.array([int(f)]))
                elif (ids := self.members(kind, _unquote(f))) is not None:
                    found.append(ids)
                else:
                    raise self.error(
                        f"{ctx} names {_unquote(f)!r}, which no earlier *{kind} defines"
                    )
        what = "node" if kind == "NSET" else "element"
        source = self.node_labels if kind == "NSET" else self.elem_labels
        if labels:
            found.append(self.index(source, np.concatenate(labels), what, ctx))
        return np.unique(np.concatenate(found)) if found else np.zeros(0, dtype=np.int64)

    def set_card(self, kind: str, card: _Card) -> None:
        name = card.params.get(kind)
        if not name:
            raise self.error(f"*{kind} card without {kind}=name; expected a named set")
        ids = self.listed(kind, card, name)
        if kind == "NSET" and card.params.get("ELSET"):
            ids = np.concatenate([ids, self.elset_nodes(str(card.params["ELSET"]), name)])
        self.add(kind, name, ids)

    def elset_nodes(self, elset: str, ctx: str) -> np.ndarray:
        cells = self.members("ELSET", elset)
        if cells is None:
            raise self.error(f"*NSET {ctx!r}: ELSET={elset!r} is defined by no earlier *ELSET")
        blocks = [np.asarray(b.data) for b in self.m.cells]
        start = np.cumsum([0] + [len(b) for b in blocks])
        parts = [
            blocks[k][cells[(cells >= a) & (cells < b)] - a].ravel()
            for k, (a, b) in enumerate(itertools.pairwise(start))
        ]
        return np.unique(np.concatenate(parts))

    def surface(self, card: _Card) -> None:
        name = card.params.get("NAME")
        if not name:
            raise self.error("*SURFACE card without NAME=; expected a named surface")
        kind = (card.params.get("TYPE") or "ELEMENT").upper()
        if kind == "NODE":
            for row in card.rows:
                self.add(
                    "NODE",
                    name,
                    self.listed("NSET", _Card("NSET", {}, [row[:1]]), name, f"*SURFACE {name!r}"),
                )
            self.add("NODE", name, np.zeros(0, dtype=np.int64))
            return
        if kind != "ELEMENT":
            self.skipped.append(
                f"*SURFACE {name!r} of TYPE={kind} not read (only TYPE=ELEMENT and TYPE=NODE "
                "give facets)"
            )
            return
        key = name.upper()
        self.names.setdefault(("FACE", key), name)
        parts = self.faces.setdefault(key, [])
        for row in card.rows:
            cells = self.listed("ELSET", _Card("ELSET", {}, [row[:1]]), name, f"*SURFACE {name!r}")
            face = -1
            if len(row) > 1:
                label = row[1].upper()
                if not (label[:1] == "S" and label[1:].isdigit()):
                    raise self.error(
                        f"*SURFACE {name!r}: face {row[1]!r}; expected S1..S6 (solid faces)"
                    )
                face = int(label[1:]) - 1
            parts.append(np.column_stack([cells, np.full(len(cells), face)]))

    def result(self) -> InpSets:
        n_nodes = sum(len(x) for x in self.node_labels)
        if n_nodes != len(self.m.points) or len(self.elem_labels) != len(self.m.cells):
            raise self.error(
                f"{n_nodes} nodes on {len(self.node_labels)} *NODE card(s) and "
                f"{len(self.elem_labels)} *ELEMENT card(s), but meshio read {len(self.m.points)} "
                f"nodes and {len(self.m.cells)} blocks; expected one *NODE card before the elements"
            )
        out: dict[str, dict[str, np.ndarray]] = {"NSET": {}, "ELSET": {}, "NODE": {}}
        for (kind, key), name in self.names.items():
            members = self.members(kind, key) if kind in out else None
            if members is not None:
                out[kind][name] = members
        faces = {
            self.names[("FACE", key)]: np.unique(np.vstack(p), axis=0)
            if p
            else np.zeros((0, 2), dtype=np.int64)
            for key, p in self.faces.items()
        }
        return InpSets(out["NSET"], out["ELSET"], faces, out["NODE"], tuple(self.skipped))


def read_cards(path: Path, where: str) -> list[_Card]:
    """The keyword cards of the .inp at ``path``, *INCLUDE files read in place; MeshError
    (one line) for a file that cannot be read."""
    return _cards(path, where)


def geometry_text(cards: list[_Card]) -> str:
    """The nodes and elements of ``cards`` as an .inp text for meshio: every *NODE card's
    lines under one *NODE card (meshio keeps the last card only), each *ELEMENT card with its
    TYPE alone, no set or surface card (meshio misreads them; read_inp_sets reads them)."""
    nodes = [", ".join(r) for c in cards if c.keyword == "NODE" for r in c.rows]
    lines = ["*NODE", *nodes]
    for c in cards:
        if c.keyword == "ELEMENT":
            lines.append(f"*ELEMENT, TYPE={c.params.get('TYPE')}")
            lines += [", ".join(r) for r in c.rows]  # meshio joins an element's lines
    return "\n".join(lines) + "\n"


def read_inp_sets(cards: list[_Card], m: meshio.Mesh, where: str) -> InpSets:
    """The node sets, element sets and surfaces of an .inp's ``cards`` (module docstring), in
    the numbering of meshio's reading ``m`` of geometry_text(cards). MeshError (one line,
    prefixed by ``where``) for a label or set name the file does not define, a GENERATE line
    that is not ``first, last[, step]``, a surface face that is not S1..S6, a card without
    its name, or cards that do not match meshio's reading.
    """
    r = _Reader(m, where)
    handlers = {
        "NODE": r.node,
        "ELEMENT": r.element,
        "NSET": lambda c: r.set_card("NSET", c),
        "ELSET": lambda c: r.set_card("ELSET", c),
        "SURFACE": r.surface,
    }
    for card in cards:
        handler = handlers.get(card.keyword)
        if handler is not None:
            handler(card)
    return r.result()


def _face_corners(
    m: meshio.Mesh, faces: np.ndarray, name: str, where: str
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Corner nodes (meshio point ids) of the faces (F, 2) (running cell index, face; -1 every
    face) of a surface, with whether each was named by its number: a list of ((n, 3|4), (n,))
    pairs, one per face shape. MeshError for a face number the element lacks or an element
    that is no volume cell."""
    start = np.cumsum([0] + [len(b.data) for b in m.cells])
    out: list[tuple[np.ndarray, np.ndarray]] = []
    for k, block in enumerate(m.cells):
        sel = faces[(faces[:, 0] >= start[k]) & (faces[:, 0] < start[k + 1])]
        if not len(sel):
            continue
        table = _faces().get(block.type)
        if table is None:
            raise MeshError(
                f"{where}: *SURFACE {name!r} lies on {block.type} elements; expected faces of "
                f"volume elements ({', '.join(_faces())})"
            )
        if np.any(sel[:, 1] >= len(table)):
            raise MeshError(
                f"{where}: *SURFACE {name!r}: face S{int(sel[:, 1].max()) + 1} of a {block.type} "
                f"element; expected S1..S{len(table)}"
            )
        data = np.asarray(block.data)[sel[:, 0] - start[k]]
        for f, corners in enumerate(table):
            rows = (sel[:, 1] == f) | (sel[:, 1] < 0)
            if rows.any():
                out.append((data[rows][:, list(corners)], sel[rows, 1] >= 0))
    return out


def surface_rows(
    m: meshio.Mesh, inp: InpSets, new_id: np.ndarray, boundary: np.ndarray, where: str
) -> dict[str, np.ndarray]:
    """Each *SURFACE of ``inp`` as rows of the skin faces ``boundary`` (B, 4) (read_mesh's
    numbering; new_id: meshio point id -> node id): an element-based one its faces (a face
    named by its number must be on the skin: MeshError otherwise, one line; an element named
    without a face gives its faces on the skin), a node-based one the skin faces whose corners
    are all its nodes (groups.skin_within)."""
    out: dict[str, np.ndarray] = {}
    for name, faces in inp.face_surfaces.items():
        rows = [np.zeros(0, dtype=np.int64)]
        for corners, named in _face_corners(m, faces, name, where):
            r = skin_rows(boundary, new_id[corners])
            if np.any((r < 0) & named):
                raise MeshError(
                    f"{where}: *SURFACE {name!r}: {int(np.sum((r < 0) & named))} face(s) inside "
                    "the body (shared by two elements); expected faces on the skin"
                )
            rows.append(r[r >= 0])
        out[name] = np.unique(np.concatenate(rows))
    n_nodes = int(new_id.max()) + 1
    for name, ids in inp.node_surfaces.items():
        mapped = new_id[ids]
        out[name] = skin_within(boundary, mapped[mapped >= 0], n_nodes)
    return out


__all__ = ["InpSets", "geometry_text", "read_cards", "read_inp_sets", "surface_rows"]
