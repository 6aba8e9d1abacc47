"""Supports beyond one clamp (issue 52 item 5, issue 53 item 2): a clamp on several node sets,
node sets held in chosen directions (pinned, roller, symmetry, fixed axes; reduction.clamp,
assembly.supports) and a spring bed on a facet set (fe/spring_bed.py).

Closed forms:
- Simply supported beam: f_n = (n^2 pi / (2 L^2)) sqrt(E I / (rho A)) (Euler-Bernoulli). The
  beam is aluminium, L = 1 m, b = h = 0.05 m (L/h = 20), 20 HEX27 cells along it, one across;
  pinned on the line x = 0, z = 0 (the neutral axis across the width: every translation held,
  turning about the line free), on rollers (z and y held) on the line x = L, z = 0.
  Timoshenko's shear and rotary inertia lower f_1, f_2, f_3 by 0.42 %, 1.65 %, 3.57 % at
  L/h = 20 (theory.timoshenko.simply_supported_omega, Cowper's kappa). Measured (2026-11-29):
  FE against Euler-Bernoulli -0.37 %, -1.43 %, -3.11 %; against Timoshenko +0.06 %, +0.22 %,
  +0.48 % (the mesh's error, growing with n). Tolerances: 0.3 % / 0.6 % / 1 % against
  Timoshenko (twice the mesh's error), and the first within 1 % of Euler-Bernoulli.
- Beam on a Winkler foundation under a central point load P (Hetenyi 1946): w0 = P beta /
  (2 k_f), beta = (k_f / (4 E I))^(1/4), k_f [N/m^2] the foundation modulus per length = the
  bed's k [N/m^3] times the width b. L = 4 m, b = h = 0.05 m, 40 HEX27 cells, beta L = 8 (the
  ends' effect e^(-beta L / 2) cos: < 0.1 %), beta h = 0.1. Measured +0.40 % with 40 cells,
  +0.45 % with 80, +0.34 % on a beam twice as long (beta L = 16): shear deformation and the
  load's local spreading, growing as ~0.4 (beta h)^2 (measured +1.7 % at beta h = 0.2).
  Tolerance 1 %.

The file takes ~3 s on a loaded machine (26 tests).
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
import scipy.sparse as sp
from _cantilever import ROD
from scipy.sparse.linalg import spsolve

from flexmvm.assembly.build import build_scenario
from flexmvm.assembly.build_cache import SetupCache
from flexmvm.errors import InputError
from flexmvm.fe.assembly import assemble
from flexmvm.fe.modes import shift_invert_modes
from flexmvm.fe.spring_bed import BedDirection, spring_bed_stiffness, with_spring_bed
from flexmvm.materials import ALUMINIUM
from flexmvm.mesh.io import write_mesh
from flexmvm.mesh.mesh import FacetSet, Mesh
from flexmvm.mesh.structured import hex27_beam
from flexmvm.reduction.clamp import bed_rigid_stiffness, held_condition, held_dofs
from flexmvm.scenarios.load import scenario_from_dict
from flexmvm.scenarios.problems import ScenarioError
from flexmvm.theory.timoshenko import TimoshenkoBeam, simply_supported_omega

L, B, H, NX = 1.0, 0.05, 0.05, 20
PIN = {"type": "pinned", "body": "beam", "node_set": "pin_line"}
ROLL_Z = {"type": "roller", "body": "beam", "node_set": "roller_line", "direction": "z"}
ROLL_Y = {**ROLL_Z, "direction": "y"}
BED = {
    "type": "spring_bed",
    "body": "beam",
    "surface": "surface",
    "stiffness_n_per_m3": 1e9,
    "direction": "normal",
}


@functools.cache
def _setup() -> SetupCache:
    return SetupCache()


def _beam(length: float, nx: int) -> Mesh:
    """The HEX27 beam (module doc) with node sets: the lines x = 0 and x = L at z = 0
    (pin_line, roller_line), the end faces (left, right) and both end faces (ends)."""
    mesh = hex27_beam(length, B, H, nx)
    x, _, z = mesh.nodes.T
    left, right = np.isclose(x, 0.0), np.isclose(x, length)
    sets = dict(mesh.node_sets)
    sets |= {
        "pin_line": np.flatnonzero(left & np.isclose(z, 0.0)),
        "roller_line": np.flatnonzero(right & np.isclose(z, 0.0)),
        "left": np.flatnonzero(left),
        "right": np.flatnonzero(right),
        "ends": np.flatnonzero(left | right),
    }
    return Mesh(mesh.nodes, mesh.cells, node_sets=sets)


@functools.cache
def _beam_file(tmp_dir: str) -> str:
    path = f"{tmp_dir}/beam.vtu"
    write_mesh(path, _beam(L, NX))
    return path


@pytest.fixture
def beam_file(tmp_path_factory) -> str:
    return _beam_file(str(tmp_path_factory.getbasetemp()))


def _scenario(mesh_file: str, supports, model=None, rotation=None):
    body = {"name": "beam", "material": "aluminium", "mesh_file": mesh_file}
    body["model"] = model or {"kind": "full"}
    if rotation is not None:
        body["placement"] = {"rotation": rotation}
    data = {
        "name": "supported",
        "time": {"t_end_s": 1e-4, "dt_s": 1e-5, "output_dt_s": 1e-5, "theta": 0.5},
        "bodies": [body],
        "supports": list(supports),
    }
    return scenario_from_dict(data)


def _modes(body, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The lowest n frequencies [Hz] of the body with its frame held and their nodal shapes
    psi phi (3 n_nodes, n)."""
    lam, phi = shift_invert_modes(sp.csr_matrix(body.inv.M_qq), sp.csr_matrix(body.k_hat), n, 0.0)
    return np.sqrt(lam) / (2 * np.pi), body.psi @ phi


