"""Constructors of a mechanism's scenario tables from Python: one function per table of
docs/scenario_format.md (joints with their drives and paths, supports, loads, spring-dampers,
a body's damping and initial rigid motion), its keyword arguments the table's keys, SI units
in their names. Each returns the validated table (a frozen pydantic model, as ``load_scenario``
makes from a file) or raises one ScenarioError line naming the call and the key, as
``fm.mvm`` and ``fm.full`` do for a body's model.

The tables go where a scenario dict takes them (``fm.scenario_from_dict``), beside plain dicts::

    data["joints"] = [fm.joint("revolute", "arm", node_set="hub", axis=(0, 0, 1),
                               drive=fm.drive(angular_velocity_radps=fm.spin_up(20.0, 0.02)))]

Keys left as None are left out (the table's default applies).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from pydantic import BaseModel

from flexmvm.scenarios.damping_schema import DampingConfig
from flexmvm.scenarios.drive_schema import DriveConfig, HistoryConfig, PathConfig
from flexmvm.scenarios.initial_motion import RigidMotionConfig
from flexmvm.scenarios.joint_schema import JointConfig
from flexmvm.scenarios.load_schema import LoadConfig, SpringConfig
from flexmvm.scenarios.problems import validate_part
from flexmvm.scenarios.support_schema import SupportConfig

Vector = Sequence[float]

__all__ = [
    "applied_load",
    "clamp",
    "damping",
    "drive",
    "joint",
    "prescribed_path",
    "rigid_motion",
    "spin_up",
    "spring",
]


def _table(cls: type[BaseModel], call: str, keys: dict[str, Any]):
    """``cls`` validated from the given (not None) ``keys``; ScenarioError naming ``call``."""
    return validate_part(cls, {k: v for k, v in keys.items() if v is not None}, call)


def _history(value: Any) -> Any:
    """A motion history from a HistoryConfig, a number (constant) or rows [[t_s, value], ...]
    (a table, piecewise linear); other values are passed on for the table's own error."""
    if value is None or isinstance(value, HistoryConfig):
        return value
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return {"constant": value}
    return {"table": value}


def spin_up(final: float, duration_s: float) -> HistoryConfig:
    """The smooth spin-up profile of Kane, Ryan and Banerjee (1987), a motion history for
    :func:`drive`: f(t) = (f_s / T)(t - T / (2 pi) sin(2 pi t / T)) for 0 <= t < T, f_s after,
    its rate zero at both ends. ``final``: f_s (an angular velocity [rad/s] under
    ``angular_velocity_radps``, an angle [rad] under ``angle_rad``); ``duration_s``: T [s],
    > 0."""
    data = {"spin_up": {"final": final, "duration_s": duration_s}}
    return validate_part(HistoryConfig, data, f"spin_up({final!r}, {duration_s!r})")


def drive(*, angle_rad: Any = None, angular_velocity_radps: Any = None) -> DriveConfig:
    """A joint's drive (the ``drive`` of a revolute joint, or of a prescribed one with an
    axis): its rotation from the placement prescribed by exactly one history, the angle
    ``angle_rad`` [rad] (0 at t = 0) or its rate ``angular_velocity_radps`` [rad/s]
    (integrated from 0 analytically). Each history is a number (constant), rows
    [[t_s, value], ...] (piecewise linear, held at its end values outside) or
    :func:`spin_up`. The joint's multiplier is then the drive torque [N m]
    (``RunResult.drive_torque[name]``)."""
    keys = {
        "angle_rad": _history(angle_rad),
        "angular_velocity_radps": _history(angular_velocity_radps),
    }
    return _table(DriveConfig, "drive(...)", keys)


def prescribed_path(*, displacement_m: Any = None, velocity_mps: Any = None) -> PathConfig:
    """A prescribed joint's path: exactly one of ``displacement_m`` rows [[t_s, dx, dy, dz],
    ...] (global [m], zero at t = 0) and ``velocity_mps`` rows [[t_s, vx, vy, vz], ...]
    (global [m/s], integrated from 0); piecewise linear, held at the end values outside."""
    keys = {"displacement_m": displacement_m, "velocity_mps": velocity_mps}
    return _table(PathConfig, "prescribed_path(...)", keys)


def joint(
    type: str,
    body: str,
    *,
    name: str | None = None,
    point_m: Vector | None = None,
    node_set: str | None = None,
    ground_m: Vector | None = None,
    body2: str | None = None,
    point2_m: Vector | None = None,
    axis: Vector | None = None,
    length_m: float | None = None,
    velocity_mps: Vector | None = None,
    drive: DriveConfig | None = None,
    path: PathConfig | None = None,
) -> JointConfig:
    """A ``[[joints]]`` entry: ``type`` one of ground, fixed, spherical, revolute, distance,
    prismatic, prescribed, on ``body``; ``point_m`` body-local [m] or ``node_set`` (its centroid),
    to the ground point ``ground_m`` (global [m]) or to ``point2_m`` of ``body2``; ``axis``
    (global at t = 0) of a revolute or prismatic joint; ``length_m`` [m] of a distance joint; a
    prescribed point's ``velocity_mps`` [m/s] or ``path``; a revolute joint's ``drive`` (:func:`drive`).
    The keys each type needs and allows: docs/scenario_format.md, "[[joints]]"."""
    keys = dict(locals())
    return _table(JointConfig, f"joint({type!r}, {body!r})", keys)


