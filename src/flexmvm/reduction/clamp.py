"""Supports held by removal: every displacement DOF of a node set held (a clamp), or chosen
components of it (pinned, roller, symmetry plane, chosen directions), in place of the
floating frame's 3-2-1 reference condition.

A body clamped on a node set C (a cantilever's root) has its frame fixed in space (a ground
joint on the frame: constraints.joints.ground_joint, added by the scenario builder) and the
nodal displacements of C held, u_C = 0. Held by removal, not by constraint rows: the bases of
reduction.basis leave out the DOFs of their reference condition, and a ClampCondition is a
reference condition whose fixed DOFs are all 3 |C| DOFs of the set (Shabana, Dynamics of
Multibody Systems, ch. 5: the body-fixed frame of a clamped body is its clamp). So

| kind          | basis of the clamped body                                        |
|---------------|------------------------------------------------------------------|
| FULL          | identity on every DOF outside C (exact: no constraint, no drift)  |
| CRAIG_BAMPTON | interface = C and the retained nodes b; C's columns removed:      |
|               | [[I, 0], [-K_ii^-1 K_ib, Phi_in]] with u_C = 0, Phi the modes of  |
|               | the body clamped on C and b held (Craig-Bampton 1968)             |
| MODAL         | the first modes of the body clamped on C                          |
| SEED_*        | seed eq. (4) with the clamped body's modes                        |

With no retained nodes a Craig-Bampton body clamped at its interface is its fixed-interface
modes; a retained node in C is refused (it cannot move and be held). The interface kind's
free-free mode pool has no clamped form: refused by the scenario builder.

Directional supports (HeldCondition) hold chosen components d of the nodes of a set,
u_{k,d} = 0, and enter every basis exactly as a clamp's DOFs do (zero rows of psi, the DOFs
left out of the Craig-Bampton interior and of the modal problem). Several supports of one body
are merged: a DOF held by two of them is held once. A pinned set (every translation held) is
a clamp for solid elements, whose nodes carry no rotation DOF. The held DOFs must fix the
body's six rigid-body motions, by themselves or with the stiffness of a spring bed
(fe/spring_bed.py), else K on the free DOFs is singular: check_held refuses such a support
(a free body on one roller is refused, not kept floating: its frame would then carry the
motions the roller holds).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError
from flexmvm.mesh.mesh import Mesh
from flexmvm.reduction.reference_condition import (
    RIGID_COND_MAX,
    ReferenceCondition,
    check_rigid,
    rigid_body_modes,
    three_two_one,
)

#: The body axes a directional support holds, by name (DOF 3 node + d).
AXES = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class ClampCondition(ReferenceCondition):
    """Every DOF of the clamped nodes held: nodes (sorted ids), fixed_dofs (3 len(nodes),)
    int64 DOF ids 3 node + d, node-major. A ReferenceCondition (every basis leaves out its
    fixed DOFs) whose fixed DOFs are all of the set's, not six."""

    def __post_init__(self) -> None:
        nodes = tuple(sorted({int(k) for k in self.nodes}))
        dofs = (3 * np.asarray(nodes, np.int64)[:, None] + np.arange(3)).ravel()
        dofs.setflags(write=False)
        object.__setattr__(self, "nodes", nodes)
        object.__setattr__(self, "fixed_dofs", dofs)


def clamp_condition(mesh: Mesh, node_ids) -> ClampCondition:
    """The clamp of nodes ``node_ids`` of ``mesh``: all their DOFs held.

    Raises InputError for ids outside the mesh, or a set that cannot hold the body (fewer
    than 3 nodes, or nodes on one line: a hinge, not a clamp; the same test as a 3-2-1
    support's, three_two_one).
    """
    ids = np.unique(np.asarray(node_ids, dtype=np.int64).ravel())
    if ids.size < 3:
        raise InputError(f"a clamp needs at least 3 nodes not on one line, got {ids.size}")
    if ids[0] < 0 or ids[-1] >= mesh.n_nodes:
        raise InputError(
            f"clamped node ids must be in 0..{mesh.n_nodes - 1}, got {ids[0]}..{ids[-1]}"
        )
    support = three_two_one(mesh, ids)  # InputError if < 3 nodes, collinear or ill-posed
    check_rigid(mesh, support.fixed_dofs)
    return ClampCondition(tuple(int(k) for k in ids), np.zeros(0, np.int64))


