"""The moving region (kind ``mvm-moving``, issue 53 item 1): static modes switching
(Tamarozzi, Heirman and Desmet 2011, 2014) in the multi-variable method's terms.

One global basis Phi (the lowest modes of the body under its reference condition: its supports
or a 3-2-1 reference of the floating frame) is shared by a family of windows along a path (a
node set, e.g. a beam's top face, parametrised by its principal axis s). Window k holds the
path nodes within ``half_width_m`` of its centre s_k: its basis spans Phi and the static
responses K^-1 e_d to unit loads at its nodes (attachment modes; one factorisation of K_ff
serves every window, each window 3 n_w back-substitutions, no eigenproblem). The basis is
written in nodal form, as kind mvm's: the window nodes' x, y, z displacements are coordinates
(unit columns there), the rest of the span is m columns zero at the window nodes (the global
modes with the window held, Rayleigh-Ritz orthogonalised: their frequencies are the
``mode_freqs_hz``). So a window's nodes are exact statically and the contact nodes shared by
two windows are coordinates of both (integrate/moving_region.py carries the state across a
switch keeping them exact).

Through the registry (build_basis) the kind makes ONE window holding every retained node: a
fixed region over the whole path with global modes. The switching run is
integrate/moving_region.py's MovingRegion on a MovingWindows made here (moving_windows).
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as sla
from threadpoolctl import ThreadpoolController

from flexmvm.errors import InputError
from flexmvm.fe.assembly import FEModel
from flexmvm.fe.modes import shift_invert_modes, spd_solver, to_hz
from flexmvm.reduction.kinds.mvm import node_dofs
from flexmvm.reduction.kinds.registry import ModelKind
from flexmvm.reduction.kinds.spec import Basis, BasisRequest, NodesAndModes

try:  # numpy >= 2
    from numpy._core.multiarray import _set_madvise_hugepage  # type: ignore[attr-defined]
except ImportError:  # pragma: no cover - numpy 1.26
    from numpy.core.multiarray import _set_madvise_hugepage  # type: ignore[no-redef]

NAME = "mvm-moving"


@functools.lru_cache(maxsize=1)
def _controller() -> ThreadpoolController:
    return ThreadpoolController()


def one_blas_thread():
    """A context of one BLAS thread, threadpoolctl's libraries looked up once (a
    threadpool_limits looks them up at each call: 2.6 ms, 0.2 s over 79 windows)."""
    return _controller().limit(limits=1, user_api="blas")


def basis_signature(psi: np.ndarray) -> np.ndarray:
    """(nq,) w^T psi for a fixed pseudo-random w (seeded): a window's basis told from another
    (a column of the opposite sign, or round-off of another BLAS) in one pass over psi, kept
    with the stored parts (setup_cache/moving_entries.py) so a window made again is checked
    against the basis its parts came from (integrate/moving_region.py)."""
    w = np.random.default_rng(53).standard_normal(psi.shape[0])
    with one_blas_thread():
        return w @ psi


def same_signature(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two signatures are of one basis: equal to 1e-9 of the largest (round-off of
    another BLAS passes; a column of the opposite sign differs by 2 |w^T psi_j|)."""
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and bool(
        np.all(np.abs(a - b) <= 1e-9 * max(float(np.abs(b).max(initial=0.0)), 1e-300))
    )


@dataclass(frozen=True)
class MovingModes(NodesAndModes):
    """Columns: the window nodes' x, y, z (unit columns), then the m global-mode columns held
    at the window; no static columns. Not cut to fewer modes (the held modes depend on m)."""

    name: str = NAME
    selectable: bool = False  # its windows follow a path: not a candidate of a selection

    def build_basis(self, request: BasisRequest) -> Basis:
        fe, ref = request.fe, request.reference
        if request.n_modes < 1:
            raise InputError(f"model kind {NAME!r} needs modes >= 1, got {request.n_modes}")
        factor = GlobalFactor.of(fe, ref, request.n_modes)
        return factor.window_basis(np.asarray(request.nodes, dtype=np.int64))


SPEC = MovingModes()