MID_BALL = {"ball": {"centre_m": [0.5, 0.0, 0.025], "radius_m": 0.01}}


@pytest.mark.parametrize(
    "model",
    [
        {"kind": "full"},
        {"kind": "modal", "modes": 10},
        {"kind": "mvm", "region": MID_BALL, "modes": 8},
    ],
    ids=["full", "modal", "craig-bampton"],
)
def test_simply_supported_beam_bending_frequencies(beam_file, model):
    """Pinned line at one end, rollers (z and y) at the other: the first three vertical
    bending frequencies against Euler-Bernoulli and Timoshenko (module doc, tolerances
    there), for full FE, the supported body's modes and a Craig-Bampton body retaining the
    top centre's nodes (measured: its f_1 +6e-5 above the full body's). The modes whose
    shape is > 90 % vertical are the vertical bending ones."""
    built = build_scenario(_scenario(beam_file, (PIN, ROLL_Z, ROLL_Y), model), _setup())
    f, shapes = _modes(built.system.bodies[0], 10)
    vertical = np.linalg.norm(shapes[2::3], axis=0) / np.linalg.norm(shapes, axis=0) > 0.9
    f_z = f[vertical][:3]
    E, rho, nu = ALUMINIUM.E, ALUMINIUM.rho, ALUMINIUM.nu
    n = np.arange(1, 4)
    euler = n**2 * math.pi / (2 * L**2) * math.sqrt(E * B * H**3 / 12 / (rho * B * H))
    beam = TimoshenkoBeam(L, B, H, E, nu, rho)
    timoshenko = np.array([simply_supported_omega(beam, k) for k in n]) / (2 * math.pi)
    assert np.all(np.abs(f_z / timoshenko - 1.0) < [0.003, 0.006, 0.01])
    assert f_z[0] == pytest.approx(euler[0], rel=0.01)
    assert sum(j.n_rows for j in built.system.joints) == 6  # one ground joint for 3 supports


def test_a_dof_held_twice_is_held_once(beam_file):
    """Rollers z and y on one line, a fixed [z] on it again and a pinned line given twice
    hold the same DOFs as pinned + fixed [y, z]: merged, not refused."""
    fixed_yz = {**ROLL_Z, "type": "fixed", "fixed": ["y", "z"]}
    del fixed_yz["direction"]
    again = {**fixed_yz, "fixed": ["z"]}
    one = build_scenario(_scenario(beam_file, (PIN, fixed_yz)), _setup()).system.bodies[0]
    many = _scenario(beam_file, (PIN, ROLL_Z, ROLL_Y, again, PIN))
    body = build_scenario(many, _setup()).system.bodies[0]
    mesh = _beam(L, NX)
    held = 3 * mesh.node_set("pin_line").size + 2 * mesh.node_set("roller_line").size
    assert body.nq == one.nq == mesh.n_dof - held


