"""Lookups on a scenario body's mesh: the nodes a reduced model retains (an i-j selection or a
region), the nodes and facet sets of its contact surfaces, the node nearest a probe's point
and the body point of a joint (in a cell, with its offset from the cell's nearest node)."""

from __future__ import annotations

import numpy as np

from flexmvm.bodies.body import FlexibleBody
from flexmvm.constraints.joints import BodyPoint
from flexmvm.errors import InputError, MeshError
from flexmvm.mesh.mesh import Mesh
from flexmvm.mesh.rod import RodMesh


def retained_nodes(model, mesh: Mesh, rod: RodMesh | None, where: str) -> np.ndarray:
    """The node ids ``model`` (a ModelConfig) retains on ``mesh`` (``rod``: the body's RodMesh,
    for an i-j selection): its selection or region; InputError (one line) if it selects none.
    The selection study counts its candidates' nodes with it (studies/regions.py)."""
    if model.selection_ij is not None:
        if rod is None:
            raise InputError(f"{where}.selection: an i-j selection needs a [bodies.rod] body")
        return rod.selection(*model.selection_ij)
    reg = model.region
    if reg is None:
        raise InputError(f"{where}: model {model.kind.value!r} needs a selection or a region")
    X = mesh.nodes
    if reg.node_set is not None:
        ids = mesh.node_set(reg.node_set)
    elif reg.ball is not None:
        ids = np.nonzero(
            np.linalg.norm(X - np.asarray(reg.ball.centre_m), axis=1) <= reg.ball.radius_m
        )[0]
    elif reg.box is not None:
        lo, hi = np.asarray(reg.box.min_m), np.asarray(reg.box.max_m)
        ids = np.nonzero(np.all((X >= lo) & (X <= hi), axis=1))[0]
    else:
        ids = np.asarray(reg.node_ids, dtype=np.int64)
        if ids.size and ids.max() >= len(X):
            raise InputError(
                f"{where}.region.node_ids: node {int(ids.max())} is outside the mesh "
                f"(0..{len(X) - 1})"
            )
    if len(ids) == 0:
        raise InputError(f"{where}.region: selects no node of the mesh")
    return np.asarray(ids, dtype=np.int64)


def contact_nodes(sc, body: str, mesh: Mesh) -> np.ndarray:
    """Nodes of ``body`` on the surfaces of the contacts that redistribute their mass
    (``redistribute_mass``): the slave face's nodes, or the master facets' nodes."""
    ids = []
    for k, c in enumerate(sc.contacts):
        if not c.redistribute_mass:
            continue
        for who, surface in ((c.slave_body, c.slave_surface), (c.master_body, c.master_surface)):
            if who == body:
                try:
                    ids.append(mesh.facet_set(surface).nodes)
                except MeshError as exc:
                    raise InputError(f"contacts[{k}]: {exc}") from None
    return np.unique(np.concatenate(ids)) if ids else np.zeros(0, np.int64)


def check_contact_surfaces(sc, body: str, mesh: Mesh) -> None:
    """InputError (one line) naming the contact key (``contacts[k].slave = 'body.surface'``)
    and the body's mesh file when a surface of ``body`` a contact names is unknown to its mesh
    (the message lists the mesh's surfaces; a node set of that name that covers no skin face
    is said to be one) or empty (a group with no facet): checked before the body is built,
    whose automatic reference would otherwise meet it first and be blamed (issue 48)."""
    for k, c in enumerate(sc.contacts):
        for role, who, surface in (
            ("slave", c.slave_body, c.slave_surface),
            ("master", c.master_body, c.master_surface),
        ):
            if who == body:
                try:
                    mesh.facet_set(surface)
                except MeshError as exc:
                    raise InputError(
                        f"contacts[{k}].{role} = {getattr(c, role)!r}: body {body!r}: {exc}"
                        f"{_node_set_note(mesh, surface)}{_mesh_file(sc, body)}"
                    ) from None


