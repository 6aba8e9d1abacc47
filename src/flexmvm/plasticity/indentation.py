"""A rigid frictionless sphere pressed into a body's flat top face under displacement
control: static, small strain, the contact found by an active set.

The sphere of radius R, its lowest point at depth d below the face z = z_top, occupies
z >= z_s(x, y) = z_top - d + R - sqrt(R^2 - rho^2), rho the distance from its axis; the body
lies below its face. A node of the face at (x, y) is in contact when z_top + u_z would lie
above z_s; the active set holds
those nodes at u_z = z_s - z_top (vertical gaps at the undeformed x, y and vertical contact
forces: Hertz's own small-strain setting, Johnson 1985, sect. 4.2), their x, y free. After
each equilibrium (plasticity/static_newton.py, from the converged state of the last depth)
nodes pulled by the sphere (tensile reaction) leave the set and penetrating ones join it,
until the set is unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError, SolverError
from flexmvm.plasticity.body import PlasticBody
from flexmvm.plasticity.static_newton import Loading, solve_static

#: Active-set passes per depth before giving up.
MAX_PASSES = 30


@dataclass(frozen=True)
class Indentation:
    """The path: depth (n,) [m], force (n,) [N] pressing the sphere down, contact_nodes
    (per depth, the active node ids), contact_forces (per depth, the force [N] of the sphere
    on each of them, > 0 pressing), displacement (n, 3n) [m], equivalent_plastic_strain
    (n, n_points) [-], stress (n, n_points, 6) [Pa], and the last state."""

    depth: np.ndarray
    force: np.ndarray
    contact_nodes: tuple[np.ndarray, ...]
    contact_forces: tuple[np.ndarray, ...]
    displacement: np.ndarray
    equivalent_plastic_strain: np.ndarray
    stress: np.ndarray
    state: object


def sphere_surface(xy: np.ndarray, depth: float, radius: float, centre_xy, z_top: float):
    """z_s (n,) [m] of the sphere's lower surface above the points xy (n, 2) [m]."""
    rho2 = np.sum((xy - np.asarray(centre_xy, float)) ** 2, axis=1)
    return z_top - depth + radius - np.sqrt(np.maximum(radius * radius - rho2, 0.0))


def _settle(body, face_nodes, support, target, active, start, tol: float):
    """Equilibrium with the face nodes ``active`` held at ``target`` (their u_z [m]) from the
    converged (state, u) ``start``, the set corrected until no node pulls or penetrates (by
    more than tol [m]). Returns the StaticPath of the step, the z-reactions (n_face,) [N] and
    the active set. SolverError if the set does not settle in MAX_PASSES."""
    state, u = start
    for _ in range(MAX_PASSES):
        fixed = np.concatenate([support, 3 * face_nodes[active] + 2])
        values = np.concatenate([np.zeros(len(support)), target[active]])[None, :]
        step = solve_static(
            body, Loading(fixed, values, np.zeros((1, body.n_dof))), state=state, u0=u
        )
        reaction = np.zeros(len(face_nodes))
        reaction[active] = step.reaction[0, len(support) :]
        uz = step.displacement[0, 3 * face_nodes + 2]
        release = active & (reaction > 1e-9 * max(np.abs(reaction).sum(), 1e-300))
        join = ~active & (uz > target + tol)
        if not (release.any() or join.any()):
            return step, reaction, active
        active = (active & ~release) | join
    raise SolverError(
        f"indentation: the contact set did not settle in {MAX_PASSES} passes "
        f"(deepest target {-target.min():.6g} m)"
    )


def indent_with_sphere(
    body: PlasticBody,
    face_nodes: np.ndarray,
    support_dofs: np.ndarray,
    radius_m: float,
    depths_m,
    centre_xy=(0.0, 0.0),
    z_top_m: float = 0.0,
) -> Indentation:
    """Press the sphere to each of ``depths_m`` in turn (module doc). face_nodes: node ids of
    the face z = z_top_m that may touch; support_dofs: DOFs held at zero (they must remove
    the rigid motions). Raises InputError on bad arguments, SolverError if the active set
    does not settle."""
    face_nodes = np.asarray(face_nodes, dtype=np.int64)
    support = np.asarray(support_dofs, dtype=np.int64)
    if not radius_m > 0:
        raise InputError(f"indentation: radius_m must be > 0, got {radius_m!r}")
    if face_nodes.size == 0 or not np.allclose(body.mesh.nodes[face_nodes, 2], z_top_m):
        raise InputError(f"indentation: face_nodes must be nodes of the face z = {z_top_m!r} m")
    xy = body.mesh.nodes[face_nodes, :2]
    state, u = body.virgin_state(), np.zeros(body.n_dof)
    active = np.zeros(len(face_nodes), bool)
    out: dict[str, list] = {"f": [], "c": [], "p": [], "u": [], "a": [], "s": []}
    for depth in np.asarray(depths_m, dtype=float):
        target = sphere_surface(xy, depth, radius_m, centre_xy, z_top_m) - z_top_m
        active |= u[3 * face_nodes + 2] > target
        step, reaction, active = _settle(
            body, face_nodes, support, target, active, (state, u), 1e-9 * max(depth, 1e-300)
        )
        state, u = step.state, step.displacement[0]
        out["f"].append(-reaction.sum())
        out["c"].append(face_nodes[active])
        out["p"].append(-reaction[active])
        out["u"].append(u)
        out["a"].append(step.equivalent_plastic_strain[0])
        out["s"].append(step.stress[0])
    return Indentation(
        np.asarray(depths_m, float),
        np.array(out["f"]),
        tuple(out["c"]),
        tuple(out["p"]),
        np.array(out["u"]),
        np.array(out["a"]),
        np.array(out["s"]),
        state,
    )
