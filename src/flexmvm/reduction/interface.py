"""A reduced interface basis for a contact region (issue 12): static contact-patch Ritz
vectors plus free-free vibration modes chosen by their participation for the expected load.

No node keeps its nodal coordinates; the contact constraints act on the nodal positions
u = psi q of the contact surface (contact rows N psi), as for a modal body.

Columns (all mass-orthonormal, M-orthogonal to the rigid-body modes, then expressed in the
floating frame of the 3-2-1 reference: reference DOF rows zero):

1. **Patch vectors** (static contact-patch Ritz vectors). For each patch radius a_k, the
   Hertz pressure p(r) = p0 sqrt(1 - r^2/a_k^2) (Hertz 1882; Johnson, *Contact Mechanics*,
   1985, eq. 3.39) on the contact surface around the expected contact point, total 1 N,
   integrated into nodal forces f_k; its inertia-relief static response (the free body's
   self-equilibrated response, Craig and Chang 1977; MacNeal 1971)
       u_k = K_ref^-1 P f_k,  P f = f - M R (R^T M R)^-1 R^T f      (R: rigid-body modes)
   made M-orthogonal to the kept modes and to the earlier patch vectors: the modal
   truncation augmentation vectors of Dickens, Nakagawa and Wittbrodt (1997, Comput. Struct.
   64), i.e. the residual flexibility of the dropped modes at the contact patch.
2. **Modes**: elastic free-free modes phi_i of (K, M). ``participation`` keeps the
   ``n_modes`` of a pool of the lowest ``pool`` with the largest static participation in the
   expected contact load f (the mean of the patch loads), p_i = |phi_i^T f| / omega_i^2
   (the modal share of the static displacement), among the modes the load excites
   (|phi_i^T f| above EXCITED_RTOL of the largest: an on-axis impact excites no bending or
   torsion mode); the default pool is doubled until it holds n_modes excited modes (an
   explicit pool is not: too few excited modes in it is an InputError);
   ``frequency`` keeps the lowest n_modes.

The two expensive parts, the free-free mode pool and the patch vectors' static solve, do not
depend on ``n_modes``: ``interface_columns`` takes them from an InterfaceSources (the setup
cache's, assembly/build.py), so the bases of one patch set that differ only in their mode
count share one eigen solve and one factor of K when they share the pool (a study gives all
of them the pool of its largest mode count: studies/interface.py, participation_pool).

A load in the span of the patch loads has its full-FE static response (inertia relief,
floating frame) in span(psi), so the reduced static solution psi k_hat^-1 psi^T P f equals
K_ref^-1 P f to round-off (tests/test_interface_basis.py).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum

import numpy as np
import scipy.linalg as sla

from flexmvm.errors import InputError, MeshError
from flexmvm.fe.assembly import FEModel
from flexmvm.fe.modes import factor, free_modes
from flexmvm.mesh.mesh import Mesh
from flexmvm.reduction.reference_condition import ReferenceCondition, rigid_body_modes

#: A patch vector whose M-norm drops below this fraction when made orthogonal to the columns
#: before it adds nothing (the radius is too close to another one, or the modes hold it).
DEPENDENT_RTOL = 1e-6

#: A mode whose modal force |phi^T f| is below this fraction of the pool's largest (rigid-body
#: modes included) is not
#: excited by the expected load (on the seed rod an on-axis load gives the axial modes 1.5 and
#: the bending and torsion modes 1e-13..2e-10, round-off of the mesh's symmetry): the
#: participation choice never keeps one, however low its frequency.
EXCITED_RTOL = 1e-6

#: The participation choice doubles its default pool until it holds ``modes`` excited modes,
#: up to this many free-free modes.
MAX_POOL = 640

#: Sub-cells per facet diameter over the patch radius: each facet near the patch is split into
#: s x s sub-cells (2 x 2 Gauss points each), s = ceil(SUBCELLS_PER_RADIUS * d / a), so the
#: square-root edge of the Hertz pressure is resolved to a fraction of the radius.
SUBCELLS_PER_RADIUS = 8


class ModeChoice(StrEnum):
    """How an interface basis picks its vibration modes (values: ``mode_choice``)."""

    PARTICIPATION = "participation"  # largest |phi^T f| / omega^2 for the expected load
    FREQUENCY = "frequency"  # lowest frequencies


@dataclass(frozen=True)
class InterfaceSpec:
    """What an interface basis is built for: the contact surface (a facet set), the expected
    contact point on it (None: the surface node nearest the surface's area centroid), the
    Hertz patch radii [m] (one patch vector each), how the modes are chosen and the pool of
    free-free modes they are chosen from (None: 4 n_modes + 6)."""

    surface: str = "end_a"
    centre_m: tuple[float, float, float] | None = None
    radii_m: tuple[float, ...] = ()
    mode_choice: ModeChoice = ModeChoice.PARTICIPATION
    pool: int | None = None

    def key(self) -> dict:
        """Setup-cache key inputs (JSON)."""
        return {
            "surface": self.surface,
            "centre_m": None if self.centre_m is None else [float(c) for c in self.centre_m],
            "radii_m": [float(a) for a in self.radii_m],
            "mode_choice": ModeChoice(self.mode_choice).value,
            "pool": self.pool,
        }

    def pool_size(self, n_modes: int) -> int:
        return int(self.pool) if self.pool is not None else 4 * int(n_modes) + 6


@dataclass(frozen=True)
class Patch:
    """The expected contact point of a surface: node id, position (3,) [m] and unit outward
    normal (3,) (area-weighted over the facets at that node)."""

    node: int
    centre_m: np.ndarray
    normal: np.ndarray


def _quads(mesh: Mesh, surface: str) -> np.ndarray:
    try:
        fs = mesh.facet_set(surface)
    except MeshError as exc:
        raise InputError(f"interface basis: {exc}") from None
    tris = np.column_stack([fs.tris, fs.tris[:, 2]]) if len(fs.tris) else np.zeros((0, 4), int)
    return np.vstack([fs.quads, tris]).astype(np.int64)  # a triangle as a degenerate quad


def contact_patch(mesh: Mesh, surface: str, centre_m=None) -> Patch:
    """The expected contact point on facet set ``surface``: the surface node nearest
    ``centre_m`` (default: the surface's area centroid), with its outward normal."""
    quads = _quads(mesh, surface)
    X = mesh.nodes
    p = X[quads]  # (f, 4, 3)
    area_n = 0.5 * np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])  # area x outward normal
    area = np.linalg.norm(area_n, axis=1)
    if centre_m is None:
        centre_m = (p.mean(axis=1) * area[:, None]).sum(axis=0) / area.sum()
    nodes = np.unique(quads)
    node = int(nodes[np.argmin(np.linalg.norm(X[nodes] - np.asarray(centre_m, float), axis=1))])
    n = area_n[np.any(quads == node, axis=1)].sum(axis=0)
    return Patch(node, X[node].copy(), n / np.linalg.norm(n))


