"""Geometric stiffening of spinning bodies (fe.geometric_stiffness, bodies.stiffening,
bodies.spin_modes, and its terms in the Moreau-Jean step) against closed forms.

The cantilever: aluminium, L = 1 m along x, 40 mm wide (y), 20 mm thick (z), root face at
x = 0 clamped, spinning about z through the root centre (hub radius 0); 8 x 1 x 1 HEX27 cells.
Its first mode is flapwise (z), at w_0 = 106.8 rad/s (Euler-Bernoulli 105.3); the second is
in-plane (lag, y) at 213.1 rad/s. Closed form (Southwell and Gough 1921, coefficient from the
exact solution of Wright, Smith, Thresher and Wang 1982, J. Appl. Mech. 49, 197-202):

    first flapwise:  w^2 = w_0^2 + K1 Omega^2,        K1 = 1.193
    first in-plane:  w^2 = w_0^2 + (K1 - 1) Omega^2   (spin softening -Omega^2 added)

and without the stiffening terms (the linear floating-frame model) the flapwise frequency stays
w_0 and the in-plane one falls as w_0^2 - Omega^2: it diverges above w_0. Module fixture
~2 s, tests ~10 s of CPU together (the three time runs ~8 s).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.sparse as sp
from test_fe import box_hex, box_tet10
from threadpoolctl import threadpool_limits

from flexmvm.assembly.build import build_scenario
from flexmvm.bodies.body import FlexibleBody
from flexmvm.bodies.spin_modes import spin_frequencies
from flexmvm.bodies.stiffening import geometric_stiffening
from flexmvm.constraints.joints import BodyPoint, revolute_joint
from flexmvm.errors import InputError, SolverError
from flexmvm.fe import assemble, constrained_modes
from flexmvm.fe.geometric_stiffness import (
    prestress_geometric_stiffness,
    spin_geometric_stiffness,
)
from flexmvm.fe.modes import shift_invert_modes
from flexmvm.integrate.moreau_jean import MoreauJeanIntegrator
from flexmvm.integrate.state import BodyState
from flexmvm.integrate.system import System
from flexmvm.materials import ALUMINIUM
from flexmvm.mesh.io import write_mesh
from flexmvm.scenarios import ScenarioError, scenario_from_dict

L, WIDTH, THICK = 1.0, 0.04, 0.02
K1 = 1.193  # Southwell coefficient, first flapwise mode, hub radius 0
OMEGA_BAR = 1.0  # Omega / sqrt(E I / (rho A L^4)): Southwell's K1 is exact to 0.1 % up to here


@dataclasses.dataclass(frozen=True)
class Cantilever:
    fe: object
    fixed: np.ndarray  # the root face's DOFs
    free: np.ndarray
    K_G: sp.csr_matrix  # geometric stiffness of a unit spin about z [kg]
    tip: int  # node at the tip's centre
    omega_ref: float  # sqrt(E I_flap / (rho A L^4)) [rad/s]


@pytest.fixture(scope="module")
def cantilever() -> Cantilever:
    mesh = box_hex((8, 1, 1), (L, WIDTH, THICK), order=2)
    mesh = dataclasses.replace(mesh, nodes=mesh.nodes - [0.0, WIDTH / 2, THICK / 2])
    fe = assemble(mesh, ALUMINIUM)
    X = mesh.nodes
    root = np.flatnonzero(np.isclose(X[:, 0], 0.0))
    fixed = (3 * root[:, None] + np.arange(3)).ravel()
    K_G, _ = spin_geometric_stiffness(fe, [0.0, 0.0, 1.0], fixed)
    tip = int(np.flatnonzero(np.isclose(X[:, 0], L) & np.all(np.isclose(X[:, 1:], 0.0), 1))[0])
    E, rho = ALUMINIUM.E, ALUMINIUM.rho
    omega_ref = float(np.sqrt(E * THICK**2 / 12.0 / (rho * L**4)))
    free = np.setdiff1d(np.arange(fe.n_dof), fixed)
    return Cantilever(fe, fixed, free, K_G, tip, omega_ref)


def _modal_body(c: Cantilever, n_modes: int, stiffened: bool) -> FlexibleBody:
    """The cantilever as a floating-frame body on its first clamped modes (frame at the root
    centre), with or without the stiffening."""
    _, phi = constrained_modes(c.fe.M, c.fe.K, c.fixed, n_modes)
    body = FlexibleBody.build("beam", c.fe.mesh.nodes, c.fe.M_scalar, phi, phi.T @ c.fe.K @ phi)
    if not stiffened:
        return body
    st = geometric_stiffening(c.fe, phi, body.k_hat, [0.0, 0.0, 1.0], c.fixed)
    return dataclasses.replace(body, stiffening=st)


@pytest.mark.parametrize(
    "mesh, degree",
    [
        (box_hex((4, 2, 1), (0.4, 0.1, 0.05), 1), 1),
        (box_hex((3, 1, 1), (0.4, 0.1, 0.05), 2), 2),
        (box_tet10((3, 2, 2), (0.4, 0.1, 0.05)), 2),
    ],
    ids=["hex8", "hex27", "tet10"],
)
def test_uniform_prestress_energy(mesh, degree):
    """A uniaxial prestress sigma_xx = E eps (from u = eps (x, -nu y, -nu z)) and the transverse
    field v_z = x^p (p = 1, 2: interpolated exactly by the cells) have
    v^T K_G v = sigma int (p x^(p-1))^2 dV = sigma A p^2 L^(2p-1) / (2p - 1)
    (Bathe sec. 6.3: the stress times the square of the gradient); exact to round-off (1e-12):
    the Gauss rules integrate these polynomials exactly. K_G is symmetric and has no coupling
    between components (kron(S_G, I3))."""
    fe = assemble(mesh, ALUMINIUM)
    X = mesh.nodes
    eps, nu = 1e-4, ALUMINIUM.nu
    u = np.column_stack([eps * X[:, 0], -nu * eps * X[:, 1], -nu * eps * X[:, 2]]).ravel()
    K_G = prestress_geometric_stiffness(fe, u)
    length, area = 0.4, 0.1 * 0.05
    v = np.zeros_like(X)
    v[:, 2] = X[:, 0] ** degree
    expected = ALUMINIUM.E * eps * area * degree**2 * length ** (2 * degree - 1) / (2 * degree - 1)
    assert float(v.ravel() @ (K_G @ v.ravel())) == pytest.approx(expected, rel=1e-12)
    assert abs(K_G - K_G.T).max() <= 1e-12 * abs(K_G).max()
    cross = K_G[0::3][:, 1::3]  # x rows, y columns
    assert abs(cross).max() == 0.0


def test_spin_prestress_virial(cantilever):
    """The unit-spin prestress of the clamped cantilever integrates to the virial of its body
    force: with w = (x, 0, 0) (zero on the root, in the FE space), int sigma_xx dV =
    int rho x^2 dV = rho A L^3 / 3 exactly, and the field v_z = x reads it off K_G:
    v^T K_G v = int sigma_xx dV. Exact up to the sparse solve's round-off (1e-10)."""
    c = cantilever
    v = np.zeros_like(c.fe.mesh.nodes)
    v[:, 2] = c.fe.mesh.nodes[:, 0]
    expected = ALUMINIUM.rho * WIDTH * THICK * L**3 / 3.0
    assert float(v.ravel() @ (c.K_G @ v.ravel())) == pytest.approx(expected, rel=1e-10)