@dataclass
class GlobalFactor:
    """K_ff's factor (free DOFs of the reference condition) and the m global modes Phi
    (n_dof, m), M-orthonormal, with their frequencies [Hz]: what every window shares."""

    fe: FEModel
    reference: Any  # a ReferenceCondition (or a support's condition: fixed_dofs, free_dofs)
    free: np.ndarray
    solve: Callable[[np.ndarray], Any]  # K_ff^-1 applied to right-hand sides
    phi: np.ndarray
    freqs_hz: np.ndarray
    columns: dict = field(default_factory=dict, repr=False)  # node -> its (n_dof, 3) statics

    @classmethod
    def of(cls, fe: FEModel, reference, n_modes: int) -> GlobalFactor:
        free = reference.free_dofs(fe.n_dof)
        k_ff = fe.K[free][:, free]
        # no thread pool: the factor outlives this call (every window's solves use it)
        with one_blas_thread():
            solve = spd_solver(k_ff)
            lam, modes = shift_invert_modes(fe.M[free][:, free], k_ff, n_modes, 0.0, solve=solve)
        phi = np.zeros((fe.n_dof, n_modes))
        phi[free] = modes
        return cls(fe, reference, free, solve, phi, to_hz(lam))

    @classmethod
    def stored(cls, fe: FEModel, reference, phi, freqs_hz, columns: dict) -> GlobalFactor:
        """The factor of a setup-cache entry (setup_cache/moving_entries.py): the modes and
        the nodes' static columns as stored; K_ff factored only if a node not stored is
        asked for (a warm run asks for none)."""
        free = reference.free_dofs(fe.n_dof)
        return cls(fe, reference, free, _LazySolve(fe, free), phi, freqs_hz, dict(columns))

    def release(self) -> None:
        """Drop the nodes' static columns and K_ff's factor (a lazy one takes its place):
        once every window is made (assembly/moving_region.py) a run needs neither, and on a
        37,000-DOF part they hold ~0.5 GB and K_ff's factor."""
        self.columns.clear()
        self.solve = _LazySolve(self.fe, self.free)

    def attachment(self, nodes: np.ndarray, extra: int = 0) -> np.ndarray:
        """(n_dof, 3 n_w) static responses to unit loads at the nodes' DOFs (a held DOF
        gives a zero column), Fortran order, and ``extra`` columns after them left unset
        (room for a window's modal part: nodal_form makes the basis in place). Each node's
        three are solved once (with K_ff's factor, one BLAS thread: the many-right-hand-side
        solve is ~10x slower threaded on shared cores) and kept: neighbouring windows share
        most of their nodes."""
        new = [int(k) for k in nodes if int(k) not in self.columns]
        if new:
            b = node_dofs(np.asarray(new, dtype=np.int64))
            pos = np.searchsorted(self.free, b)
            ok = (pos < self.free.size) & (self.free[np.minimum(pos, self.free.size - 1)] == b)
            rhs = np.zeros((self.free.size, b.size))
            rhs[pos[ok], np.flatnonzero(ok)] = 1.0
            out = np.zeros((self.fe.n_dof, b.size), order="F")
            with one_blas_thread():
                out[self.free] = np.asarray(self.solve(rhs)).reshape(self.free.size, b.size)
            for j, k in enumerate(new):
                self.columns[k] = out[:, 3 * j : 3 * j + 3]
        return _columns_side_by_side([self.columns[int(k)] for k in nodes], extra)

    def window_basis(self, nodes: np.ndarray) -> Basis:
        """The window of ``nodes``: span{attachment modes, Phi} in nodal form (module doc)."""
        return self.window(nodes)[0]

    def window(self, nodes: np.ndarray) -> tuple[Basis, np.ndarray]:
        """(the window's Basis, its k_hat = psi^T K psi (nq, nq) [N/m]) (nodal_form)."""
        work = self.attachment(nodes, self.phi.shape[1])
        psi, freqs, k_hat = nodal_form(self.fe, work, self.phi, node_dofs(nodes))
        basis = Basis(ModelKind(NAME), psi, nodes, self.phi.shape[1], self.reference, freqs)
        return basis, k_hat


class _LazySolve:
    """K_ff^-1 of a stored GlobalFactor, factored on the first call (one BLAS thread)."""

    def __init__(self, fe: FEModel, free: np.ndarray):
        self.fe, self.free = fe, free
        self._solve: Callable[[np.ndarray], Any] | None = None

    def __call__(self, rhs: np.ndarray):
        solve = self._solve
        if solve is None:
            with one_blas_thread():
                solve = self._solve = spd_solver(self.fe.K[self.free][:, self.free])
        return solve(rhs)


@contextlib.contextmanager
def _no_hugepage_advice():
    """numpy's transparent-hugepage advice off for the allocations inside (restored after).
    A window's basis is ~80 MB of fresh memory (the cam's follower); with the advice, under a
    kernel whose THP defrag is "madvise", each first touch of it tries to compact memory: its
    copy took 145 ms against 40 ms without (and no huge page was given). Only here: off for
    the whole process, full FE's simulation took 35 % longer."""
    previous = _set_madvise_hugepage(False)
    try:
        yield
    finally:
        _set_madvise_hugepage(previous)