def _mesh_file(sc, body: str) -> str:
    """``; mesh file 'path'`` for a body read from a file, else empty."""
    path = next((b.mesh_file for b in sc.bodies if b.name == body), None)
    return f"; mesh file {str(path)!r}" if path is not None else ""


def _node_set_note(mesh: Mesh, name: str) -> str:
    """Why a name is no surface of ``mesh``, where it can be told: a node set that covers no
    skin face, or a surface spelled in another case (Abaqus names are case-insensitive in the
    file; the scenario names them as the file spells them). Empty otherwise."""
    if name in mesh.node_sets and name not in mesh.facet_sets:
        return (
            f" ({name!r} is a node set covering no skin face: a surface needs faces whose "
            "corner nodes are all in it)"
        )
    same = [k for k in mesh.facet_sets if k.lower() == name.lower() and k != name]
    if same:
        return f" (did you mean {same[0]!r}? names are matched as the mesh file spells them)"
    return ""


def contact_surfaces(sc, body: str) -> tuple[str, ...]:
    """The facet sets of ``body`` named in the scenario's contacts, as slave or master."""
    names = [
        surface
        for c in sc.contacts
        for who, surface in ((c.slave_body, c.slave_surface), (c.master_body, c.master_surface))
        if who == body
    ]
    return tuple(dict.fromkeys(names))


def nearest_node(mesh: Mesh, point, where: str, tol: float) -> int:
    """The node of ``mesh`` nearest ``point`` [m]; InputError if it is farther than ``tol`` [m]."""
    d = np.linalg.norm(mesh.nodes - np.asarray(point, float), axis=1)
    k = int(np.argmin(d))
    if d[k] > tol:
        raise InputError(
            f"{where}: point {list(point)} is {d[k]:.3g} m from the nearest node of "
            f"the body (off the body; tolerance {tol:.3g} m)"
        )
    return k


# A joint point is on the body when it lies in a cell's node bounding box grown by this
# fraction of the box's diagonal (curved cell faces bulge beyond their nodes' box).
CELL_BOX_PAD = 0.05


def host_node(mesh: Mesh, point: np.ndarray, where: str) -> int:
    """The node nearest `point` among the cells whose (padded) node box holds it; InputError
    when no cell does (the point is off the body)."""
    best, best_d = -1, np.inf
    for block in mesh.cells:
        xc = mesh.nodes[block.connectivity]  # (cells, nodes per cell, 3)
        lo, hi = xc.min(axis=1), xc.max(axis=1)
        pad = CELL_BOX_PAD * np.linalg.norm(hi - lo, axis=1)[:, None]
        inside = np.all((point >= lo - pad) & (point <= hi + pad), axis=1)
        ids = np.unique(block.connectivity[inside])
        if ids.size:
            d = np.linalg.norm(mesh.nodes[ids] - point, axis=1)
            if d.min() < best_d:
                best, best_d = int(ids[np.argmin(d)]), float(d.min())
    if best < 0:
        d = float(np.linalg.norm(mesh.nodes - point, axis=1).min())
        raise InputError(
            f"{where}: point {point.tolist()} m (body frame) is off the body: in no "
            f"cell, {d:.3g} m from the nearest node"
        )
    return best


def body_point(index, body: FlexibleBody, mesh: Mesh, point, where) -> BodyPoint:
    """The body point at `point` (body frame, reference configuration) exactly: a rigid body's
    frame point, else the nearest node of its cell with the offset to the point, carried by
    that node's displacement and the frame's rotation (joints.BodyPoint)."""
    p = np.asarray(point, float)
    node = host_node(mesh, p, where)
    if body.nq == 0:
        return BodyPoint(index, local=(float(p[0]), float(p[1]), float(p[2])))
    off = p - mesh.nodes[node]
    if not np.any(off):
        return BodyPoint(index, node=node)
    return BodyPoint(index, node=node, offset_m=(float(off[0]), float(off[1]), float(off[2])))
