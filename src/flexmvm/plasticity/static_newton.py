"""Static equilibrium of an elastic-plastic body along a load path: full Newton with the
consistent tangent (Simo and Hughes 1998, sect. 3.3; de Souza Neto et al. 2008, box 4.2).

Step k prescribes the displacements of the fixed DOFs D (displacement control) and the
external force f_ext (load control); each Newton iteration solves, on the free DOFs F,

    K_FF du_F = -(f_int(u) - f_ext)_F - K_FD du_D

with du_D the not yet applied part of the prescribed increment (nonzero only in the first
iteration), from the converged state of step k-1; the step converges when the free residual
is below ``rtol`` times the force scale of the path so far (the largest |f_ext| and |f_int|,
reactions included, of every iteration: a step that unloads to zero force is measured
against the forces it came from). With the consistent
tangent the convergence is quadratic; a step that does not converge raises SolverError.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError, SolverError
from flexmvm.fe.solvers.superlu import factor
from flexmvm.plasticity.body import PlasticBody
from flexmvm.plasticity.return_mapping import PointState

#: Default relative residual tolerance: quadratic convergence reaches it in a few iterations
#: from any increment of a converged path; round-off floors the residual near 1e-14.
RTOL = 1e-10
MAX_ITERATIONS = 30


@dataclass(frozen=True)
class Loading:
    """A load path of n_steps: fixed_dofs (m,) DOF ids, fixed_values (n_steps, m) [m] their
    displacements, force (n_steps, 3n) [N] the external nodal forces."""

    fixed_dofs: np.ndarray
    fixed_values: np.ndarray
    force: np.ndarray

    @classmethod
    def proportional(
        cls, n_dof: int, factors, fixed_dofs, unit_values=None, unit_force=None
    ) -> Loading:
        """Step k of a body of n_dof DOFs: fixed values factors[k] * unit_values, force
        factors[k] * unit_force (either may be None: zero)."""
        factors = np.asarray(factors, dtype=float)
        fixed = np.asarray(fixed_dofs, dtype=np.int64)
        values = np.zeros(len(fixed)) if unit_values is None else np.asarray(unit_values, float)
        force = np.zeros(n_dof) if unit_force is None else np.asarray(unit_force, float)
        return cls(fixed, np.outer(factors, values), np.outer(factors, force))

    @property
    def n_steps(self) -> int:
        return len(self.force)


@dataclass(frozen=True)
class StaticPath:
    """Converged equilibria: displacement (n_steps, 3n) [m], reaction (n_steps, m) [N] at the
    fixed DOFs (f_int - f_ext there), equivalent_plastic_strain (n_steps, n_points) [-],
    residuals (per step, the relative free residual of every iteration), stress (n_steps,
    n_points, 6) [Pa] and state (the last step's PointState)."""

    displacement: np.ndarray
    reaction: np.ndarray
    equivalent_plastic_strain: np.ndarray
    residuals: tuple[tuple[float, ...], ...]
    stress: np.ndarray
    state: PointState


def _check(body: PlasticBody, loading: Loading) -> np.ndarray:
    """The free DOFs; InputError on shapes that do not fit the body."""
    n, fixed = body.n_dof, loading.fixed_dofs
    if loading.force.ndim != 2 or loading.force.shape[1] != n:
        raise InputError(
            f"loading: force must have shape (n_steps, {n}), got {loading.force.shape}"
        )
    if loading.fixed_values.shape != (loading.n_steps, len(fixed)):
        raise InputError(
            f"loading: fixed_values must have shape ({loading.n_steps}, {len(fixed)}), "
            f"got {loading.fixed_values.shape}"
        )
    if len(fixed) and (fixed.min() < 0 or fixed.max() >= n or len(np.unique(fixed)) < len(fixed)):
        raise InputError(f"loading: fixed_dofs must be distinct DOF ids in 0..{n - 1}")
    free = np.setdiff1d(np.arange(n), fixed)
    if len(free) == 0:
        raise InputError("loading: every DOF is fixed; nothing to solve")
    return free


def _solve(k_ff, rhs: np.ndarray) -> np.ndarray:
    """K_FF^-1 rhs: SuperLU with the symmetric ordering (the consistent tangent of J2 with
    associative flow is symmetric and, with hardening, positive definite); the general LU
    where diagonal pivots fail (a perfectly plastic tangent near its limit)."""
    try:
        return factor(k_ff, spd=True)(rhs)
    except SolverError:
        return factor(k_ff, spd=False)(rhs)


def solve_static(
    body: PlasticBody,
    loading: Loading,
    state: PointState | None = None,
    u0: np.ndarray | None = None,
    rtol: float = RTOL,
    max_iterations: int = MAX_ITERATIONS,
) -> StaticPath:
    """Equilibria of ``body`` along ``loading`` from ``state``/``u0`` (default: virgin, at
    rest) by full Newton (module doc). Raises SolverError naming the step that failed."""
    free = _check(body, loading)
    fixed = loading.fixed_dofs
    state = body.virgin_state() if state is None else state
    u = np.zeros(body.n_dof) if u0 is None else np.array(u0, dtype=float)
    resp = body.respond(u, state)
    scale = max(float(np.linalg.norm(resp.force)), 1e-300)
    out_u, out_r, out_a, out_res, out_s = [], [], [], [], []
    for k in range(loading.n_steps):
        f_ext = loading.force[k]
        residuals = []
        du = np.zeros(body.n_dof)
        du[fixed] = loading.fixed_values[k] - u[fixed]
        for _ in range(max_iterations):
            r = resp.force - f_ext
            k_t = resp.tangent.tocsc()
            rhs = -(r[free] + k_t[free][:, fixed] @ du[fixed])
            du[free] = _solve(k_t[free][:, free], rhs)
            u = u + du
            du[:] = 0.0
            resp = body.respond(u, state)
            r = resp.force - f_ext
            scale = max(scale, float(np.linalg.norm(f_ext)), float(np.linalg.norm(resp.force)))
            residuals.append(float(np.linalg.norm(r[free]) / scale))
            if not np.isfinite(residuals[-1]):
                break
            if residuals[-1] <= rtol:
                break
        if not residuals[-1] <= rtol:
            raise SolverError(
                f"static Newton: step {k + 1} of {loading.n_steps} did not converge in "
                f"{len(residuals)} iterations (relative residuals "
                f"{', '.join(f'{r:.2g}' for r in residuals[-4:])}; tolerance {rtol:g})"
            )
        state = resp.state
        out_u.append(u.copy())
        out_r.append((resp.force - f_ext)[fixed])
        out_a.append(state.equivalent_plastic_strain)
        out_res.append(tuple(residuals))
        out_s.append(resp.stress)
    return StaticPath(
        np.array(out_u), np.array(out_r), np.array(out_a), tuple(out_res), np.array(out_s), state
    )