def test_southwell_full_fe(cantilever):
    """The clamped FE cantilever spinning at Omega_bar = 1: the first eigenvalue of
    (K + Omega^2 K_G - Omega^2 M_perp, M) (M_perp: the mass of the motion across the axis,
    spin softening; Coriolis does not couple the flapwise mode) against the Southwell relation:
    K1 within 1 % (measured +0.65 % on these 8 cells, +0.3 % on 16 x 2 x 1: the mesh's
    flap mode converges from above; Southwell's own error at Omega_bar = 1 is 0.1 %).
    Without K_G the flapwise frequency stays w_0 (|K1| < 1e-3: the mode's small axial motion
    feels the spin softening)."""
    c = cantilever
    sub = lambda a: sp.csr_matrix(a)[c.free][:, c.free]
    M_perp = sp.kron(c.fe.M_scalar, sp.diags([1.0, 1.0, 0.0]))
    M, K = sub(c.fe.M), sub(c.fe.K)
    lam0 = shift_invert_modes(M, K, 1, 0.0)[0][0]
    omega = OMEGA_BAR * c.omega_ref
    lam = shift_invert_modes(M, sub(c.fe.K + omega**2 * (c.K_G - M_perp)), 1, 0.0)[0][0]
    assert (lam - lam0) / omega**2 == pytest.approx(K1, rel=0.01)
    lam_lin = shift_invert_modes(M, sub(c.fe.K - omega**2 * M_perp), 1, 0.0)[0][0]
    assert abs(lam_lin - lam0) / omega**2 < 1e-3


