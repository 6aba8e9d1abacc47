"""A moving region at run time (issue 53 items 1 and 5): the body holds one window of a
reduction.kinds.mvm_moving.MovingWindows; after every accepted step the driver asks
MovingRegion.after_step whether the contact centre has left the window (with hysteresis) and,
if so, gets the system with the body of the new window and the states carried over.

What is carried across a switch (docs/notes/2026-11-29-moving-load.md, design note): the frame
state (r, A, r_dot, omega) unchanged; q projected in the K metric on the new window with the
displacements of the nodes both windows hold kept exactly (they are coordinates of both: the
contact nodes, so the gap and with the position law the contact force do not jump) and the
first moment S1 q kept; q_dot projected in the M metric with the linear momentum (S1 q_dot)
and the angular momentum at the new q kept (equality rows of a small KKT system): the kinetic
energy of the part the new window cannot hold is dropped, none is added. (Keeping the shared
nodes' velocities exactly too raised the kinetic energy at every switch until the run blew up:
docs/notes/2026-11-29-moving-region.md.) The integrator is made again for the new system (its
iteration matrices depend on the basis; a window has a few dozen coordinates, so this costs a
few small factorisations), and the contact providers' gathered psi rows are re-gathered
(ContactNodes.rebind).

The guard: a contact that carries force at a path parameter no window covers is reported
(``outside``: WARN, once, the run going on in the last window) or stops the run (STOP, the
driver keeping what it computed), as plastic_outside does for a plastic zone.
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from dataclasses import dataclass
from enum import Enum

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from flexmvm.bodies.build import BodyParts, body_from_parts
from flexmvm.bodies.invariants import inertia_invariants
from flexmvm.bodies.rotation import cross3
from flexmvm.integrate.state import BodyState
from flexmvm.reduction.kinds.mvm_moving import (
    MovingWindows,
    basis_signature,
    one_blas_thread,
    same_signature,
)

#: The switch's hysteresis: the contact centre must pass the half spacing by this fraction of
#: the spacing before the body switches (no switching back and forth at a boundary)
HYSTERESIS = 0.2


class MovingOutside(Enum):
    """What a run does when the contact reaches a place no window covers."""

    WARN = "warn"
    STOP = "stop"


class MovingRegionWarning(UserWarning):
    """The contact of a moving region reached a place no window covers."""


@dataclass(frozen=True)
class Switch:
    """One switch at t_s [s] from window ``old`` to ``new`` with the contact centre at s_m;
    the body's kinetic and strain energy [J], linear momentum [kg m/s] and angular momentum
    [kg m^2/s] before and after the projection."""

    t_s: float
    old: int
    new: int
    s_m: float
    kinetic: tuple[float, float]
    strain: tuple[float, float]
    momentum: tuple[np.ndarray, np.ndarray]
    angular: tuple[np.ndarray, np.ndarray]


class MovingRegion:
    """The run-time state of body ``index`` reduced on ``windows``: the window it holds
    (``window``), the bodies of the windows used (made once each), the switches made and the
    guard's finding. Its first body: ``body(start)``."""

    def __init__(
        self,
        index: int,
        windows: MovingWindows,
        name: str,
        start: int = 0,
        outside: MovingOutside = MovingOutside.WARN,
        hysteresis: float = HYSTERESIS,
    ):
        self.index, self.windows, self.name = index, windows, name
        self.window, self.outside, self.hysteresis = start, MovingOutside(outside), hysteresis
        self._bodies: dict[int, object] = {}
        self.parts: dict[int, BodyParts] = {}  # each window's parts (made, or from the cache)
        # the signatures of the bases stored parts came from (basis_signature), and how many
        # windows made again differed from theirs (their parts then made again too)
        self.signatures: dict[int, np.ndarray] = {}
        self.parts_remade = 0
        self.switches: list[Switch] = []
        self.uncovered: str | None = None  # the guard's message, once the contact left
        self.centres: list[tuple[float, float]] = []  # (t, s) of the contact centre
        self.switch_cpu_s = 0.0  # CPU [s] of the switches (projections, rebinds, integrators)
        self.setup_cpu_s = 0.0  # CPU [s] of the windows' setup, when its maker measured it

    def body(self, k: int):
        """The FlexibleBody of window k (its parts made on first use unless ``parts`` holds
        them: a setup-cache entry, used only if the basis made now has the signature of the
        one they came from)."""
        if k not in self._bodies:
            fe = self.windows.factor.fe
            with one_blas_thread():  # small products, shared cores
                basis = self.windows.basis(k)
                stored = self.signatures.get(k) if k in self.parts else None
                if stored is not None and not same_signature(basis_signature(basis.psi), stored):
                    del self.parts[k]
                    self.parts_remade += 1
                if k not in self.parts:
                    inv = inertia_invariants(fe.mesh.nodes, fe.M_scalar, basis.psi)
                    self.parts[k] = BodyParts(inv, self.windows.stiffness(k))  # no K psi
            self._bodies[k] = body_from_parts(self.name, fe.mesh, basis, self.parts[k])
        return self._bodies[k]

    # -- the driver's hook -------------------------------------------------------------------
    def after_step(self, t_s: float, system, states, result):
        """(system, states) with the body switched to the window of the contact centre, or
        None (no contact carrying force, or still inside the window's hysteresis band)."""
        s = contact_centre(system, states, result, self.index, self.windows)
        if s is None:
            return None
        self.centres.append((t_s, s))
        if not self.windows.covers(s):
            self._guard(t_s, s)
            return None
        w = self.windows
        if abs(s - w.centres[self.window]) <= (0.5 + self.hysteresis) * w.spacing_m:
            return None
        new = w.nearest(s)
        if new == self.window:
            return None
        c0 = time.process_time()
        moved = self.switch_window(t_s, system, states, new, s)
        self.switch_cpu_s += time.process_time() - c0
        return moved

    def outside_stop(self) -> str | None:
        """The guard's message when the run must stop (STOP), else None."""
        return self.uncovered if self.outside is MovingOutside.STOP else None

    def _guard(self, t_s: float, s: float) -> None:
        if self.uncovered is not None:
            return
        lo, hi = self.windows.covered
        self.uncovered = (
            f"body {self.name!r}: the contact reached s = {s:.6g} m on its moving region's path "
            f"at t = {t_s:.6g} s; its windows cover s in [{lo:.6g}, {hi:.6g}] m"
        )
        if self.outside is MovingOutside.WARN:
            warnings.warn(self.uncovered, MovingRegionWarning, stacklevel=3)

    def switch_window(self, t_s: float, system, states, new: int, s: float = float("nan")):
        """The system with body ``index`` on window ``new`` and the states carried over
        (project_state); the contact providers re-gather the body's rows."""
        b, old = self.index, self.window
        body_a, body_b = self.body(old), self.body(new)
        st = states[b]
        moved = project_state(self.windows, old, new, body_a, body_b, st)
        bodies = list(system.bodies)
        bodies[b] = body_b
        system = dataclasses.replace(system, bodies=tuple(bodies))
        rebind_contacts(system, b, body_b)
        states = list(states)
        states[b] = moved
        self.switches.append(
            Switch(
                t_s,
                old,
                new,
                s,
                (
                    body_a.kinetic_energy(st.A, st.q, st.v),
                    body_b.kinetic_energy(st.A, moved.q, moved.v),
                ),
                (body_a.strain_energy(st.q), body_b.strain_energy(moved.q)),
                (
                    body_a.linear_momentum(st.A, st.q, st.v),
                    body_b.linear_momentum(st.A, moved.q, moved.v),
                ),
                (
                    body_a.angular_momentum(st.r, st.A, st.q, st.v),
                    body_b.angular_momentum(st.r, st.A, moved.q, moved.v),
                ),
            )
        )
        self.window = new
        return system, states