def test_global_directions_follow_the_placement(beam_file):
    """A beam placed turned 90 deg about z: global x is its body y, so a roller in global
    x and one in body y hold the same DOFs; a roller along a global axis that is no body
    axis is refused in one line."""
    turned = {"axis": [0.0, 0.0, 1.0], "angle_deg": 90.0}
    glob = {**ROLL_Y, "direction": "x", "frame": "global"}
    a = _scenario(beam_file, (PIN, ROLL_Z, glob), rotation=turned)
    b = _scenario(beam_file, (PIN, ROLL_Z, ROLL_Y), rotation=turned)
    body_a = build_scenario(a, _setup()).system.bodies[0]
    body_b = build_scenario(b, _setup()).system.bodies[0]
    assert body_a.nq == body_b.nq
    assert abs(body_a.psi - body_b.psi).max() == 0.0
    oblique = _scenario(beam_file, (PIN, ROLL_Z, glob), rotation={**turned, "angle_deg": 30.0})
    with pytest.raises(InputError, match="is not along a body axis") as e:
        build_scenario(oblique, _setup())
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("model", [{"kind": "full"}, {"kind": "modal", "modes": 6}])
def test_plate_clamped_on_two_sets_equals_its_union(beam_file, model):
    """A clamp on the list [left, right], two clamps (one per edge) and a clamp on their
    union give the same basis and frequencies (the held DOFs are the same: round-off)."""
    listed = {"type": "clamp", "body": "beam", "node_set": ["left", "right"]}
    two = ({**listed, "node_set": "left"}, {**listed, "node_set": "right"})
    union = {**listed, "node_set": "ends"}
    bodies = [
        build_scenario(_scenario(beam_file, s, model), _setup()).system.bodies[0]
        for s in ((listed,), two, (union,))
    ]
    f = [_modes(b, 4)[0] for b in bodies]
    for b, fk in zip(bodies[1:], f[1:], strict=True):
        assert b.nq == bodies[0].nq
        np.testing.assert_allclose(fk, f[0], rtol=1e-9)


@pytest.mark.parametrize(
    "support, message",
    [
        ({**ROLL_Z, "direction": "w"}, "supports[0].direction"),
        ({**PIN, "direction": "z"}, "a pinned support takes no 'direction'"),
        ({k: v for k, v in ROLL_Z.items() if k != "direction"}, "a roller support needs"),
        ({**ROLL_Z, "type": "fixed", "fixed": ["z", "z"], "direction": None}, "distinct"),
        ({**ROLL_Z, "frame": "global", "ground_frame": False}, "need the frame fixed"),
        ({**ROLL_Z, "direction": "normal"}, "a roller's direction must be x, y or z"),
        ({**BED, "surface": None}, "a spring_bed support needs 'surface'"),
        ({**BED, "node_set": "left"}, "a spring_bed support takes no 'node_set'"),
        ({**BED, "stiffness_n_per_m3": -1.0}, "supports[0].stiffness_n_per_m3"),
    ],
    ids=[
        "unknown-direction",
        "pinned-direction",
        "roller-without",
        "fixed-repeat",
        "global",
        "roller-normal",
        "bed-without-surface",
        "bed-on-nodes",
        "bed-negative",
    ],
)
def test_bad_directional_supports_give_one_line_errors(beam_file, support, message):
    """Each mistake is one ScenarioError line naming the key."""
    support = {k: v for k, v in support.items() if v is not None}
    with pytest.raises(ScenarioError, match=message.replace("[", r"\[")) as e:
        _scenario(beam_file, (support,))
    assert "\n" not in str(e.value)


@pytest.mark.parametrize(
    "supports, message",
    [
        ((ROLL_Z,), "leave 4 of the 6 rigid-body motions free"),  # z and tilt about x held
        ((PIN,), "leave 1 of the 6 rigid-body motions free"),  # turning about the pin line
        (({**PIN, "node_set": ["pin_line", "tip"]}, {**PIN, "node_set": "nowhere"}), "nowhere"),
        ((PIN, {**BED, "surface": "nowhere"}), "unknown surface 'nowhere'"),
    ],
    ids=["one-roller", "one-pin-line", "unknown-set", "unknown-surface"],
)
def test_supports_that_do_not_hold_the_body_are_refused(beam_file, supports, message):
    """A free body on one roller, or pinned on one line, is refused (not kept floating), as
    is an unknown set: one InputError line naming the supports."""
    with pytest.raises(InputError, match=message) as e:
        build_scenario(_scenario(beam_file, supports), _setup())
    assert str(e.value).startswith("supports[") and "\n" not in str(e.value)