def clamp(body: str, node_set: str, *, ground_frame: bool = True) -> SupportConfig:
    """A ``[[supports]]`` clamp: every displacement of ``body``'s node set ``node_set`` held
    by removal from the basis (not by constraint rows), and with ``ground_frame`` the body's
    frame fixed at its placement; ``ground_frame=False`` holds the set in the body's frame
    only, which the scenario's joints move (a cantilever on a driven hub)."""
    keys = {"type": "clamp", "body": body, "node_set": node_set, "ground_frame": ground_frame}
    return _table(SupportConfig, f"clamp({body!r}, {node_set!r})", keys)


def applied_load(
    type: str,
    *,
    body: str | None = None,
    point_m: Vector | None = None,
    node_set: str | None = None,
    joint: int | None = None,
    frame: str | None = None,
    force_n: Any = None,
    torque_nm: Any = None,
    times_s: Sequence[float] | None = None,
    name: str | None = None,
) -> LoadConfig:
    """A ``[[loads]]`` entry: ``"force"`` ``force_n`` [N] at ``point_m`` (body-local [m]) or
    the centroid of ``node_set`` of ``body``; ``"torque"`` ``torque_nm`` [N m] on ``body``'s
    frame; ``"motor"`` ``torque_nm`` [N m] about the axis of revolute ``joint`` (its index
    in the joints). A constant, or one value per time of ``times_s`` [s] (piecewise linear);
    ``frame="body"`` turns a force or torque with the body (a follower load), ``"global"``
    (default) keeps it fixed in space; ``name`` keys its work in the energy ledger."""
    keys = dict(locals())
    return _table(LoadConfig, f"applied_load({type!r})", keys)


def spring(
    type: str = "linear",
    *,
    body: str | None = None,
    point_m: Vector | None = None,
    node_set: str | None = None,
    body2: str | None = None,
    point2_m: Vector | None = None,
    ground_m: Vector | None = None,
    joint: int | None = None,
    stiffness_n_per_m: float | None = None,
    damping_n_s_per_m: float | None = None,
    rest_length_m: float | None = None,
    stiffness_nm_per_rad: float | None = None,
    damping_nms_per_rad: float | None = None,
    rest_angle_deg: float | None = None,
    name: str | None = None,
) -> SpringConfig:
    """A ``[[springs]]`` spring-damper. ``"linear"``: tension k (l - l0) + c l_dot
    (``stiffness_n_per_m`` [N/m], ``damping_n_s_per_m`` [N s/m], ``rest_length_m`` l0 [m],
    default the initial distance) between a point of ``body`` (``point_m`` or ``node_set``)
    and ``point2_m`` of ``body2`` or the ground point ``ground_m`` (global [m]).
    ``"rotational"``: torque -k (phi - phi0) - c phi_dot on the relative angle of revolute
    ``joint`` (``stiffness_nm_per_rad``, ``damping_nms_per_rad``, ``rest_angle_deg``)."""
    keys = dict(locals())
    return _table(SpringConfig, f"spring({type!r})", keys)


def damping(
    *,
    alpha_per_s: float | None = None,
    beta_s: float | None = None,
    rayleigh_ratios: Sequence[Sequence[float]] | None = None,
    modal_ratios: Sequence[float] | None = None,
) -> DampingConfig:
    """A body's ``damping`` table, exactly one form: Rayleigh C = alpha M + beta K
    (``alpha_per_s`` [1/s], ``beta_s`` [s]); Rayleigh through two points of its ratio curve,
    ``rayleigh_ratios=[(f1_hz, zeta1), (f2_hz, zeta2)]``; or the damping ratios of a reduced
    body's modes, ``modal_ratios`` (one for all, or one per mode in ascending frequency)."""
    keys = dict(locals())
    return _table(DampingConfig, "damping(...)", keys)


def rigid_motion(
    angular_velocity_radps: Vector,
    *,
    about_joint: str | None = None,
    about_m: Vector | None = None,
    velocity_mps: Vector | None = None,
) -> RigidMotionConfig:
    """A body's initial rigid motion (its placement's ``rigid_motion``): angular velocity
    ``angular_velocity_radps`` [rad/s] (global axes) about the pivot of the joint named
    ``about_joint``, or the global point ``about_m`` [m], or the frame origin; that point
    moves at ``velocity_mps`` [m/s] (global, default 0). The frame's velocities follow:
    v_O = v_P + w x (r_O - r_P)."""
    keys = dict(locals())
    return _table(RigidMotionConfig, "rigid_motion(...)", keys)