@dataclass(frozen=True)
class HeldCondition(ReferenceCondition):
    """Chosen nodal DOFs held: fixed_dofs (m,) int64 DOF ids 3 node + d, sorted and unique
    (a DOF given twice is held once); nodes: the sorted ids of the nodes they belong to
    (derived from fixed_dofs, the ``nodes`` given are ignored). A ReferenceCondition whose
    fixed DOFs are any number, not six."""

    def __post_init__(self) -> None:
        dofs = np.unique(np.asarray(self.fixed_dofs, dtype=np.int64).ravel())
        dofs.setflags(write=False)
        object.__setattr__(self, "nodes", tuple(int(k) for k in np.unique(dofs // 3)))
        object.__setattr__(self, "fixed_dofs", dofs)


def held_dofs(node_ids, axes) -> np.ndarray:
    """DOF ids 3 k + d of nodes ``node_ids`` and body axes ``axes`` (names of AXES), sorted.
    InputError for an unknown axis name."""
    bad = [a for a in axes if a not in AXES]
    if bad or not len(axes):
        raise InputError(f"held directions must be some of x, y, z, got {list(axes)!r}")
    ids = np.unique(np.asarray(node_ids, dtype=np.int64).ravel())
    d = np.array(sorted({AXES[a] for a in axes}), dtype=np.int64)
    return np.unique((3 * ids[:, None] + d).ravel())


def free_rigid_motions(mesh: Mesh, dofs: np.ndarray, bed: np.ndarray | None = None) -> int:
    """How many of the six rigid-body motions of ``mesh`` the held DOFs ``dofs`` (and the
    6 x 6 stiffness ``bed`` = R^T K_bed R of a spring bed on the rigid modes R about the
    mesh's centroid, rotations per radian) leave free: eigenvalues of the unit-free 6 x 6
    Gram matrix R_h^T R_h / |dofs| + bed / max|bed| (rotations scaled by the mesh's size) below
    1 / RIGID_COND_MAX^2 of its largest (the condition number check_rigid bounds)."""
    pts = mesh.nodes
    centre = pts.mean(axis=0)
    size = float(np.max(np.linalg.norm(pts - centre, axis=1))) or 1.0
    scale = np.r_[np.ones(3), np.full(3, size)]
    gram = np.zeros((6, 6))
    dofs = np.asarray(dofs, dtype=np.int64)
    if dofs.size:
        nodes = np.unique(dofs // 3)
        modes = rigid_body_modes(pts[nodes], centre) / scale
        rows = 3 * np.searchsorted(nodes, dofs // 3) + dofs % 3
        gram += modes[rows].T @ modes[rows] / dofs.size
    if bed is not None:
        b = np.asarray(bed, dtype=float) / np.outer(scale, scale)
        if np.abs(b).max() > 0:
            gram += b / np.abs(b).max()
    lam = np.linalg.eigvalsh(gram)
    return int(np.sum(lam <= lam[-1] / RIGID_COND_MAX**2)) if lam[-1] > 0 else 6


def bed_rigid_stiffness(mesh: Mesh, k_bed) -> np.ndarray:
    """R^T K_bed R (6 x 6): a spring bed's stiffness (fe/spring_bed.py, 3n x 3n) against the
    rigid-body motions R of ``mesh`` about its centroid (translations [N/m], rotations per
    radian): the ``bed`` of free_rigid_motions and held_condition."""
    modes = rigid_body_modes(mesh.nodes, mesh.nodes.mean(axis=0))
    return modes.T @ (k_bed @ modes)


def held_condition(mesh: Mesh, dofs, bed: np.ndarray | None = None) -> HeldCondition:
    """The support holding DOFs ``dofs`` of ``mesh`` (merged: a DOF given twice is held once).

    bed: the 6 x 6 rigid-mode stiffness of a spring bed on the body (free_rigid_motions), which
    may hold what the DOFs leave free. Raises InputError for DOF ids outside the mesh or
    supports that leave a rigid-body motion free (K on the free DOFs would be singular).
    """
    ids = np.unique(np.asarray(dofs, dtype=np.int64).ravel())
    if ids.size and (ids[0] < 0 or ids[-1] >= mesh.n_dof):
        raise InputError(f"held DOF ids must be in 0..{mesh.n_dof - 1}, got {ids[0]}..{ids[-1]}")
    free = free_rigid_motions(mesh, ids, bed)
    if free:
        raise InputError(
            f"the supports hold {ids.size} DOFs of {np.unique(ids // 3).size} nodes and leave "
            f"{free} of the 6 rigid-body motions free; expected supports (with a spring bed) "
            "that fix the body"
        )
    return HeldCondition((), ids)


__all__ = [
    "AXES",
    "ClampCondition",
    "HeldCondition",
    "bed_rigid_stiffness",
    "clamp_condition",
    "free_rigid_motions",
    "held_condition",
    "held_dofs",
]