def patch_nodes(mesh: Mesh, surface: str, patch: Patch, radius_m: float) -> np.ndarray:
    """Nodes of facet set ``surface`` within ``radius_m`` of the patch centre, measured in
    its tangent plane (the centre node alone for radius 0), sorted."""
    nodes = np.unique(_quads(mesh, surface))
    return nodes[tangent_distance(mesh.nodes[nodes], patch) <= radius_m * (1 + 1e-9)]


def tangent_distance(points: np.ndarray, patch: Patch) -> np.ndarray:
    """Distance (p,) [m] of points (p, 3) from the patch centre in its tangent plane."""
    d = np.asarray(points, float) - patch.centre_m
    return np.linalg.norm(d - np.outer(d @ patch.normal, patch.normal), axis=1)


def hertz_load(mesh: Mesh, surface: str, patch: Patch, radius_m: float) -> np.ndarray:
    """Nodal forces (3n,) [N] of the Hertz pressure p(r) = p0 sqrt(1 - r^2/a^2), a = radius_m,
    on facet set ``surface`` about ``patch`` (r: distance from the patch centre in its tangent
    plane), pushing into the body, scaled to a total of 1 N. Integrated over each (bilinear)
    facet with its shape functions on s x s sub-cells, 2 x 2 Gauss points each."""
    if not radius_m > 0.0:
        raise InputError(f"patch radius must be > 0 m, got {radius_m!r}")
    X = mesh.nodes
    quads = _quads(mesh, surface)
    p = X[quads]
    diam = np.max(np.linalg.norm(p[:, [2, 3]] - p[:, [0, 1]], axis=2), axis=1)
    rel = p - patch.centre_m
    dist = np.linalg.norm(
        rel - np.einsum("fkj,j->fk", rel, patch.normal)[..., None] * patch.normal, axis=2
    ).min(axis=1)
    near = np.nonzero(dist <= radius_m + diam)[0]
    f = np.zeros(3 * mesh.n_nodes)
    g = np.array([-1.0, 1.0]) / np.sqrt(3.0)
    for k in near:
        s = int(np.clip(np.ceil(SUBCELLS_PER_RADIUS * diam[k] / radius_m), 2, 64))
        edges = np.linspace(-1.0, 1.0, s + 1)
        mid, half = 0.5 * (edges[1:] + edges[:-1]), 1.0 / s
        xi = (mid[:, None] + half * g[None, :]).ravel()  # (2s,) Gauss abscissae
        XI, ETA = (a.ravel() for a in np.meshgrid(xi, xi, indexing="ij"))
        N = 0.25 * np.column_stack(
            [(1 - XI) * (1 - ETA), (1 + XI) * (1 - ETA), (1 + XI) * (1 + ETA), (1 - XI) * (1 + ETA)]
        )
        dxi = 0.25 * np.column_stack([-(1 - ETA), (1 - ETA), (1 + ETA), -(1 + ETA)])
        deta = 0.25 * np.column_stack([-(1 - XI), -(1 + XI), (1 + XI), (1 - XI)])
        x = N @ p[k]
        an = np.cross(dxi @ p[k], deta @ p[k]) * half * half  # area x outward normal
        d = x - patch.centre_m
        d -= np.outer(d @ patch.normal, patch.normal)
        pr = np.sqrt(np.clip(1.0 - np.einsum("ij,ij->i", d, d) / radius_m**2, 0.0, None))
        nodal = -(N * pr[:, None]).T @ an  # (4, 3): into the body
        np.add.at(f.reshape(-1, 3), quads[k], nodal)
    total = np.linalg.norm(f.reshape(-1, 3).sum(axis=0))
    if total == 0.0:
        raise InputError(
            f"patch radius {radius_m:g} m: the Hertz pressure about node "
            f"{patch.node} loads no facet of surface {surface!r}"
        )
    return f / total


