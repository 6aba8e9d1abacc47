"""A clamped support: every displacement DOF of a node set held, in place of the floating
frame's 3-2-1 reference condition.

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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError
from flexmvm.mesh.mesh import Mesh
from flexmvm.reduction.reference import ReferenceCondition, check_rigid, three_two_one


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


__all__ = ["ClampCondition", "clamp_condition"]