def _bottom(mesh: Mesh, nx: int) -> FacetSet:
    """The bottom face z = -h/2 of a hex27_beam as linear sub-quads, normals -z."""
    ids = np.arange(mesh.n_nodes).reshape(2 * nx + 1, 3, 3)[:, :, 0]
    quads = np.stack([ids[:-1, :-1], ids[:-1, 1:], ids[1:, 1:], ids[1:, :-1]], axis=-1)
    return FacetSet(quads=quads.reshape(-1, 4))


def test_beam_on_winkler_foundation_central_deflection():
    """A free beam on a spring bed (its bottom face, the facet normal held) under a central
    load P = 1 kN spread across the width on the mid-height line: w0 = P beta / (2 k_f)
    within 1 % (module doc). The bed holds z and the tilts; the symmetry planes x = L/2
    (x held) and y = 0 (y held) hold the rest. The bed's stiffness against a uniform z
    translation is k b L (the surface's area) to round-off."""
    length, nx, beta = 4.0, 40, 2.0
    E, inertia = ALUMINIUM.E, B * H**3 / 12
    k_f = 4 * E * inertia * beta**4  # [N/m^2]
    mesh = _beam(length, nx)
    k_bed = spring_bed_stiffness(mesh, _bottom(mesh, nx), k_f / B, BedDirection.NORMAL)
    assert k_bed[2::3, 2::3].sum() == pytest.approx(k_f * length, rel=1e-12)
    x, y, z = mesh.nodes.T
    mid, sym = np.flatnonzero(np.isclose(x, length / 2)), np.flatnonzero(np.isclose(y, 0.0))
    dofs = np.r_[held_dofs(mid, "x"), held_dofs(sym, "y")]
    with pytest.raises(InputError, match="rigid-body motions free"):
        held_condition(mesh, dofs)  # without the bed: z and the tilts are free
    ref = held_condition(mesh, dofs, bed_rigid_stiffness(mesh, k_bed))
    fe = with_spring_bed(assemble(mesh, ALUMINIUM), k_bed)
    load = np.flatnonzero(np.isclose(x, length / 2) & np.isclose(z, 0.0))
    f = np.zeros(mesh.n_dof)
    f[3 * load + 2] = -1e3 * np.where(np.isclose(y[load], 0.0), 4 / 6, 1 / 6)  # quadratic edge
    free = ref.free_dofs(mesh.n_dof)
    u = np.zeros(mesh.n_dof)
    u[free] = spsolve(sp.csc_matrix(fe.K[free][:, free]), f[free])
    centre = load[np.isclose(y[load], 0.0)][0]
    assert -u[3 * centre + 2] == pytest.approx(1e3 * beta / (2 * k_f), rel=0.01)


def _rod_scenario(supports, model=None):
    """The aluminium rod of tests/_cantilever.py (L = 0.6 m, r = 0.01 m) on ``supports``."""
    body = {"name": "rod", "material": "aluminium", "rod": ROD, "model": model or {"kind": "full"}}
    data = {
        "name": "bedded",
        "time": {"t_end_s": 1e-4, "dt_s": 1e-5, "output_dt_s": 1e-5, "theta": 0.5},
        "bodies": [body],
        "supports": list(supports),
    }
    return scenario_from_dict(data)


AXIAL_BED = {
    "type": "spring_bed",
    "body": "rod",
    "surface": "side",
    "stiffness_n_per_m3": 5e8,
    "direction": "x",
}
ENDS_YZ = {"type": "fixed", "body": "rod", "node_set": ["end_a", "end_b"], "fixed": ["y", "z"]}


@pytest.mark.parametrize("model", [{"kind": "full"}, {"kind": "modal", "modes": 6}])
def test_rod_on_an_axial_spring_bed(model):
    """A rod whose side carries an axial spring bed k [N/m^3] (a scenario's spring_bed
    support; its K holds the bed in every basis) and whose end faces are held in y and z
    only: its axial translation on the bed has omega^2 = k A_side / m = 2 k / (rho r) (a rigid
    translation; the shear lag across the radius lowers it by ~k r / G ~ 2e-4). The mesh
    (an O-grid with one ring) has a side area 2.55 % below 2 pi r L (the bed is integrated
    on the linear sub-facets of the quadratic faces, chords of the circle) and a mass 1.18 %
    below rho pi r^2 L: measured -0.70 % against 2 k / (rho r), -4e-5 against the mesh's own
    k A_side / m. Tolerances 1 % and 1e-4. Without the bed the axial translation is free:
    refused in one line."""
    built = build_scenario(_rod_scenario((AXIAL_BED, ENDS_YZ), model), _setup())
    f, shapes = _modes(built.system.bodies[0], 6)
    axial = np.linalg.norm(shapes[0::3], axis=0) / np.linalg.norm(shapes, axis=0) > 0.99
    k, rho, r = AXIAL_BED["stiffness_n_per_m3"], ALUMINIUM.rho, ROD["radius_m"]
    assert f[axial][0] == pytest.approx(math.sqrt(2 * k / (rho * r)) / (2 * math.pi), rel=0.01)
    mesh = built.info[0].mesh
    area = spring_bed_stiffness(mesh, mesh.facet_set("side"), 1.0, BedDirection.X)[0::3, 0::3]
    mass = assemble(mesh, ALUMINIUM).mass
    assert f[axial][0] == pytest.approx(math.sqrt(k * area.sum() / mass) / (2 * math.pi), rel=1e-4)
    with pytest.raises(InputError, match="leave 1 of the 6 rigid-body motions free"):
        build_scenario(_rod_scenario((ENDS_YZ,), model), _setup())