class MovingRegions:
    """The driver's hook for several moving regions in one run (one per body): after every
    accepted step each region may switch its body's window, one after the other on the system
    the previous one left. ``regions``: their MovingRegion, in body order."""

    def __init__(self, regions):
        self.regions = tuple(regions)

    def after_step(self, t_s: float, system, states, result):
        """(system, states) after the switches of every region that switched, or None."""
        moved = None
        for region in self.regions:
            out = region.after_step(t_s, system, states, result)
            if out is not None:
                moved = system, states = out
        return moved

    def outside_stop(self) -> str | None:
        """The first region's message that stops the run (MovingRegion.outside_stop), or None."""
        return next((m for r in self.regions if (m := r.outside_stop()) is not None), None)

    def region(self, name: str) -> MovingRegion:
        """The region of body ``name``."""
        return next(r for r in self.regions if r.name == name)


def contact_centre(system, states, result, index: int, windows: MovingWindows) -> float | None:
    """The path parameter s [m] of the force-weighted centre of the contact points that carried
    a compressive normal impulse in the step (contact rows (contact name, slave node, facet)) with
    body ``index`` as slave or master: the slave node's position in the body's frame; None
    when no such row carried any."""
    crows, lam = result.contact, result.contact_impulses
    total, point = 0.0, np.zeros(3)
    for i in np.flatnonzero(lam > 0.0):
        key = crows.keys[i]
        if i < crows.n_eq or len(key) != 3:
            continue
        provider = next((c for c in system.contacts if c.name == key[0]), None)
        if provider is None:
            continue
        if index not in (provider.slave, provider.master):
            continue
        sb, st = provider.slave, states[provider.slave]
        x = system.bodies[sb].node_positions(np.array([key[1]]), st.r, st.A, st.q)[0]
        own = states[index]
        point += lam[i] * (own.A.T @ (x - own.r))
        total += lam[i]
    if total <= 0.0:
        return None
    return windows.path.parameter(point / total)


