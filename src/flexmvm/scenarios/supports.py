"""The builder's side of a scenario's ``[[supports]]`` (support_schema.py): a clamped body's
reference label, which the setup cache turns into a reduction.clamp.ClampCondition (every DOF
of the set held, in place of the 3-2-1 support), and the ground joint that fixes its frame at
its placement.

The caches are keyed by the reference label (body_reference.py); a clamp's is
``clamp[<node set>]``, so a clamped body and the same body free get different bases.
"""

from __future__ import annotations

import numpy as np

from flexmvm.constraints.joints import ground_joint
from flexmvm.errors import InputError, MeshError
from flexmvm.mesh.mesh import Mesh
from flexmvm.reduction.clamp import ClampCondition, clamp_condition

_CLAMP_OPEN, _CLAMP_CLOSE = "clamp[", "]"


def clamp_set(label: str) -> str | None:
    """The node set of a clamp's reference label; None for any other label."""
    if label.startswith(_CLAMP_OPEN) and label.endswith(_CLAMP_CLOSE):
        return label[len(_CLAMP_OPEN) : -len(_CLAMP_CLOSE)]
    return None


def clamp_reference(mesh: Mesh, label: str) -> ClampCondition | None:
    """The clamp of a clamp label on ``mesh`` (every DOF of its node set held); None for
    another label."""
    name = clamp_set(label)
    return None if name is None else clamp_condition(mesh, mesh.node_set(name))


def clamp_label(cfg, mesh: Mesh, supports, retained=()) -> str | None:
    """The reference label of body ``cfg`` if a support clamps it, else None. The clamped set
    is checked on ``mesh``: it exists and its nodes fix the body (at least 3, not on one
    line), and none of the body's ``retained`` nodes (region II) is in it (a retained node
    moves, a clamped one cannot). InputError (one line, naming the support's key) otherwise."""
    for k, s in enumerate(supports):
        if s.body != cfg.name:
            continue
        key = f"supports[{k}].node_set"
        try:
            clamp = clamp_condition(mesh, mesh.node_set(s.node_set))
        except (MeshError, InputError) as exc:
            raise InputError(f"{key}: {exc}") from None
        both = np.intersect1d(np.asarray(retained, np.int64), clamp.nodes)
        if both.size:
            raise InputError(
                f"{key}: {both.size} of body {cfg.name!r}'s retained nodes (first "
                f"{both[:5].tolist()}) are in the clamped set {s.node_set!r}; expected none "
                "(retain nodes away from the clamp)"
            )
        return f"{_CLAMP_OPEN}{s.node_set}{_CLAMP_CLOSE}"
    return None


def support_joints(supports, index: dict[str, int], states) -> list:
    """The ground joints (frame fixed at its placement: 6 rows) of the clamped bodies whose
    frame the clamp fixes (ground_frame)."""
    joints = []
    for s in supports:
        if s.ground_frame:
            joints.extend(ground_joint(index[s.body], states))
    return joints


__all__ = ["clamp_label", "clamp_reference", "clamp_set", "support_joints"]
