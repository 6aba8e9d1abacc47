"""The builder's side of a scenario's ``[[supports]]`` (support_schema.py): a supported body's
reference label, which the setup cache turns into a reduction.clamp condition (the held DOFs
removed from the basis, in place of the 3-2-1 support), and the ground joint that fixes its
frame at its placement.

The caches are keyed by the reference label (body_reference.py). A body clamped on one node
set has the label ``clamp[<node set>]`` (a ClampCondition, as before directional supports
existed); any other combination of a body's supports is merged into
``held[<set>:<axes>;...]``: every set once, sorted by name, with the union of the body axes
its supports hold (a DOF held by two supports is held once), e.g. ``held[end:xyz;far:yz]``.
"""

from __future__ import annotations

import numpy as np

from flexmvm.constraints.joints import ground_joint
from flexmvm.errors import InputError, MeshError
from flexmvm.mesh.mesh import Mesh
from flexmvm.reduction.clamp import (
    AXES,
    ClampCondition,
    HeldCondition,
    clamp_condition,
    held_condition,
    held_dofs,
)
from flexmvm.scenarios.support_schema import AxisFrame, SupportType

_CLAMP_OPEN, _CLAMP_CLOSE = "clamp[", "]"
_HELD_OPEN, _HELD_CLOSE = "held[", "]"


def clamp_set(label: str) -> str | None:
    """The node set of a clamp's reference label; None for any other label."""
    if label.startswith(_CLAMP_OPEN) and label.endswith(_CLAMP_CLOSE):
        return label[len(_CLAMP_OPEN) : -len(_CLAMP_CLOSE)]
    return None


def held_sets(label: str) -> dict[str, str] | None:
    """The node sets and held body axes of a ``held[...]`` label ({set: "xz"}); None for
    any other label."""
    if not (label.startswith(_HELD_OPEN) and label.endswith(_HELD_CLOSE)):
        return None
    inner = label[len(_HELD_OPEN) : -len(_HELD_CLOSE)]
    return dict(part.split(":") for part in inner.split(";"))


def _held_label(sets: dict[str, str]) -> str:
    return _HELD_OPEN + ";".join(f"{k}:{sets[k]}" for k in sorted(sets)) + _HELD_CLOSE


def clamp_reference(mesh: Mesh, label: str) -> ClampCondition | HeldCondition | None:
    """The condition of a support label on ``mesh``: a clamp label's (every DOF of its node
    set held), a held label's (the merged DOFs of its sets and axes); None for another
    label."""
    name = clamp_set(label)
    if name is not None:
        return clamp_condition(mesh, mesh.node_set(name))
    sets = held_sets(label)
    if sets is None:
        return None
    dofs = [held_dofs(mesh.node_set(name), tuple(axes)) for name, axes in sets.items()]
    return held_condition(mesh, np.concatenate(dofs))


def _body_axes(s, rotation: np.ndarray, key: str) -> str:
    """The body axes (a string of x, y, z) that support ``s`` holds; a global direction is
    turned into the body axis along it at the placement ``rotation`` (body -> global)."""
    if s.frame is AxisFrame.BODY:
        return "".join(a.value for a in s.axes)
    axes = []
    for a in s.axes:
        d = rotation.T[:, AXES[a.value]]  # the global axis in body components
        k = int(np.argmax(np.abs(d)))
        if abs(d[k]) < 1.0 - 1e-9:
            raise InputError(
                f"{key}: global direction {a.value} is not along a body axis at the body's "
                f"placement (body components {np.round(d, 6).tolist()}); expected a placement "
                "rotation that maps body axes onto global ones"
            )
        axes.append("xyz"[k])
    return "".join(axes)


def _merged_sets(cfg, supports) -> tuple[dict[str, str], list[int], bool]:
    """The body's supported sets with the union of their held body axes, the indices of its
    supports, and whether they are one clamp on one set."""
    sets: dict[str, set] = {}
    ids = []
    rotation = np.asarray(cfg.placement.rotation.matrix(), float)
    for k, s in enumerate(supports):
        if s.body != cfg.name:
            continue
        ids.append(k)
        axes = _body_axes(s, rotation, f"supports[{k}].frame")
        for name in s.node_sets:
            sets.setdefault(name, set()).update(axes)
    merged = {name: "".join(sorted(axes)) for name, axes in sets.items()}
    single = len(ids) == 1 and supports[ids[0]].type is SupportType.CLAMP and len(sets) == 1
    return merged, ids, single


def _check_retained(cfg, retained, sets, mesh: Mesh, key: str) -> None:
    """InputError if a retained node (region II) is in a supported set: it moves, a held
    one cannot."""
    held = np.concatenate([mesh.node_set(name) for name in sets])
    both = np.intersect1d(np.asarray(retained, np.int64), held)
    if both.size:
        names = sorted(sets)
        raise InputError(
            f"{key}: {both.size} of body {cfg.name!r}'s retained nodes (first "
            f"{both[:5].tolist()}) are in the supported sets {names}; expected none "
            "(retain nodes away from the supports)"
        )


def clamp_label(cfg, mesh: Mesh, supports, retained=()) -> str | None:
    """The reference label of body ``cfg`` if supports hold it, else None. The supported sets
    are checked on ``mesh``: they exist, the merged held DOFs fix the body's rigid motion (a
    single clamp: at least 3 nodes, not on one line), and none of the body's ``retained``
    nodes (region II) is in them (a retained node moves, a held one cannot). InputError (one
    line, naming the support's key) otherwise."""
    sets, ids, single = _merged_sets(cfg, supports)
    if not ids:
        return None
    key = f"supports[{ids[0]}].node_set"
    label = f"{_CLAMP_OPEN}{next(iter(sets))}{_CLAMP_CLOSE}" if single else _held_label(sets)
    try:
        clamp_reference(mesh, label)
        _check_retained(cfg, retained, sets, mesh, key)
    except (MeshError, InputError) as exc:
        where = key if single or len(ids) == 1 else f"supports{ids} of body {cfg.name!r}"
        text = str(exc).removeprefix(f"{key}: ")
        raise InputError(f"{where}: {text}") from None
    return label


def support_joints(supports, index: dict[str, int], states) -> list[list]:
    """Per support, the ground joints (frame fixed at its placement: 6 rows) it adds: the
    first support of each body whose supports fix its frame (ground_frame) adds one, the
    body's other supports none (one frame, fixed once)."""
    groups, grounded = [], set()
    for s in supports:
        joints = []
        if s.ground_frame and s.body not in grounded:
            grounded.add(s.body)
            joints = ground_joint(index[s.body], states)
        groups.append(list(joints))
    return groups


__all__ = ["clamp_label", "clamp_reference", "clamp_set", "held_sets", "support_joints"]