def rebind_contacts(system, index: int, body) -> None:
    """Re-gather body ``index``'s psi rows in every contact provider (and its penetration
    measure) that holds them: their ContactNodes rebound to ``body``, in place."""
    for provider in system.contacts:
        provider.rebind(index, body)


def project_state(
    windows: MovingWindows, old: int, new: int, body_a, body_b, st: BodyState, keep_velocity=False
):
    """The state on window ``new`` of the state ``st`` on window ``old`` (module doc): q by
    the K-metric projection with the shared window nodes' displacements exact and the first
    moment kept; q_dot by the M-metric projection with both momenta kept (and, with
    keep_velocity, the shared nodes' velocities exact). The new window's k_hat and M_qq are
    its body's; the old field enters by one product with K and with M and one with psi_new^T
    (O(nnz K + n_dof nq), no product of the two bases)."""
    fe = windows.factor.fe
    psi_a, psi_b = windows.basis(old).psi, windows.basis(new).psi
    nodes_a, nodes_b = windows.basis(old).retained_nodes, windows.basis(new).retained_nodes
    shared = np.intersect1d(nodes_a, nodes_b)
    cols_a = (3 * np.searchsorted(nodes_a, shared)[:, None] + np.arange(3)).ravel()
    cols_b = (3 * np.searchsorted(nodes_b, shared)[:, None] + np.arange(3)).ravel()
    S1a, S1b = body_a.inv.S1, body_b.inv.S1
    ku = psi_b.T @ (fe.K @ (psi_a @ st.q))
    q = _closest(body_b.k_hat, ku, S1b, S1a @ st.q, cols_b, st.q[cols_a])
    qd_old = st.v[6:]
    frame_v = np.r_[st.A.T @ st.v[:3], st.v[3:6]]  # r_dot in the body frame, omega
    h_old = body_a.angular_momentum(np.zeros(3), np.eye(3), st.q, np.r_[frame_v, qd_old])
    S, J, M_wq, _ = body_b.inertia_terms(q)
    h_rest = cross3(S, frame_v[:3]) + J @ frame_v[3:]
    keep = (cols_b, qd_old[cols_a]) if keep_velocity else (cols_b[:0], qd_old[cols_a[:0]])
    rows, target = np.vstack([S1b, M_wq]), np.r_[S1a @ qd_old, h_old - h_rest]
    mu = psi_b.T @ (fe.M @ (psi_a @ qd_old))
    qd = _closest(body_b.inv.M_qq, mu, rows, target, *keep)
    return BodyState(st.r.copy(), st.A.copy(), q, np.r_[st.v[:6], qd])


def _closest(G, g, C, d, fixed, values) -> np.ndarray:
    """x = argmin 1/2 x^T G x - g^T x (G = psi^T W psi, g = psi^T W u: the W-closest psi x to
    u) with x[fixed] = values and C x = d (C (k, nq)): the coordinates ``fixed`` set, the
    others by the KKT system of the rest, solved by least squares (its rows may be
    dependent)."""
    G = G.toarray() if sp.issparse(G) else np.asarray(G)
    x = np.zeros(G.shape[0])
    x[fixed] = values
    free = np.setdiff1d(np.arange(G.shape[0]), fixed)
    Gf = G[np.ix_(free, free)]
    gf = g[free] - G[np.ix_(free, fixed)] @ values
    Cf = C[:, free]
    k = C.shape[0]
    kkt = np.block([[Gf, Cf.T], [Cf, np.zeros((k, k))]])
    rhs = np.r_[gf, d - C[:, fixed] @ values]
    x[free] = sla.lstsq(kkt, rhs, lapack_driver="gelsy")[0][: free.size]
    return x