@dataclass(frozen=True)
class InterfaceColumns:
    """psi (3n, nq) [patch vectors, modes] in the reference frame; mode frequencies [Hz];
    participation of the kept modes [m/N]; the patch (expected contact point); the patch
    loads (3n, n_patch) [N] and their inertia-relieved static responses (3n, n_patch) [m]
    (reference frame), for checks."""

    psi: np.ndarray
    mode_freqs_hz: np.ndarray
    participation: np.ndarray
    patch: Patch
    loads: np.ndarray
    static: np.ndarray


#: free(k) -> (frequencies [Hz] (k,), modes (3n, k) M-normalised): the lowest k free-free
#: modes, the six rigid-body modes first, as fe.modes.free_modes(fe, k) gives them.
FreeModes = Callable[[int], tuple[np.ndarray, np.ndarray]]

#: statics(patch, radii, loads (3n, k)) -> (3n, k): the inertia-relieved static responses of
#: the patch loads of ``radii`` about ``patch``, as relieved_statics gives them.
PatchStatics = Callable[["Patch", tuple[float, ...], np.ndarray], np.ndarray]


@dataclass(frozen=True)
class InterfaceSources:
    """Where interface_columns takes its expensive parts from (None: computed here): the
    free-free mode pool (``free_modes``) and the patch vectors' static responses
    (``patch_statics``). Both must return what the default computation would (the setup
    cache's stored copies of it), so that a basis does not depend on where they came from."""

    free_modes: FreeModes | None = None
    patch_statics: PatchStatics | None = None


