"""The builder's side of a scenario's ``[[supports]]`` (support_schema.py): a supported body's
reference label, which the setup cache turns into a reduction.clamp condition (the held DOFs
removed from the basis, in place of the 3-2-1 support), and the ground joint that fixes its
frame at its placement.

The caches are keyed by the reference label (body_reference.py). A body clamped on one node
set has the label ``clamp[<node set>]`` (a ClampCondition, as before directional supports
existed); any other combination of a body's supports is merged into
``held[<set>:<axes>;...]``: every set once, sorted by name, with the union of the body axes
its supports hold (a DOF held by two supports is held once), e.g. ``held[end:xyz;far:yz]``,
followed by its spring beds, ``|<surface>:<direction>:<stiffness>;...``, which the rigid-motion
check counts (``held[end:z|bottom:normal:2e+09]``). A body on spring beds has the mesh key
SpringBeds (cache_keys.py): its K holds the beds' stiffness in every cache.
"""

from __future__ import annotations

import numpy as np

from flexmvm.assembly.cache_keys import MergedFile, SpringBeds
from flexmvm.constraints.joints import ground_joint
from flexmvm.errors import InputError, MeshError
from flexmvm.fe.spring_bed import BedDirection, beds_stiffness
from flexmvm.mesh.mesh import Mesh
from flexmvm.mesh.rod import RodSpec
from flexmvm.reduction.clamp import (
    AXES,
    ClampCondition,
    HeldCondition,
    bed_rigid_stiffness,
    clamp_condition,
    held_condition,
    held_dofs,
)
from flexmvm.scenarios.support_schema import AxisFrame, SupportType

#: A spring bed of a body: (facet set, stiffness [N/m^3], body axis or "normal").
Bed = tuple[str, float, str]

_CLAMP_OPEN, _CLAMP_CLOSE = "clamp[", "]"
_HELD_OPEN, _HELD_CLOSE = "held[", "]"


def clamp_set(label: str) -> str | None:
    """The node set of a clamp's reference label; None for any other label."""
    if label.startswith(_CLAMP_OPEN) and label.endswith(_CLAMP_CLOSE):
        return label[len(_CLAMP_OPEN) : -len(_CLAMP_CLOSE)]
    return None


def held_sets(label: str) -> tuple[dict[str, str], tuple[Bed, ...]] | None:
    """The node sets with their held body axes ({set: "xz"}) and the spring beds of a
    ``held[...]`` label; None for any other label."""
    if not (label.startswith(_HELD_OPEN) and label.endswith(_HELD_CLOSE)):
        return None
    inner = label[len(_HELD_OPEN) : -len(_HELD_CLOSE)]
    sets, _, beds = inner.partition("|")
    held = dict(part.split(":") for part in sets.split(";") if part)
    parts = [part.split(":") for part in beds.split(";") if part]
    return held, tuple((name, float(k), d) for name, d, k in parts)


def _held_label(sets: dict[str, str], beds: tuple[Bed, ...]) -> str:
    text = ";".join(f"{k}:{sets[k]}" for k in sorted(sets))
    if beds:
        text += "|" + ";".join(f"{name}:{d}:{k!r}" for name, k, d in beds)
    return _HELD_OPEN + text + _HELD_CLOSE


def clamp_reference(mesh: Mesh, label: str) -> ClampCondition | HeldCondition | None:
    """The condition of a support label on ``mesh``: a clamp label's (every DOF of its node
    set held), a held label's (the merged DOFs of its sets and axes); None for another
    label."""
    name = clamp_set(label)
    if name is not None:
        return clamp_condition(mesh, mesh.node_set(name))
    parts = held_sets(label)
    if parts is None:
        return None
    sets, beds = parts
    dofs = [held_dofs(mesh.node_set(name), tuple(axes)) for name, axes in sets.items()]
    bed = bed_rigid_stiffness(mesh, beds_stiffness(mesh, beds)) if beds else None
    return held_condition(mesh, np.concatenate([np.zeros(0, np.int64), *dofs]), bed)


def _body_axes(s, rotation: np.ndarray, key: str, axes=None) -> str:
    """The body axes (a string of x, y, z) that support ``s`` holds (or ``axes`` of it); a
    global direction is turned into the body axis along it at the placement ``rotation``
    (body -> global)."""
    given = s.axes if axes is None else axes
    if s.frame is AxisFrame.BODY:
        return "".join(a.value for a in given)
    axes = []
    for a in given:
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


def _bed(s, rotation: np.ndarray, key: str) -> Bed:
    """The spring bed of support ``s``, its direction a body axis or "normal"."""
    d = s.direction
    if d is not BedDirection.NORMAL:
        d = _body_axes(s, rotation, key, (d,))
    return (s.surface, float(s.stiffness_n_per_m3), BedDirection(d).value)


def _merged_sets(cfg, supports) -> tuple[dict[str, str], tuple[Bed, ...], list[int], bool]:
    """The body's supported sets with the union of their held body axes, its spring beds
    (sorted), the indices of its supports, and whether they are one clamp on one set."""
    sets: dict[str, set] = {}
    beds: list[Bed] = []
    ids = []
    rotation = np.asarray(cfg.placement.rotation.matrix(), float)
    for k, s in enumerate(supports):
        if s.body != cfg.name:
            continue
        ids.append(k)
        if s.type is SupportType.SPRING_BED:
            beds.append(_bed(s, rotation, f"supports[{k}].frame"))
            continue
        axes = _body_axes(s, rotation, f"supports[{k}].frame")
        for name in s.node_sets:
            sets.setdefault(name, set()).update(axes)
    merged = {name: "".join(sorted(axes)) for name, axes in sets.items()}
    single = len(ids) == 1 and supports[ids[0]].type is SupportType.CLAMP and len(sets) == 1
    return merged, tuple(sorted(beds)), ids, single


def bedded_key(
    key: RodSpec | str | MergedFile, cfg, supports
) -> RodSpec | str | MergedFile | SpringBeds:
    """The mesh key of body ``cfg`` with its spring beds (SpringBeds), or ``key`` itself for
    a body on none."""
    beds = _merged_sets(cfg, supports)[1]
    return SpringBeds(key, beds) if beds else key


def _check_retained(cfg, retained, sets, mesh: Mesh, key: str) -> None:
    """InputError if a retained node (region II) is in a supported set: it moves, a held
    one cannot."""
    held = np.concatenate([np.zeros(0, np.int64), *(mesh.node_set(name) for name in sets)])
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
    sets, beds, ids, single = _merged_sets(cfg, supports)
    if not ids:
        return None
    first = supports[ids[0]]
    key = f"supports[{ids[0]}].{'surface' if first.type is SupportType.SPRING_BED else 'node_set'}"
    if single:
        label = f"{_CLAMP_OPEN}{next(iter(sets))}{_CLAMP_CLOSE}"
    else:
        label = _held_label(sets, beds)
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


__all__ = [
    "bedded_key",
    "clamp_label",
    "clamp_reference",
    "clamp_set",
    "held_sets",
    "support_joints",
]