def test_southwell_reduced_body(cantilever):
    """The same on the floating-frame body of 12 clamped modes with K_G projected on them
    (psi^T K_G psi), from its linearized equations with Coriolis (bodies.spin_modes): flapwise
    K1 within 1 % (as the full FE: the projection loses nothing measurable, 1e-6), in-plane
    (K1 - 1) Omega^2 within 5 % of 0.193 (a difference of two near numbers: K1 - 1 carries
    K1's discretization error five times). Without the terms the flapwise frequency stays w_0
    (1e-3) and the in-plane one diverges above its w_0: SolverError."""
    c = cantilever
    body = _modal_body(c, 12, stiffened=True)
    w0 = spin_frequencies(body, np.zeros(3))
    omega = OMEGA_BAR * c.omega_ref
    w = spin_frequencies(body, [0.0, 0.0, omega])
    assert (w[0] ** 2 - w0[0] ** 2) / omega**2 == pytest.approx(K1, rel=0.01)
    assert (w[1] ** 2 - w0[1] ** 2) / omega**2 == pytest.approx(K1 - 1.0, rel=0.05)
    w_lin = spin_frequencies(body, [0.0, 0.0, omega], stiffening=False)
    assert w_lin[0] == pytest.approx(w0[0], rel=1e-3)
    fast = [0.0, 0.0, 1.2 * w0[1]]  # above the in-plane frequency
    assert np.all(np.isfinite(spin_frequencies(body, fast)))
    with pytest.raises(SolverError, match="diverges"):
        spin_frequencies(body, fast, stiffening=False)


def _flap_frequency(body, tip, omega, w_eig, mode, periods, per_period):
    """Spin the body steadily at omega about z on a revolute joint at its frame origin (the
    root centre), its elastic velocity 0.01 * mode, theta = 1/2, h = 2 pi / (w_eig
    per_period); the tip's flapwise displacement's upward zero crossings give the frequency.
    Returns (measured [rad/s], h [s], the body's BodySolver)."""
    h = 2.0 * np.pi / w_eig / per_period
    v = np.zeros(body.nv)
    v[5], v[6:] = omega, 0.01 * mode
    states = [BodyState(np.zeros(3), np.eye(3), np.zeros(body.nq), v)]
    joints = revolute_joint(BodyPoint(0, local=(0.0, 0.0, 0.0)), np.zeros(3), [0, 0, 1], states)
    integ = MoreauJeanIntegrator(System((body,), tuple(joints)), theta=0.5)
    z = np.empty(periods * per_period)
    with threadpool_limits(limits=1, user_api="blas"):
        for k in range(z.size):
            states = integ.step(k * h, states, h).states
            z[k] = body.local_displacements(np.array([tip]), states[0].q)[0, 2]
    t = h * np.arange(1, z.size + 1)
    z -= z.mean()
    up = np.flatnonzero((z[:-1] < 0.0) & (z[1:] >= 0.0))
    crossings = t[up] - z[up] * h / (z[up + 1] - z[up])
    # a steady spin: the joint leaves omega_z free, and a full-FE body's centrifugal stretch
    # (rho Omega^2 L^2 / E ~ 1e-4) changes its inertia about the axis by as much
    assert states[0].v[5] == pytest.approx(omega, rel=1e-3)
    return 2.0 * np.pi / np.mean(np.diff(crossings)), h, integ.solvers[0]


@pytest.mark.parametrize("stiffened", [True, False], ids=["with", "without"])
def test_steady_spin_time_run(cantilever, stiffened):
    """The time run (6 modes, Omega_bar = 2, 32 steps a period, 6 periods) at theta = 1/2 has
    the flapwise frequency of the eigen-analysis as the implicit midpoint rule sees it,
    (2/h) arctan(w h / 2) (exact for a linear oscillator), within 3e-5 (zero crossings by
    linear interpolation over 5 periods; measured 3e-6, both runs): with the terms raised by the
    Southwell relation (K1 within 1 %), without them at w_0. W is factored once: the spin
    squared is constant after the first step (BodySolver.use_spin)."""
    c = cantilever
    body = _modal_body(c, 6, stiffened)
    omega = 2.0 * c.omega_ref
    w_eig = spin_frequencies(body, [0.0, 0.0, omega])[0]
    mode = np.eye(body.nq)[0]
    measured, h, solver = _flap_frequency(body, c.tip, omega, w_eig, mode, 6, 32)
    assert measured == pytest.approx(2.0 / h * np.arctan(w_eig * h / 2.0), rel=3e-5)
    w0 = spin_frequencies(body, np.zeros(3))[0]
    if stiffened:
        # Southwell at Omega_bar = 2: the exact coefficient is 1.189 there (0.4 % below K1)
        assert (w_eig**2 - w0**2) / omega**2 == pytest.approx(K1, rel=0.01)
        assert solver.n_spin_updates == 1 and solver.n_factorizations == 1
    else:
        assert w_eig == pytest.approx(w0, rel=1e-3)
        assert solver.n_spin_updates == 0