def inertia_relief(fe: FEModel, f: np.ndarray) -> np.ndarray:
    """P f = f - M R (R^T M R)^-1 R^T f: the load balanced by the rigid-body inertia it
    causes (self-equilibrated: R^T P f = 0), f (3n,) or (3n, k)."""
    R = rigid_body_modes(fe.mesh.nodes)
    MR = fe.M @ R
    return f - MR @ np.linalg.solve(R.T @ MR, R.T @ f)


def _excited(force: np.ndarray) -> np.ndarray:
    """force (6 + p,): |phi^T f| of a free-free mode pool, the six rigid-body modes first ->
    (p,) indices of the elastic modes the load excites. The scale of a real modal force is the
    largest, rigid-body modes included (a 1 N load gives a rigid translation 1/sqrt(mass)), so
    a pool holding no excited elastic mode keeps none."""
    return np.nonzero(force[6:] > EXCITED_RTOL * force.max())[0]


def excited_modes_below(
    fe: FEModel, f: np.ndarray, f_max_hz: float, pool: int = 16, free: FreeModes | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The elastic free-free modes of ``fe`` below ``f_max_hz`` that the load ``f`` (3n,) [N]
    excites, by the participation choice's rule (modal force |phi^T f| above EXCITED_RTOL of
    the pool's largest): (frequencies [Hz], participations |phi^T f| / omega^2 [m/N]), in
    frequency order. The pool of the lowest ``pool`` elastic modes is doubled until its top
    mode reaches f_max_hz (or holds every mode). free: the source of the free-free modes
    (default free_modes(fe, k)).

    Raises:
        InputError: f_max_hz <= 0, or MAX_POOL modes do not reach f_max_hz.
    """
    if not f_max_hz > 0:
        raise InputError(f"f_max_hz: expected a frequency > 0 Hz, got {f_max_hz!r}")
    free = _free_source(fe, free)
    n_free = fe.n_dof - 7
    pool = min(int(pool), n_free)
    while True:
        f_hz, modes = free(pool + 6)
        if f_hz[-1] >= f_max_hz or pool >= n_free:
            break
        if pool >= MAX_POOL:
            raise InputError(
                f"the lowest {pool} free-free modes end at {f_hz[-1]:.4g} Hz, "
                f"below f_max = {f_max_hz:.4g} Hz; expected f_max within "
                f"{MAX_POOL} modes"
            )
        pool = min(2 * pool, MAX_POOL, n_free)
    force = np.abs(modes.T @ f)
    idx = _excited(force)
    idx = idx[f_hz[6:][idx] < f_max_hz]
    omega = 2.0 * np.pi * f_hz[6:][idx]
    return f_hz[6:][idx], force[6:][idx] / omega**2


def chosen_modes(
    fe: FEModel, spec: InterfaceSpec, n_modes: int, f_exp: np.ndarray, free: FreeModes | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(phi (3n, n_modes) free-free elastic modes, M-normalised, their frequencies [Hz] and
    participations |phi^T f| / omega^2 [m/N]) chosen as spec.mode_choice says for the expected
    load f_exp (3n,). free: the source of the free-free modes (default free_modes(fe, k))."""
    free = _free_source(fe, free)
    n_free = fe.n_dof - 7
    if spec.mode_choice is ModeChoice.FREQUENCY:
        f_hz, modes = free(min(n_modes, n_free) + 6)
        f_hz, modes = f_hz[6:], modes[:, 6:]  # the six rigid-body modes come first
        return modes, f_hz, np.abs(modes.T @ f_exp) / (2.0 * np.pi * f_hz) ** 2
    _pool, f_hz, modes, force, excited = _participation_pool(fe, spec, n_modes, f_exp, free)
    p_all = force / (2.0 * np.pi * f_hz) ** 2
    keep = np.sort(excited[np.argsort(-p_all[excited], kind="stable")[:n_modes]])
    return modes[:, keep], f_hz[keep], p_all[keep]


def _free_source(fe: FEModel, free: FreeModes | None) -> FreeModes:
    return free if free is not None else (lambda k: free_modes(fe, k))


def _participation_pool(
    fe: FEModel, spec: InterfaceSpec, n_modes: int, f_exp: np.ndarray, free: FreeModes
):
    """The participation choice's pool: (pool, elastic frequencies [Hz], elastic modes, their
    |phi^T f_exp|, indices of the excited ones); spec.pool if given, else the default pool
    doubled until it holds n_modes excited modes. InputError (one line) when it holds fewer."""
    n_free = fe.n_dof - 7
    grow = spec.pool is None
    pool = min(spec.pool_size(n_modes), n_free)
    while True:
        if pool < n_modes:
            raise InputError(f"interface basis: {n_modes} modes asked, the mode pool holds {pool}")
        f_hz, modes = free(pool + 6)
        force = np.abs(modes.T @ f_exp)
        excited = _excited(force)
        f_hz, modes, force = f_hz[6:], modes[:, 6:], force[6:]
        if excited.size >= n_modes or not grow or pool >= min(MAX_POOL, n_free):
            break
        pool = min(2 * pool, MAX_POOL, n_free)
    if excited.size < n_modes:
        raise InputError(
            f"interface basis: the expected load excites {excited.size} of the "
            f"lowest {pool} free-free modes, {n_modes} asked; ask for fewer modes"
            + (" or a larger mode_pool" if not grow else "")
        )
    return pool, f_hz, modes, force, excited


def patch_loads(mesh: Mesh, spec: InterfaceSpec) -> tuple[Patch, np.ndarray, np.ndarray]:
    """(patch, loads (3n, n_patch) [N]: the Hertz load of each radius, f_exp (3n,) [N]: the
    expected contact load, the mean patch load, or 1 N along the inward normal at the patch
    node without radii)."""
    radii = tuple(float(a) for a in spec.radii_m)
    n = 3 * mesh.n_nodes
    patch = contact_patch(mesh, spec.surface, spec.centre_m)
    loads = (
        np.column_stack([hertz_load(mesh, spec.surface, patch, a) for a in radii])
        if radii
        else np.zeros((n, 0))
    )
    f_exp = loads.mean(axis=1) if radii else np.zeros(n)
    if not radii:
        f_exp[3 * patch.node : 3 * patch.node + 3] = -patch.normal
    return patch, loads, f_exp


def participation_pool(
    fe: FEModel, spec: InterfaceSpec, n_modes: int, free: FreeModes | None = None
) -> int:
    """The pool of free-free modes from which the participation choice of ``spec`` takes
    ``n_modes`` modes: spec.pool if given, else 4 n_modes + 6 doubled until it holds n_modes
    excited modes. An explicit ``mode_pool`` of this size gives the same basis as the default;
    a study gives it to every mode count of a patch set, so that they share one eigen solve.
    Raises InputError (one line) as interface_columns does when the pool excites too few."""
    if spec.mode_choice is not ModeChoice.PARTICIPATION:
        raise InputError(
            f"a mode pool is the participation choice's, got mode_choice "
            f"{ModeChoice(spec.mode_choice).value!r}"
        )
    _patch, _loads, f_exp = patch_loads(fe.mesh, spec)
    return int(_participation_pool(fe, spec, int(n_modes), f_exp, _free_source(fe, free))[0])


def relieved_statics(fe: FEModel, reference: ReferenceCondition, loads: np.ndarray) -> np.ndarray:
    """u = K_ref^-1 P f of each load column f of ``loads`` (3n, k) [N]: the inertia-relieved
    static responses (3n, k) [m], reference DOF rows zero (one sparse factor of K_ref, one
    solve of all columns)."""
    n = fe.n_dof
    static = np.zeros((n, loads.shape[1]))
    if loads.shape[1]:
        free = reference.free_dofs(n)
        solve = factor(fe.K[free][:, free])
        static[free] = solve(inertia_relief(fe, loads)[free])
    return static


def interface_columns(
    fe: FEModel,
    reference: ReferenceCondition,
    spec: InterfaceSpec,
    n_modes: int,
    sources: InterfaceSources | None = None,
) -> InterfaceColumns:
    """The interface basis of ``fe`` for ``spec`` with ``n_modes`` modes (module doc); its
    mode pool and patch statics from ``sources`` (default: computed here)."""
    radii = tuple(float(a) for a in spec.radii_m)
    if n_modes + len(radii) < 1:
        raise InputError("an interface basis needs at least one patch radius or one mode")
    if len(set(radii)) != len(radii):
        raise InputError(f"patch radii repeat: {list(radii)}")
    sources = sources if sources is not None else InterfaceSources()
    mesh = fe.mesh
    R = rigid_body_modes(mesh.nodes)
    MR = fe.M @ R
    RMR = R.T @ MR
    patch, loads, f_exp = patch_loads(mesh, spec)
    # modes: free-free, elastic ones (the six rigid-body modes come first)
    phi, freqs, part = np.zeros((fe.n_dof, 0)), np.zeros(0), np.zeros(0)
    if n_modes:
        phi, freqs, part = chosen_modes(fe, spec, n_modes, f_exp, sources.free_modes)
    # patch vectors: inertia-relief static responses, then M-orthonormal to the modes and
    # each other (modal truncation augmentation)
    static = (
        sources.patch_statics(patch, radii, loads)
        if sources.patch_statics is not None and radii
        else relieved_statics(fe, reference, loads)
    )
    cols = [phi]
    basis = phi
    for k in range(len(radii)):
        w = static[:, k] - R @ np.linalg.solve(RMR, MR.T @ static[:, k])  # no rigid part
        norm0 = np.sqrt(w @ (fe.M @ w))
        for _ in range(2):  # Gram-Schmidt twice: orthogonal to round-off
            w = w - basis @ (basis.T @ (fe.M @ w))
        norm = np.sqrt(w @ (fe.M @ w))
        if not norm > DEPENDENT_RTOL * norm0:
            raise InputError(
                f"patch radius {radii[k]:g} m adds nothing beyond the other "
                "columns of the interface basis; choose distinct radii"
            )
        w = (w / norm)[:, None]
        cols.insert(len(cols) - 1, w)  # patch vectors before the modes
        basis = np.hstack([basis, w])
    U = np.hstack(cols)
    # floating frame: subtract the rigid motion that moves the reference DOFs
    fixed = reference.fixed_dofs
    psi = U - R @ sla.solve(R[fixed], U[fixed])
    psi[fixed] = 0.0
    return InterfaceColumns(np.ascontiguousarray(psi), freqs, part, patch, loads, static)


__all__ = [
    "FreeModes",
    "InterfaceColumns",
    "InterfaceSources",
    "InterfaceSpec",
    "ModeChoice",
    "Patch",
    "PatchStatics",
    "chosen_modes",
    "contact_patch",
    "excited_modes_below",
    "hertz_load",
    "inertia_relief",
    "interface_columns",
    "participation_pool",
    "patch_loads",
    "patch_nodes",
    "relieved_statics",
    "tangent_distance",
]
