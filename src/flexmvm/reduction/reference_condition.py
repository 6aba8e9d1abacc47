"""Reference condition of the floating frame: a 3-2-1 support (six fixed nodal DOFs).

The body frame is attached to the body by clamping six displacement components of three
nodes A, B, C (Shabana, Dynamics of Multibody Systems, ch. 5): A all three, B two, C one.
Every basis of flexmvm.reduction has zero rows at these DOFs, so the elastic coordinates q
carry no rigid-body motion. Choose the nodes far from any contact (for a rod: end B; for a
mesh body without a named set: far_reference, the nodes farthest from its contact surfaces).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError
from flexmvm.mesh.mesh import Mesh

#: Largest accepted condition number of the 6x6 rigid-mode matrix at the fixed DOFs
#: (rotations scaled by the size of the support, so the number is unit-free).
RIGID_COND_MAX = 1e8


def rigid_body_modes(points: np.ndarray, centre: np.ndarray | None = None) -> np.ndarray:
    """Rigid-body displacement fields of a point cloud, shape (3p, 6), node-major rows.

    Columns: unit translations x, y, z, then unit rotations about x, y, z through ``centre``
    (default: the centroid): u_k = omega x (X_k - centre). points: (p, 3) [m].
    """
    pts = np.asarray(points, dtype=float)
    rel = pts - (pts.mean(axis=0) if centre is None else np.asarray(centre, dtype=float))
    modes = np.zeros((len(pts), 3, 6))
    modes[:, :, :3] = np.eye(3)
    for axis in range(3):
        modes[:, :, 3 + axis] = np.cross(np.eye(3)[axis], rel)
    return modes.reshape(-1, 6)


def _rigid_condition(mesh: Mesh, dofs: np.ndarray) -> float:
    """Condition number of the rigid-body modes restricted to ``dofs`` (6x6, scaled)."""
    nodes = np.unique(dofs // 3)
    pts = mesh.nodes[nodes]
    centre = pts.mean(axis=0)
    size = float(np.max(np.linalg.norm(pts - centre, axis=1)))
    modes = rigid_body_modes(pts, centre)
    modes[:, 3:] /= size if size > 0 else 1.0
    rows = 3 * np.searchsorted(nodes, dofs // 3) + dofs % 3
    r = modes[rows]
    return float(np.linalg.cond(r)) if np.all(np.isfinite(r)) else np.inf


@dataclass(frozen=True)
class ReferenceCondition:
    """Six clamped displacement DOFs that fix the floating frame.

    nodes: the support's node ids (A, B, C for a 3-2-1 support); fixed_dofs: (6,) int64
    global DOF ids 3*node + d. Raises InputError unless fixed_dofs holds 6 distinct ids >= 0
    belonging to ``nodes``.
    """

    nodes: tuple[int, ...]
    fixed_dofs: np.ndarray

    def __post_init__(self) -> None:
        dofs = np.asarray(self.fixed_dofs)
        if dofs.shape != (6,) or not np.issubdtype(dofs.dtype, np.integer):
            raise InputError(
                f"reference condition needs 6 integer DOF ids, got {self.fixed_dofs!r}"
            )
        dofs = dofs.astype(np.int64)
        if len(np.unique(dofs)) != 6 or dofs.min() < 0:
            raise InputError(f"reference DOF ids must be 6 distinct ids >= 0, got {dofs.tolist()}")
        nodes = tuple(int(k) for k in self.nodes)
        if set(np.unique(dofs // 3).tolist()) != set(nodes):
            raise InputError(f"reference nodes {nodes} do not match DOFs {dofs.tolist()}")
        dofs.setflags(write=False)
        object.__setattr__(self, "nodes", nodes)
        object.__setattr__(self, "fixed_dofs", dofs)

    @classmethod
    def from_dofs(cls, mesh: Mesh, fixed_dofs: np.ndarray) -> ReferenceCondition:
        """A reference condition from six explicit DOF ids 3*node + d.

        Raises InputError if a DOF is outside the mesh or the six DOFs do not fix the
        rigid-body motion (condition number of the rigid modes there > RIGID_COND_MAX).
        """
        dofs = np.asarray(fixed_dofs).ravel()
        if (
            dofs.size
            and np.issubdtype(dofs.dtype, np.integer)
            and (dofs.min() < 0 or dofs.max() >= mesh.n_dof)
        ):
            raise InputError(
                f"reference DOF ids must be in 0..{mesh.n_dof - 1}, got {dofs.tolist()}"
            )
        nodes = tuple(dict.fromkeys(int(d) // 3 for d in dofs)) if dofs.size else ()
        ref = cls(nodes, dofs)
        check_rigid(mesh, ref.fixed_dofs)
        return ref

    def free_dofs(self, n_dof: int) -> np.ndarray:
        """Sorted DOF ids in 0..n_dof-1 that the reference condition leaves free."""
        return np.setdiff1d(np.arange(n_dof), self.fixed_dofs)


def check_rigid(mesh: Mesh, dofs: np.ndarray) -> None:
    cond = _rigid_condition(mesh, dofs)
    if not cond <= RIGID_COND_MAX:
        raise InputError(
            f"reference DOFs {dofs.tolist()} do not fix the rigid-body motion (condition number "
            f"{cond:.3g} of the rigid modes there, expected <= {RIGID_COND_MAX:g})"
        )


def three_two_one(mesh: Mesh, node_ids: np.ndarray) -> ReferenceCondition:
    """Choose a 3-2-1 support among ``node_ids`` (e.g. a rod's end_b node set).

    A = node closest to the set's centroid: x, y, z fixed.
    B = node farthest from A: the two global components least aligned with AB fixed.
    C = node maximising |AB x AC|: the global component most aligned with AB x AC fixed.
    Raises InputError for ids outside the mesh, fewer than 3 distinct nodes, collinear nodes,
    or a support that does not fix the rigid-body motion.
    """
    ids = np.unique(np.asarray(node_ids, dtype=np.int64).ravel())
    if ids.size < 3:
        raise InputError(f"a 3-2-1 support needs at least 3 distinct nodes, got {ids.size}")
    if ids[0] < 0 or ids[-1] >= mesh.n_nodes:
        raise InputError(
            f"support node ids must be in 0..{mesh.n_nodes - 1}, got {ids[0]}..{ids[-1]}"
        )
    pts = mesh.nodes[ids]
    a = int(np.argmin(np.linalg.norm(pts - pts.mean(axis=0), axis=1)))
    ab_all = pts - pts[a]
    b = int(np.argmax(np.linalg.norm(ab_all, axis=1)))
    ab = ab_all[b]
    normals = np.cross(ab, ab_all)
    c = int(np.argmax(np.linalg.norm(normals, axis=1)))
    n = normals[c]
    if np.linalg.norm(n) <= 1e-9 * float(ab @ ab):
        raise InputError(f"support nodes {ids.tolist()[:10]}... are collinear; need a plane")
    node_a, node_b, node_c = (int(ids[k]) for k in (a, b, c))
    b_dirs = np.sort(np.argsort(np.abs(ab), kind="stable")[:2])
    c_dir = int(np.argmax(np.abs(n)))
    dofs = np.concatenate([3 * node_a + np.arange(3), 3 * node_b + b_dirs, [3 * node_c + c_dir]])
    ref = ReferenceCondition((node_a, node_b, node_c), dofs.astype(np.int64))
    check_rigid(mesh, ref.fixed_dofs)
    return ref


#: Shares of the largest node distance from the contacts that a support node must reach, tried
#: in turn (the first that gives a well-conditioned support wins): 0.9 keeps the support in
#: the far zone of a body; the lower ones serve bodies whose far zone is a point or a line
#: (a sphere whose whole skin is a contact surface: its centre).
AUTO_FAR_SHARES = (0.9, 0.8, 0.6, 0.4, 0.2, 0.0)

#: Largest scaled rigid-mode condition number (see _rigid_condition) of an automatic support:
#: a compact triangle measures ~3, one spanning a slender beam (height 1/20 of its base) ~30,
#: three nodes of one straight edge are singular (inf).
AUTO_COND_MAX = 1e4


def far_reference(mesh: Mesh, contact_nodes: np.ndarray) -> ReferenceCondition:
    """A 3-2-1 support chosen far from the contacts, for a body without a named reference set.

    d_k = distance [m] of node k from the nearest of ``contact_nodes`` (the nodes of the
    body's contact surfaces; none given: the distance from the nodes' centroid, a support on
    the body's periphery). For each share s of AUTO_FAR_SHARES in turn, the candidates are the
    nodes with d_k >= s max(d), and three_two_one picks A, B, C among them (A nearest their
    centroid, B farthest from A, C spanning the largest triangle); the first support whose
    scaled rigid-mode condition number is <= AUTO_COND_MAX (three non-collinear nodes, a
    triangle not too slender to fix the frame's rotation) is returned. Far nodes because the
    frame must not follow the contact's local deformation (DESIGN.md, Bodies). Raises
    InputError if no share gives such a support (a mesh whose nodes are all on one line).
    """
    x = mesh.nodes
    ids = np.unique(np.asarray(contact_nodes, dtype=np.int64).ravel())
    if ids.size:
        from scipy.spatial import cKDTree  # here: scipy.spatial is slow to import

        d = cKDTree(x[ids]).query(x)[0]
    else:
        d = np.linalg.norm(x - x.mean(axis=0), axis=1)
    best = np.inf
    for share in AUTO_FAR_SHARES:
        candidates = np.flatnonzero(d >= share * d.max())
        if candidates.size < 3:
            continue
        try:
            ref = three_two_one(mesh, candidates)
        except InputError:
            continue
        cond = _rigid_condition(mesh, ref.fixed_dofs)
        if cond <= AUTO_COND_MAX:
            return ref
        best = min(best, cond)
    raise InputError(
        f"no well-conditioned 3-2-1 support far from the contacts: best scaled "
        f"condition number {best:.3g}, expected <= {AUTO_COND_MAX:g} (nodes on one "
        f"line?); name a reference node set instead"
    )


__all__ = [
    "AUTO_COND_MAX",
    "AUTO_FAR_SHARES",
    "RIGID_COND_MAX",
    "ReferenceCondition",
    "far_reference",
    "rigid_body_modes",
    "three_two_one",
]