def _columns_side_by_side(blocks: list[np.ndarray], extra: int = 0) -> np.ndarray:
    """np.hstack(blocks) in Fortran order and ``extra`` unset columns after them: each
    block's columns copied whole (a C-order hstack of column blocks of 12,000 rows took 18 ms
    a window on the fine beam), into memory allocated without the hugepage advice
    (_no_hugepage_advice)."""
    n = sum(b.shape[1] for b in blocks)
    with _no_hugepage_advice():
        out = np.empty((blocks[0].shape[0], n + extra), order="F")
    j = 0
    for b in blocks:
        out[:, j : j + b.shape[1]] = b
        j += b.shape[1]
    return out


def nodal_form(
    fe: FEModel, work: np.ndarray, phi: np.ndarray, b: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """span{statics, phi} (n_dof, 3 n_w + m) rewritten as [T, Z], made in ``work`` (n_dof,
    3 n_w + m), Fortran order, whose first 3 n_w columns hold the statics (attachment's
    ``extra``: a 74 MB copy a window less on the cam's follower): T = statics F^-1 with F =
    statics[b] (the window's flexibility, symmetric positive definite): the static constraint
    modes of the window DOFs b (T[b] = I, the least strain energy with those values), and
    Z = phi - T phi[b] (the global modes with the window held, Z[b] = 0) made M-orthonormal
    and K-orthogonal by Rayleigh-Ritz (their frequencies returned, [Hz]). Returned with the
    reduced stiffness without a product with K: K T = E F^-1 (E the unit columns at b), so
    T^T K T = F^-1 and T^T K Z = F^-1 Z[b] = 0; Z^T K Z = diag(omega^2). InputError when F
    is singular (a DOF in b held by the reference condition)."""
    n_b, n_z = b.size, phi.shape[1]
    psi, statics = work, work[:, :n_b]
    F = 0.5 * (statics[b] + statics[b].T)
    try:
        chol = sla.cho_factor(F)
    except np.linalg.LinAlgError:
        raise InputError("a moving window holds a DOF its reference condition holds") from None
    T = _right_solve(chol, statics)
    T[b] = np.eye(b.size)
    Z = phi - T @ phi[b]
    Z[b] = 0.0
    m_z = Z.T @ (fe.M @ Z)
    k_z = Z.T @ (fe.K @ Z)
    lam, vec = sla.eigh(0.5 * (k_z + k_z.T), 0.5 * (m_z + m_z.T))
    k_hat = np.zeros((n_b + n_z, n_b + n_z))
    f_inv = sla.cho_solve(chol, np.eye(n_b))
    k_hat[:n_b, :n_b] = 0.5 * (f_inv + f_inv.T)
    k_hat[n_b:, n_b:] = np.diag(lam)
    if not np.shares_memory(T, psi):  # dtrsm solved on a copy
        psi[:, :n_b] = T
    psi[:, n_b:] = Z @ vec
    return psi, to_hz(np.maximum(lam, 0.0)), k_hat


def _right_solve(chol, S: np.ndarray) -> np.ndarray:
    """S F^-1 in place of S (Fortran order), F = U^T U (cho_factor's upper U): two
    triangular solves from the right (cho_solve on S^T copied S to its transpose's
    layout: 9 ms a window on the fine beam)."""
    U, lower = chol
    X = sla.blas.dtrsm(1.0, U, S, side=1, lower=int(lower), trans_a=int(lower), overwrite_b=1)
    return sla.blas.dtrsm(
        1.0, U, X, side=1, lower=int(lower), trans_a=1 - int(lower), overwrite_b=1
    )


@dataclass(frozen=True)
class Path:
    """A path along a node set: its nodes, their parameter s [m] along the principal axis
    (origin: the nodes' centroid), the axis (3,) and the centroid (3,)."""

    nodes: np.ndarray
    s: np.ndarray
    axis: np.ndarray
    origin: np.ndarray

    @classmethod
    def along(cls, X: np.ndarray, nodes: np.ndarray) -> Path:
        """The path of node ids ``nodes`` of positions X (n, 3): their largest principal axis,
        oriented so that s grows with the axis' largest component."""
        nodes = np.unique(np.asarray(nodes, dtype=np.int64))
        if nodes.size < 2:
            raise InputError(f"a moving region's path needs 2 or more nodes, got {nodes.size}")
        P = X[nodes]
        c = P.mean(axis=0)
        _, vecs = np.linalg.eigh((P - c).T @ (P - c))
        axis = vecs[:, -1] * np.sign(vecs[np.argmax(np.abs(vecs[:, -1])), -1])
        return cls(nodes, (P - c) @ axis, axis, c)

    def parameter(self, x: np.ndarray) -> float:
        """s of a point x (3,) in the body frame [m]."""
        return float((np.asarray(x) - self.origin) @ self.axis)


@dataclass(frozen=True)
class MovingWindows:
    """The family of windows of a moving region: the shared GlobalFactor, the path, window
    centres s_k (K,) [m] spaced ``spacing_m``, each window's nodes (those with
    |s - s_k| <= half_width_m) and its basis (made on first use, kept)."""

    factor: GlobalFactor
    path: Path
    centres: np.ndarray
    spacing_m: float
    half_width_m: float
    span: tuple[float, float]
    _bases: dict = field(default_factory=dict, compare=False, repr=False)

    def nodes(self, k: int) -> np.ndarray:
        """The path nodes with s in [s_k - half width, s_k + half width], the interval shifted
        inside the path at its ends (every window of a regular path holds as many nodes)."""
        s, hw = self.path.s, self.half_width_m
        lo = min(max(self.centres[k] - hw, s.min()), max(s.max() - 2.0 * hw, s.min()))
        tol = 1e-9 * max(hw, 1e-12)
        return self.path.nodes[(s >= lo - tol) & (s <= lo + 2.0 * hw + tol)]

    def basis(self, k: int) -> Basis:
        """Window k's Basis (made on first use, kept), always under one BLAS thread: a basis
        made later (a warm run's window, made when the contact reaches it) must equal bit for
        bit the one its stored parts came from, and a threaded product rounds otherwise (a
        modal column of the opposite sign, from eigh on a round-off-different pencil)."""
        if k not in self._bases:
            with one_blas_thread():
                self._bases[k] = self.factor.window(self.nodes(k))
        return self._bases[k][0]

    def stiffness(self, k: int) -> np.ndarray:
        """Window k's k_hat (nq, nq) [N/m], from its construction (nodal_form)."""
        self.basis(k)
        return self._bases[k][1]

    def nearest(self, s: float) -> int:
        return int(np.argmin(np.abs(self.centres - s)))

    def covers(self, s: float) -> bool:
        """Whether a contact at s [m] lies in the covered interval ``covered``."""
        return self.covered[0] <= s <= self.covered[1]

    @property
    def covered(self) -> tuple[float, float]:
        """The path parameters [m] a contact may reach: the windows' span (the path's nodes,
        those on a support included, or s_range) widened by half a spacing."""
        lo, hi = self.span
        return lo - 0.5 * self.spacing_m, hi + 0.5 * self.spacing_m


def moving_windows(
    fe: FEModel,
    reference,
    path_nodes: np.ndarray,
    n_modes: int,
    spacing_m: float,
    half_width_m: float,
    s_range: tuple[float, float] | None = None,
    factor: GlobalFactor | None = None,
) -> MovingWindows:
    """The windows along the path of ``path_nodes``: centres every ``spacing_m`` from the
    path's first to its last s (or over s_range, [m] in the path's s), each holding the path
    nodes within ``half_width_m`` of it; the global factor and modes made once. A contact
    at s is then at most spacing / 2 (+ the switch's hysteresis) from its window's centre, so
    half_width_m >= that + the contact's reach (a facet's size for a point contact) keeps the
    nodes it loads in the window. Path nodes with a held DOF (on a support) are left out."""
    if not (spacing_m > 0 and half_width_m >= 0.5 * spacing_m):
        raise InputError(
            f"moving windows: spacing {spacing_m!r} m and half width {half_width_m!r} m; "
            "expected spacing > 0 and half width >= spacing / 2"
        )
    factor = GlobalFactor.of(fe, reference, n_modes) if factor is None else factor
    held = np.unique(np.asarray(reference.fixed_dofs, dtype=np.int64) // 3)
    whole = Path.along(fe.mesh.nodes, path_nodes)
    path = Path(**_restricted(whole, held))
    span = (
        (float(whole.s.min()), float(whole.s.max()))
        if s_range is None
        else (float(s_range[0]), float(s_range[1]))
    )
    lo, hi = (path.s.min(), path.s.max()) if s_range is None else s_range
    count = max(int(np.ceil((hi - lo) / spacing_m - 1e-9)) + 1, 1)
    centres = lo + spacing_m * np.arange(count)
    return MovingWindows(factor, path, centres, spacing_m, half_width_m, span)


def _restricted(path: Path, held: np.ndarray) -> dict:
    """The fields of ``path`` without its nodes in ``held`` (same axis and origin)."""
    keep = ~np.isin(path.nodes, held)
    return {"nodes": path.nodes[keep], "s": path.s[keep], "axis": path.axis, "origin": path.origin}