def test_steady_spin_time_run_full_fe(cantilever):
    """The same run on the full-FE body (432 DOF, sparse K_G on its free DOFs; 4 periods,
    ~3 s): the flapwise frequency within 1e-4 of the FE eigenvalue of (K + Omega^2 (K_G -
    M_perp), M) seen by the midpoint rule (measured 2.6e-5: that eigen-analysis leaves out the
    Coriolis coupling of the mode's small axial motion, which the run keeps)."""
    c = cantilever
    free = c.free
    psi = sp.csr_matrix((np.ones(free.size), (free, np.arange(free.size))), (c.fe.n_dof, free.size))
    k_hat = sp.csr_matrix(c.fe.K)[free][:, free]
    body = FlexibleBody.build("beam", c.fe.mesh.nodes, c.fe.M_scalar, psi, k_hat)
    st = geometric_stiffening(c.fe, psi, body.k_hat, [0.0, 0.0, 1.0], c.fixed)
    body = dataclasses.replace(body, stiffening=st)
    omega = 2.0 * c.omega_ref
    M_perp = sp.kron(c.fe.M_scalar, sp.diags([1.0, 1.0, 0.0]))
    K_spin = sp.csr_matrix(c.fe.K + omega**2 * (c.K_G - M_perp))[free][:, free]
    lam, phi = shift_invert_modes(sp.csr_matrix(c.fe.M)[free][:, free], K_spin, 1, 0.0)
    w_eig = float(np.sqrt(lam[0]))
    measured, h, solver = _flap_frequency(body, c.tip, omega, w_eig, phi[:, 0], 4, 32)
    assert measured == pytest.approx(2.0 / h * np.arctan(w_eig * h / 2.0), rel=1e-4)
    assert solver.n_spin_updates == 1


def test_bad_input(cantilever):
    """One-line InputErrors: a zero axis, supports that leave the body free."""
    c = cantilever
    with pytest.raises(InputError, match="spin axis"):
        spin_geometric_stiffness(c.fe, [0.0, 0.0, 0.0], c.fixed)
    with pytest.raises(InputError, match="supports"):
        spin_geometric_stiffness(c.fe, [0.0, 0.0, 1.0], c.fixed[:2])


def _scenario(mesh_path, stiffening) -> dict:
    """A scenario of the cantilever's mesh file as a full-FE body (3-2-1 reference on its root
    face) with the given geometric_stiffening table (None: without the key)."""
    model = {"kind": "full", "reference": "root"}
    if stiffening is not None:
        model["geometric_stiffening"] = stiffening
    body = {"name": "beam", "material": "aluminium", "mesh_file": str(mesh_path), "model": model}
    time = {"t_end_s": 1e-3, "dt_s": 1e-5, "output_dt_s": 1e-4}
    return {"name": "spin", "time": time, "bodies": [body]}


def test_scenario_key(cantilever, tmp_path):
    """[bodies.model] geometric_stiffening on a full-FE body: the built body carries the
    stiffening of its (normalized) axis, the prestress supported by its 3-2-1 reference on the
    root face, whose virial is the clamped one's (every support at x = 0: v^T K_G v =
    rho A L^3/3 for v_z = x, to 1e-9); a scenario without the key dumps without it (study keys
    hash the dumps), and a zero axis is a one-line ScenarioError naming the key."""
    X = cantilever.fe.mesh.nodes
    mesh = dataclasses.replace(
        cantilever.fe.mesh, node_sets={"root": np.flatnonzero(np.isclose(X[:, 0], 0.0))}
    )
    path = tmp_path / "beam.vtu"
    write_mesh(path, mesh)
    sc = scenario_from_dict(_scenario(path, {"axis": [0, 0, 2]}))
    body = build_scenario(sc).system.bodies[0]
    assert np.array_equal(body.stiffening.axis, [0.0, 0.0, 1.0])
    v = np.zeros_like(X)
    v[:, 2] = X[:, 0]
    vq = body.psi.T @ v.ravel()  # the full-FE basis selects the free DOFs
    expected = ALUMINIUM.rho * WIDTH * THICK * L**3 / 3.0
    assert float(vq @ (body.stiffening.K_G @ vq)) == pytest.approx(expected, rel=1e-9)
    assert 0.0 < body.stiffening.spin_crit < np.inf
    plain = scenario_from_dict(_scenario(path, None))
    assert "geometric_stiffening" not in plain.model_dump()["bodies"][0]["model"]
    with pytest.raises(ScenarioError, match="geometric_stiffening.axis: must be non-zero"):
        scenario_from_dict(_scenario(path, {"axis": [0, 0, 0]}))