def test_supports_dump_and_read_back(beam_file):
    """Every support type dumps to a dict that reads back to the same scenario; a clamp's
    dump has only the keys it had before directional supports existed."""
    fixed = {"type": "fixed", "body": "beam", "node_set": ["left", "right"], "fixed": ["y"]}
    sym = {"type": "symmetry", "body": "beam", "node_set": "left", "normal": "x"}
    clamp = {"type": "clamp", "body": "beam", "node_set": "right"}
    sc = _scenario(beam_file, (PIN, ROLL_Z, fixed, sym, BED, clamp))
    data = sc.model_dump(mode="json")
    assert scenario_from_dict(data) == sc
    assert set(data["supports"][-1]) == {"type", "body", "node_set", "ground_frame"}


def test_rod_sags_onto_its_axial_bed():
    """The bedded rod (above) started in its quasi-static sag under gravity along its axis
    (placement.sagged): a uniform shift u = m g / (k A_side) (the mesh's own mass and side
    area: 1.41 % above rho g r / (2 k) for the chordal side): measured mean +5.8e-5 from it,
    the nodes within 2.7e-4 of each other (the body force per volume and the bed per area
    strain the rod a little); tolerances 1e-3. The strain energy 1/2 q^T k_hat q holds the
    bed's, 1/2 k A_side u^2: measured +7.8e-5 (the rod's own strain), tolerance 1e-3."""
    data = _rod_scenario((AXIAL_BED, ENDS_YZ)).model_dump(mode="json")
    data["gravity_mps2"] = [-9.81, 0.0, 0.0]
    data["bodies"][0]["placement"] = {"sagged": True}
    built = build_scenario(scenario_from_dict(data), _setup())
    body, state, mesh = built.system.bodies[0], built.states[0], built.info[0].mesh
    u = body.local_displacements(np.arange(mesh.n_nodes), state.q)[:, 0]
    k = AXIAL_BED["stiffness_n_per_m3"]
    area = spring_bed_stiffness(mesh, mesh.facet_set("side"), 1.0, BedDirection.X)[0::3, 0::3]
    shift = -assemble(mesh, ALUMINIUM).mass * 9.81 / (k * area.sum())
    assert u.mean() == pytest.approx(shift, rel=1e-3)
    assert np.ptp(u) < 1e-3 * abs(shift)
    energy = 0.5 * state.q @ (body.k_hat @ state.q)
    assert energy == pytest.approx(0.5 * k * area.sum() * shift**2, rel=1e-3)


def test_a_bed_alone_can_hold_a_body(beam_file):
    """A beam whose whole skin rests on a normal spring bed needs no held DOF: a full-FE body
    of all 3 n DOFs (no reference DOF removed), its frame fixed by one ground joint. Its
    lowest mode is the axial translation on the end faces' springs, omega^2 = 2 k b h /
    (rho b h L) = 2 k / (rho L) (137.0 Hz); the rod's own axial compliance (k L / E = 1.4 %
    of the springs') lowers it: measured -0.11 %, tolerance 0.5 %."""
    built = build_scenario(_scenario(beam_file, (BED,)), _setup())
    body, mesh = built.system.bodies[0], built.info[0].mesh
    assert body.nq == mesh.n_dof
    assert sum(j.n_rows for j in built.system.joints) == 6
    f0 = math.sqrt(2 * BED["stiffness_n_per_m3"] / (ALUMINIUM.rho * L)) / (2 * math.pi)
    assert _modes(body, 1)[0][0] == pytest.approx(f0, rel=0.005)
