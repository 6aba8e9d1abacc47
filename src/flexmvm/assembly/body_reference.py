"""The reference condition (3-2-1 frame support) of a scenario's body, from its model's
``reference``: a rod's end_b (rod_reference), a named node set (three_two_one), or, for a mesh
body that names none (``"auto"``), the nodes farthest from the body's contact surfaces
(far_reference).

The builder's caches are keyed by a reference *label*, a string: the set's name, or for the
automatic choice ``auto[surface,...]`` with the contact surfaces it keeps away from, so that
one mesh with other contacts gets another support (and another cache entry).
"""

from __future__ import annotations

import numpy as np

from flexmvm.assembly.supports import clamp_reference
from flexmvm.errors import InputError, MeshError
from flexmvm.mesh.mesh import Mesh
from flexmvm.reduction.reference_condition import ReferenceCondition, far_reference, three_two_one
from flexmvm.scenarios.body_schema import AUTO_REFERENCE

_AUTO_OPEN, _AUTO_CLOSE = f"{AUTO_REFERENCE}[", "]"


def auto_label(surfaces: tuple[str, ...]) -> str:
    """The reference label of the automatic support far from facet sets ``surfaces``."""
    return f"{_AUTO_OPEN}{','.join(sorted(set(surfaces)))}{_AUTO_CLOSE}"


def auto_surfaces(label: str) -> tuple[str, ...] | None:
    """The contact surfaces of an automatic reference label; None for a node set's name."""
    if not (label.startswith(_AUTO_OPEN) and label.endswith(_AUTO_CLOSE)):
        return None
    inner = label[len(_AUTO_OPEN) : -len(_AUTO_CLOSE)]
    return tuple(inner.split(",")) if inner else ()


def reference_label(reference: str, mesh: Mesh, surfaces: tuple[str, ...], where: str) -> str:
    """The label of a body's reference (its model's ``reference``), checked against its mesh:
    the node set must exist and hold nodes, the contact surfaces of an automatic choice too.
    InputError (one line, prefixed by ``where``) otherwise."""
    try:
        if reference != AUTO_REFERENCE:
            mesh.node_set(reference)
            return reference
        for name in surfaces:
            mesh.facet_set(name)
    except MeshError as exc:
        raise InputError(f"{where}: {exc}") from None
    return auto_label(surfaces)


def support(mesh: Mesh, label: str) -> ReferenceCondition:
    """The 3-2-1 support of reference label ``label`` on ``mesh``: far_reference from the
    nodes of an automatic label's surfaces, else three_two_one on the named node set (a rod's
    end_b is build.reference_condition's, rod_reference); a clamp's label (supports.py) gives
    its ClampCondition, every DOF of the clamped set held."""
    clamp = clamp_reference(mesh, label)
    if clamp is not None:
        return clamp
    surfaces = auto_surfaces(label)
    if surfaces is None:
        return three_two_one(mesh, mesh.node_set(label))
    nodes = [mesh.facet_set(name).nodes for name in surfaces]
    return far_reference(mesh, np.concatenate(nodes) if nodes else np.zeros(0, np.int64))


__all__ = ["auto_label", "auto_surfaces", "reference_label", "support"]
