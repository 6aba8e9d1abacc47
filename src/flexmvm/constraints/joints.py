"""Joints as bilateral position constraints phi(x) = 0 with their velocity Jacobian rows
(seed eq. 9-11, superscript J). Every joint returns phi (m,) and Rows (m rows of Phi_v).

Points are nodes of a body (for flexible bodies), points at a small body-frame offset from a
node (carried by the node's displacement and the frame's rotation), the centroid of a node set
(NodeSetPoint: a pin in a hole, held by the mean of the hole face's nodes), or points fixed to a
body's frame (body-frame coordinates); the ground is a fixed global point.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import TypeGuard

import numpy as np
import scipy.sparse as sp

from flexmvm.bodies.rotation import cross3
from flexmvm.constraints.rows import Rows
from flexmvm.errors import InputError


class JointType(StrEnum):
    """The joints a scenario can declare (values: the scenario file's ``type``)."""

    GROUND = "ground"  # the body's floating frame fixed at its placement (6 constraints)
    FIXED = "fixed"  # weld at a point: 6 constraints
    SPHERICAL = "spherical"  # point coincidence: 3 constraints
    REVOLUTE = "revolute"  # point coincidence + axis: 5 constraints
    DISTANCE = "distance"  # constant distance between two points (a string): 1 constraint
    PRESCRIBED = "prescribed"  # a point moves with a constant global velocity: 3 constraints
    PRISMATIC = "prismatic"  # slides along a fixed global axis, no rotation: 5 (prismatic.py)


@dataclass(frozen=True)
class BodyPoint:
    """A node (`node`), a point at `offset_m` (body frame [m]) from a node, or a frame-attached
    point (`local`, body frame [m]) of body `body`.

    With an offset the point is x_k + A offset: it moves with node k's elastic displacement and
    turns with the frame, not with the material's local elastic rotation; the error is that
    rotation times |offset| (for a string 0.01 m from a node of a sagging rod, ~1e-4 rad x 0.01 m
    = 1e-6 m, against 0.01 m if the node itself were taken)."""

    body: int
    node: int | None = None
    local: tuple[float, float, float] | None = None
    offset_m: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        if (self.node is None) == (self.local is None):
            raise InputError("a body point needs exactly one of a node id or a frame point")
        if self.offset_m is not None and self.node is None:
            raise InputError("a body point's offset_m is measured from a node: give node too")

    def position(self, bodies, states) -> np.ndarray:
        st = states[self.body]
        if self.node is not None:
            x = bodies[self.body].node_positions(np.array([self.node]), st.r, st.A, st.q)[0]
            return x if self.offset_m is None else x + st.A @ np.asarray(self.offset_m)
        return st.r + st.A @ np.asarray(self.local)

    def add_row(self, rows: Rows, row: int, direction, sign: float, bodies, states) -> None:
        """rows[row] += sign * d^T dx/dv for this point (with its nodal selector entries:
        node k's DOFs times A^T d, none for a frame point)."""
        body = bodies[self.body]
        st = states[self.body]
        d = np.asarray(direction, float)
        if self.node is not None:
            fr, qp = body.point_jacobian(self.node, st.A, st.q, d)
            if self.offset_m is not None:
                fr = fr + np.concatenate(
                    [np.zeros(3), cross3(np.asarray(self.offset_m, float), st.A.T @ d)]
                )
            nodal = (
                3 * self.node + np.arange(3),
                sign * (st.A.T @ d),
                body.psi.shape[0] if body.nq else 0,
            )
        else:
            p = np.asarray(self.local, float)
            fr = np.concatenate([d, cross3(p, st.A.T @ d)])
            qp = np.zeros(body.nq)
            nodal = _no_elastic(body)
        rows.add(row, self.body, sign * fr, sign * qp, body.nq, nodal)

    def add_rows(self, rows: Rows, row0: int, directions, sign: float, bodies, states) -> None:
        """add_row for each direction (rows of `directions` (k, 3)) into rows row0.. (the
        same arithmetic; a frame point's k rows added as one block)."""
        if self.node is not None:
            for i, d in enumerate(directions):
                self.add_row(rows, row0 + i, d, sign, bodies, states)
            return
        body = bodies[self.body]
        A = states[self.body].A
        p = np.asarray(self.local, float)
        k = len(directions)
        frame = np.empty((k, 6))
        for i, d in enumerate(directions):
            d = np.asarray(d, float)
            frame[i, :3], frame[i, 3:] = d, cross3(p, A.T @ d)
        nodal = [_no_elastic(body)] * k
        rows.add_block(row0, self.body, sign * frame, sign * np.zeros((k, body.nq)), body.nq, nodal)


@dataclass(frozen=True, eq=False)
class NodeSetPoint:
    """The centroid of the nodes `nodes` of body `body`, all weighted alike:

        x_bar = (1/n) sum_k x_k = r + A (X_bar + psi_bar q),   psi_bar = (1/n) sum_k psi_k

    (an averaging constraint, the interpolation element RBE3 of Nastran with equal weights).
    A joint on it holds the set's mean motion and leaves the set free to deform: a pin in a
    hole, where a joint on one node of the hole face would hold that node against the whole
    body (a point load, singular in 3D elasticity). For a reduced body the rows are those of
    the set's rows of psi, retained or not: the basis interpolates every node. Made by
    :meth:`of`, which averages X (3,) and psi (3, nq, dense) once."""

    body: int
    nodes: tuple[int, ...]
    X_bar: np.ndarray
    psi_bar: np.ndarray

    @classmethod
    def of(cls, index: int, body, nodes) -> NodeSetPoint:
        """The centroid of `nodes` (node ids of `body`, the body at `index` of the system)."""
        ids = np.unique(np.asarray(nodes, np.int64))
        if not ids.size:
            raise InputError("a node-set point needs at least one node")
        idx = (3 * ids[:, None] + np.arange(3)).ravel()
        psi_bar = (
            np.asarray(body.psi[idx, :].todense() if sp.issparse(body.psi) else body.psi[idx, :])
            .reshape(len(ids), 3, body.nq)
            .mean(axis=0)
            if body.nq
            else np.zeros((3, 0))
        )
        return cls(index, tuple(int(k) for k in ids), body.X[ids].mean(axis=0), psi_bar)

    def _local(self, q) -> np.ndarray:
        return self.X_bar + (self.psi_bar @ q if self.psi_bar.shape[1] else 0.0)

    def position(self, bodies, states) -> np.ndarray:
        st = states[self.body]
        return st.r + st.A @ self._local(st.q)

    def add_row(self, rows: Rows, row: int, direction, sign: float, bodies, states) -> None:
        """rows[row] += sign * d^T dx_bar/dv: frame part [d, s_bar x A^T d], elastic part
        psi_bar^T A^T d. No nodal selector: through the cached nodal columns of W_qq^-1
        (integrate.moreau_jean.compliance) a row on every DOF of a hole face would gather those
        columns at every iterate, dearer than one back-substitution with the rows' columns
        (docs/notes/2026-11-27-comment-measurements.md, "Joints")."""
        body = bodies[self.body]
        st = states[self.body]
        d = np.asarray(direction, float)
        dl = st.A.T @ d
        fr = np.concatenate([d, cross3(self._local(st.q), dl)])
        qp = self.psi_bar.T @ dl
        rows.add(
            row, self.body, sign * fr, sign * qp, body.nq, None if body.nq else _no_elastic(body)
        )

    def add_rows(self, rows: Rows, row0: int, directions, sign: float, bodies, states) -> None:
        """add_row for each direction (rows of `directions` (k, 3)) into rows row0.., as one
        block: the centroid's body-frame position once, the same products per row."""
        body = bodies[self.body]
        A = states[self.body].A
        s_bar = self._local(states[self.body].q)
        k = len(directions)
        frame, elastic = np.empty((k, 6)), np.empty((k, body.nq))
        for i, d in enumerate(directions):
            d = np.asarray(d, float)
            dl = A.T @ d
            frame[i, :3], frame[i, 3:] = d, cross3(s_bar, dl)
            elastic[i] = self.psi_bar.T @ dl
        nodal = None if body.nq else [_no_elastic(body)] * k
        rows.add_block(row0, self.body, sign * frame, sign * elastic, body.nq, nodal)


Anchor = BodyPoint | NodeSetPoint | np.ndarray
_AXES = np.eye(3)  # the rows' directions of a point coincidence (read only)
_AXES.flags.writeable = False


def _on_body(a: Anchor) -> TypeGuard[BodyPoint | NodeSetPoint]:
    return isinstance(a, (BodyPoint, NodeSetPoint))


def _anchor_position(a: Anchor, bodies, states) -> np.ndarray:
    return a.position(bodies, states) if _on_body(a) else np.asarray(a, float)


class Joint:
    """Base: n_rows rows; evaluate(bodies, states, t) -> (phi, Rows); time_rate: the explicit
    time derivative d phi / d t at fixed configuration (zero but for prescribed motions), so
    that d phi / d t = Phi_v v + time_rate along a motion."""

    n_rows: int = 0

    def evaluate(self, bodies, states, t: float) -> tuple[np.ndarray, Rows]:
        raise NotImplementedError

    def value(self, bodies, states, t: float) -> np.ndarray:
        """phi (n_rows,) alone, as evaluate's (the same arithmetic): the Newton iteration
        needs phi at the step's end and the rows at the midpoint only, and building rows it
        throws away was half of a mechanism's joint work a step."""
        return self.evaluate(bodies, states, t)[0]

    def time_rate(self, bodies, states, t: float) -> np.ndarray:
        return np.zeros(self.n_rows)

    @property
    def pivot(self) -> BodyPoint | NodeSetPoint | None:
        """The body point the joint holds (its p1), which an initial spin of its body may
        turn about; None for a joint without one (an orientation lock, a drive row)."""
        return None


@dataclass(frozen=True)
class SphericalJoint(Joint):
    """Coincident points: x_1 - x_2 = 0 (3 rows); p2 may be a ground point."""

    p1: BodyPoint | NodeSetPoint
    p2: Anchor
    n_rows: int = 3

    @property
    def pivot(self) -> BodyPoint | NodeSetPoint:
        return self.p1

    def value(self, bodies, states, t):
        return self.p1.position(bodies, states) - _anchor_position(self.p2, bodies, states)

    def evaluate(self, bodies, states, t):
        phi = self.value(bodies, states, t)
        rows = Rows(3)
        self.p1.add_rows(rows, 0, _AXES, 1.0, bodies, states)
        if _on_body(self.p2):
            self.p2.add_rows(rows, 0, _AXES, -1.0, bodies, states)
        return phi, rows


@dataclass(frozen=True)
class DistanceJoint(Joint):
    """A massless inextensible string or rod: |x_1 - x_2| - length = 0 (1 row)."""

    p1: BodyPoint | NodeSetPoint
    p2: Anchor
    length: float
    n_rows: int = 1

    @property
    def pivot(self) -> BodyPoint | NodeSetPoint:
        return self.p1

    def __post_init__(self) -> None:
        if not self.length > 0:
            raise InputError(f"distance joint length must be > 0 m, got {self.length!r}")

    def value(self, bodies, states, t):
        d = self.p1.position(bodies, states) - _anchor_position(self.p2, bodies, states)
        return np.array([float(np.linalg.norm(d)) - self.length])

    def evaluate(self, bodies, states, t):
        d = self.p1.position(bodies, states) - _anchor_position(self.p2, bodies, states)
        dist = float(np.linalg.norm(d))
        e = d / dist
        rows = Rows(1)
        self.p1.add_row(rows, 0, e, 1.0, bodies, states)
        if _on_body(self.p2):
            self.p2.add_row(rows, 0, e, -1.0, bodies, states)
        return np.array([dist - self.length]), rows


@dataclass(frozen=True)
class PrescribedMotion(Joint):
    """A point moving with a prescribed velocity: x(t) - (x0 + v t) = 0 (3 rows)."""

    p1: BodyPoint | NodeSetPoint
    x0: tuple[float, float, float]
    velocity: tuple[float, float, float]
    n_rows: int = 3

    @property
    def pivot(self) -> BodyPoint | NodeSetPoint:
        return self.p1

    def value(self, bodies, states, t):
        target = np.asarray(self.x0) + np.asarray(self.velocity) * t
        return self.p1.position(bodies, states) - target

    def evaluate(self, bodies, states, t):
        phi = self.value(bodies, states, t)
        rows = Rows(3)
        self.p1.add_rows(rows, 0, _AXES, 1.0, bodies, states)
        return phi, rows

    def time_rate(self, bodies, states, t):
        return -np.asarray(self.velocity, float)


@dataclass(frozen=True)
class OrientationLock(Joint):
    """Frame directions kept perpendicular: (A1 u_i) . (A2 w_i) = 0 for each pair (u_i, w_i).

    With body 2 = None the second direction is a fixed global vector. Used for revolute
    (2 pairs) and fixed (3 pairs) joints. Row of d/dt: w1 . (u x A1^T d2) + w2 . (w x A2^T d1).
    """

    body1: int
    body2: int | None
    pairs: tuple[tuple[tuple[float, ...], tuple[float, ...]], ...]

    @property
    def n_rows(self) -> int:  # type: ignore[override]
        return len(self.pairs)

    def value(self, bodies, states, t):
        phi = np.zeros(len(self.pairs))
        A1 = states[self.body1].A
        A2 = states[self.body2].A if self.body2 is not None else np.eye(3)
        for i, (u, w) in enumerate(self.pairs):
            phi[i] = (A1 @ np.asarray(u, float)) @ (A2 @ np.asarray(w, float))
        return phi

    def evaluate(self, bodies, states, t):
        rows = Rows(len(self.pairs))
        phi = np.zeros(len(self.pairs))
        A1 = states[self.body1].A
        A2 = states[self.body2].A if self.body2 is not None else np.eye(3)
        for i, (u, w) in enumerate(self.pairs):
            u, w = np.asarray(u, float), np.asarray(w, float)
            d1, d2 = A1 @ u, A2 @ w
            phi[i] = d1 @ d2
            fr = np.concatenate([np.zeros(3), cross3(u, A1.T @ d2)])
            b1 = bodies[self.body1]
            rows.add(i, self.body1, fr, np.zeros(b1.nq), b1.nq, _no_elastic(b1))
            if self.body2 is not None:
                fr2 = np.concatenate([np.zeros(3), cross3(w, A2.T @ d1)])
                b2 = bodies[self.body2]
                rows.add(i, self.body2, fr2, np.zeros(b2.nq), b2.nq, _no_elastic(b2))
        return phi, rows


def _no_elastic(body) -> tuple[np.ndarray, np.ndarray, int]:
    """Nodal selector entries of a row without elastic part: none."""
    return np.zeros(0, np.int64), np.zeros(0), body.psi.shape[0] if body.nq else 0


def _perpendicular_pair(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a = axis / np.linalg.norm(axis)
    t = np.eye(3)[int(np.argmin(np.abs(a)))]
    b = np.cross(a, t)
    b /= np.linalg.norm(b)
    return b, np.cross(a, b)


def revolute_joint(p1: BodyPoint | NodeSetPoint, p2: Anchor, axis_global, states) -> list[Joint]:
    """Spherical joint plus two orientation rows keeping body 1's axis along axis_global."""
    axis = np.asarray(axis_global, float)
    if not np.linalg.norm(axis) > 0:
        raise InputError("revolute joint axis must be non-zero")
    b, c = _perpendicular_pair(axis)
    A1 = states[p1.body].A
    u = A1.T @ (axis / np.linalg.norm(axis))
    body2 = p2.body if _on_body(p2) else None
    A2 = states[body2].A if body2 is not None else np.eye(3)
    pairs = tuple((tuple(u), tuple(A2.T @ w)) for w in (b, c))
    return [SphericalJoint(p1, p2), OrientationLock(p1.body, body2, pairs)]


def fixed_joint(p1: BodyPoint | NodeSetPoint, p2: Anchor, states) -> list[Joint]:
    """Spherical joint plus three orientation rows: no relative rotation."""
    A1 = states[p1.body].A
    body2 = p2.body if _on_body(p2) else None
    A2 = states[body2].A if body2 is not None else np.eye(3)
    e = np.eye(3)
    pairs = tuple((tuple(A1.T @ e[i]), tuple(A2.T @ e[j])) for i, j in ((0, 1), (1, 2), (2, 0)))
    return [SphericalJoint(p1, p2), OrientationLock(p1.body, body2, pairs)]


def ground_joint(body: int, states) -> list[Joint]:
    """Fix a body's frame to the ground at its current pose."""
    return fixed_joint(BodyPoint(body, local=(0.0, 0.0, 0.0)), states[body].r.copy(), states)
