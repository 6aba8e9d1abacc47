"""Scenario schema: the shipped scenarios load with the seed's numbers, and every kind of bad
input gives one ScenarioError line naming the file and the key."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from flexmvm.errors import InputError
from flexmvm.materials import PRESETS
from flexmvm.scenarios import (
    ContactKind,
    EndShape,
    ModelConfig,
    ModelKind,
    Rotation,
    ScenarioError,
    load_scenario,
    scenario_from_dict,
)

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
ROD_IMPACT = (SCENARIOS / "rod_impact.toml").read_text()
B2_ROD = '[bodies.rod]\nlength_m = 1.0\nradius_m = 0.01\nend_a = "flat"\nend_b = "flat"\n'


def _joint(keys: str) -> tuple[str, str]:
    """Edit adding one [[joints]] table with the given key lines before the contacts."""
    return ("[[contacts]]", f"[[joints]]\n{keys}\n\n[[contacts]]")


def _variant(tmp_path: Path, *edits: tuple[str, str], name: str = "rod_impact.toml") -> Path:
    """rod_impact.toml with text edits (each must apply exactly once), written to tmp_path."""
    text = ROD_IMPACT
    for old, new in edits:
        assert text.count(old) == 1, f"edit does not apply once: {old!r}"
        text = text.replace(old, new)
    path = tmp_path / name
    path.write_text(text)
    return path


def _error(path: Path) -> str:
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    msg = str(info.value)
    assert "\n" not in msg
    assert isinstance(info.value, InputError)
    return msg


@pytest.mark.parametrize("name", ["rod_impact", "rod_impact_flat", "pendulum_release"])
def test_shipped_scenarios_load(name: str) -> None:
    s = load_scenario(SCENARIOS / f"{name}.toml")
    assert s.name == name
    b1, b2 = s.body("b1"), s.body("b2")
    assert b1.material_obj() == PRESETS["brass"]
    assert (b1.material_obj().E, b1.material_obj().nu, b1.material_obj().rho) == (
        96.5e9,
        0.36,
        8390.0,
    )
    assert (b2.material_obj().E, b2.material_obj().rho) == (72.71e9, 2700.0)
    assert b1.model.kind is ModelKind.FULL
    assert b2.model.kind is ModelKind.MVM
    assert (b2.model.selection_ij, b2.model.modes) == ((1, 3), 37)
    assert b2.rod is not None and (b2.rod.end_a, b2.rod.end_b) == (EndShape.FLAT, EndShape.FLAT)
    assert [
        (c.slave_body, c.slave_surface, c.master_body, c.master_surface, c.kind) for c in s.contacts
    ] == [("b2", "end_a", "b1", "end_a", ContactKind.FRICTIONLESS)]
    probes = {p.name: (p.body, p.node_set) for p in s.probes}
    assert probes["b2_impact_end"] == ("b2", "end_a_centre")
    assert probes["b2_free_end"] == ("b2", "end_b_centre")
    assert s.time.dt_s <= s.time.dt_max_s and s.time.output_dt_s >= s.time.dt_s


def test_rod_impact_seed_case() -> None:
    """b1 covers x in [-1, 0] with its apex at the origin, moving +x at 0.21 m/s; b2 covers
    [0, 1] at rest: they touch at t = 0."""
    s = load_scenario(SCENARIOS / "rod_impact.toml")
    b1, b2 = s.body("b1"), s.body("b2")
    assert b1.rod is not None and b1.rod.end_a is EndShape.HEMISPHERE
    assert (b1.rod.length_m, b1.rod.radius_m) == (1.0, 0.01)
    np.testing.assert_allclose(b1.placement.to_global((0.0, 0.0, 0.0)), [0, 0, 0], atol=1e-15)
    np.testing.assert_allclose(b1.placement.to_global((1.0, 0.0, 0.0)), [-1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(b2.placement.to_global((1.0, 0.0, 0.0)), [1, 0, 0], atol=1e-15)
    assert b1.placement.velocity_mps == (0.21, 0.0, 0.0)
    assert b2.placement.velocity_mps == (0.0, 0.0, 0.0)
    assert (s.time.t_end_s, s.time.dt_s, s.time.dt_max_s, s.time.output_dt_s) == (
        2e-3,
        0.5e-6,
        2e-6,
        2e-6,
    )
    assert s.gravity_mps2 == (0.0, 0.0, 0.0)


def test_flat_variant_differs_only_in_the_striker_end() -> None:
    hemi = load_scenario(SCENARIOS / "rod_impact.toml").model_dump()
    flat = load_scenario(SCENARIOS / "rod_impact_flat.toml").model_dump()
    assert flat["bodies"][0]["rod"]["end_a"] is EndShape.FLAT
    for d in (hemi, flat):
        d.pop("name"), d.pop("description")
        d["bodies"][0]["rod"].pop("end_a")
    assert hemi == flat


def test_pendulum_reaches_the_impact_speed_at_the_origin() -> None:
    """Parallelogram pendulum of string length l = 0.5 m: b1 translates on a circle of radius l
    about the ground points; at the bottom (position 0) its apex is at the origin and the strings
    are vertical; from rest at height h, v = sqrt(2 g h) = 0.21 m/s at the bottom."""
    s = load_scenario(SCENARIOS / "pendulum_release.toml")
    g = -s.gravity_mps2[2]
    assert s.gravity_mps2 == (0.0, 0.0, -9.81)
    b1 = s.body("b1")
    start = np.asarray(b1.placement.position_m)
    bottom = b1.placement.model_copy(update={"position_m": (0.0, 0.0, 0.0)})
    np.testing.assert_allclose(bottom.to_global((0.0, 0.0, 0.0)), 0.0, atol=1e-15)
    assert math.sqrt(2 * g * start[2]) == pytest.approx(0.21, rel=1e-9)
    assert b1.placement.velocity_mps == (0.0, 0.0, 0.0)
    strings = [j for j in s.joints if j.body == "b1"]
    assert len(strings) == 2 and all(j.type.value == "distance" for j in strings)
    for j in strings:
        ground = np.asarray(j.ground_m)
        at_bottom = bottom.to_global(j.point_m)
        assert j.point_m[2] == 0.01
        np.testing.assert_allclose(ground - at_bottom, [0.0, 0.0, 0.5], atol=1e-15)
        assert np.linalg.norm(ground - b1.placement.to_global(j.point_m)) == pytest.approx(
            0.5, rel=1e-12
        )
    assert start[0] < 0  # displaced back, swings towards +x onto b2
    quarter_period = math.pi / 2 * math.sqrt(0.5 / g)
    assert quarter_period < s.time.t_end_s < quarter_period + 0.01
    for j in (j for j in s.joints if j.body == "b2"):  # b2 hangs at rest on vertical strings
        ground = np.asarray(j.ground_m)
        np.testing.assert_allclose(
            ground - s.body("b2").placement.to_global(j.point_m), [0.0, 0.0, 0.5], atol=1e-15
        )
    # the seed case's contact step and output step near contact; the swing's steps dt 2^k never
    # cut by an output (output_dt_s a whole number of the largest steps)
    seed = load_scenario(SCENARIOS / "rod_impact.toml").time
    assert (s.time.dt_s, s.time.output_contact_dt_s) == (seed.dt_s, seed.output_dt_s)
    k = math.log2(s.time.dt_max_s / s.time.dt_s)
    assert k == round(k) and k >= 8
    assert (s.time.output_dt_s / s.time.dt_max_s) == round(s.time.output_dt_s / s.time.dt_max_s)


BAD = [
    pytest.param(
        ('name = "b1"', 'name = "b1"\ncolour = "red"'),
        "bodies[0].colour: unknown key",
        id="unknown-key",
    ),
    pytest.param(
        ('master = "b1.end_a"', 'master = "b3.end_a"'),
        "contacts[0].master: unknown body 'b3' (bodies: b1, b2)",
        id="contact-body",
    ),
    pytest.param(
        ('material = "aluminium"', "material = {E_pa = -1.0, nu = 0.3, rho_kg_m3 = 2700.0}"),
        "bodies[1].material.E_pa: Young's modulus E must be > 0 Pa, got -1.0",
        id="negative-E",
    ),
    pytest.param(
        ('material = "aluminium"', "material = {E_pa = 7e10, nu = 0.5, rho_kg_m3 = 2700.0}"),
        "bodies[1].material.nu: Poisson ratio nu must be in (-1, 0.5), got 0.5",
        id="nu-half",
    ),
    pytest.param(
        ('material = "aluminium"', "material = {E_pa = 7e10, nu = 0.3, rho_kg_m3 = 0}"),
        "bodies[1].material.rho_kg_m3: density rho must be > 0",
        id="zero-rho",
    ),
    pytest.param(
        ('material = "aluminium"', 'material = "unobtainium"'),
        "bodies[1].material: unknown material preset 'unobtainium'",
        id="preset",
    ),
    pytest.param(
        ('selection = "1-3"', 'selection = "1x1"'),
        "bodies[1].model.selection: must be 'i-j' (layers-laps, both >= 1), got '1x1'",
        id="selection",
    ),
    pytest.param(
        ('selection = "1-3"', 'selection = "0-2"'),
        "bodies[1].model.selection: must be 'i-j'",
        id="selection-zero",
    ),
    pytest.param(
        ("modes = 37", "modes = 0"),
        "bodies[1].model.modes: must be >= 1 for kind 'mvm', got 0",
        id="modes",
    ),
    pytest.param(
        ('name = "b2"', 'name = "b1"'),
        "bodies[1].name: duplicate body 'b1' (also bodies[0])",
        id="duplicate-body",
    ),
    pytest.param(
        ('body = "b2"\nnode_set = "end_b_centre"', 'body = "b5"\nnode_set = "end_b_centre"'),
        "probes[1].body: unknown body 'b5' (bodies: b1, b2)",
        id="probe-body",
    ),
    pytest.param(
        ('node_set = "end_b_centre"', 'node_set = "middle"'),
        "probes[1].node_set: rods have no set 'middle'",
        id="probe-set",
    ),
    pytest.param(
        ("dt_max_s = 2.0e-6 ", "dt_max_s = 1.0e-7 "),
        "time.dt_max_s: must be >= dt_s = 5e-07, got 1e-07",
        id="dt-max",
    ),
    pytest.param(
        ("output_dt_s = 2.0e-6", "output_dt_s = 1.0e-7"),
        "time.output_dt_s: must be >= dt_s",
        id="output-dt",
    ),
    pytest.param(
        ("t_end_s = 2.0e-3", "t_end_s = -2.0e-3"),
        "time.t_end_s: must be > 0, got -0.002",
        id="t-end",
    ),
    pytest.param(
        ("t_end_s = 2.0e-3", "t_end_s = inf"),
        "time.t_end_s: input should be a finite number",
        id="t-end-inf",
    ),
    pytest.param(
        ("velocity_mps = [0.21, 0.0, 0.0]", "velocity_mps = [0.21, 0.0]"),
        "bodies[0].placement.velocity_mps: must be 3 finite numbers",
        id="vector-length",
    ),
    pytest.param(
        ("axis = [0.0, 0.0, 1.0]", "axis = [0.0, 0.0, 0.0]"),
        "bodies[0].placement.rotation.axis: must be non-zero",
        id="zero-axis",
    ),
    pytest.param(
        ('end_a = "hemisphere"', 'end_a = "round"'),
        "bodies[0].rod.end_a: input should be 'flat' or 'hemisphere', got 'round'",
        id="end-shape",
    ),
    pytest.param(
        ('kind = "mvm"', 'kind = "fem"'), "bodies[1].model.kind: input should be", id="model-kind"
    ),
    pytest.param(
        ('master = "b1.end_a"', 'master = "b2.end_b"'),
        "contacts[0].master: slave and master are both on body 'b2'",
        id="self-contact",
    ),
    pytest.param(
        ('master = "b1.end_a"', 'master = "b1.face"'),
        "contacts[0].master: rods have no set 'face'",
        id="contact-surface",
    ),
    pytest.param(
        ('[[probes]]\nname = "b2_free_end"', '[[probes]]\nname = "b2_impact_end"'),
        "probes[1].name: duplicate probe 'b2_impact_end'",
        id="duplicate-probe",
    ),
    pytest.param(
        _joint('type = "distance"\nbody = "b1"\npoint_m = [0.25, 0.0, 0.01]'),
        "joints[0].ground_m: required by a 'distance' joint to ground",
        id="joint-ground",
    ),
    pytest.param(
        _joint(
            'type = "revolute"\nbody = "b1"\npoint_m = [0.0, 0.0, 0.0]\nground_m = [0.0, 0.0, 0.0]'
        ),
        "joints[0].axis: required by a 'revolute' joint",
        id="joint-axis",
    ),
    pytest.param(
        _joint('type = "ground"\nbody = "b1"\npoint_m = [0.0, 0.0, 0.0]'),
        "joints[0].point_m: not used by a 'ground' joint",
        id="joint-extra",
    ),
    pytest.param(
        _joint(
            'type = "spherical"\nbody = "b1"\nbody2 = "b9"\n'
            "point_m = [0.0, 0.0, 0.0]\npoint2_m = [0.0, 0.0, 0.0]"
        ),
        "joints[0].body2: unknown body 'b9'",
        id="joint-body2",
    ),
    pytest.param(
        (B2_ROD, 'mesh_file = "rod.msh"\n' + B2_ROD),
        "bodies[1].mesh_file: no such mesh file",
        id="mesh-file-missing",
    ),
    pytest.param(
        (B2_ROD, ""),
        "bodies[1].rod: needs exactly one of [bodies.rod] or mesh_file",
        id="no-geometry",
    ),
]


@pytest.mark.parametrize(("edit", "expected"), BAD)
def test_bad_input_gives_one_line_naming_the_key(
    tmp_path: Path, edit: tuple[str, str], expected: str
) -> None:
    msg = _error(_variant(tmp_path, edit))
    assert msg.startswith(f"{tmp_path / 'rod_impact.toml'}: ")
    assert expected in msg


def test_toml_syntax_error_names_line_and_column(tmp_path: Path) -> None:
    msg = _error(_variant(tmp_path, ("[time]", "[time")))
    assert msg.startswith(f"{tmp_path / 'rod_impact.toml'}: invalid TOML: ")
    line = ROD_IMPACT.splitlines().index("[time]") + 1
    assert f"(at line {line}, column 6)" in msg


def test_missing_file(tmp_path: Path) -> None:
    msg = _error(tmp_path / "nowhere.toml")
    assert msg.startswith(f"{tmp_path / 'nowhere.toml'}: cannot read scenario file")


def test_mesh_file_resolved_relative_to_the_scenario(tmp_path: Path) -> None:
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "target.msh").write_text("not parsed here")
    path = _variant(
        tmp_path,
        (B2_ROD, 'mesh_file = "meshes/target.msh"\n'),
        (
            'selection = "1-3"',
            "region = { ball = { centre_m = [0.0, 0.0, 0.0], radius_m = 0.002 } }",
        ),
        ('slave = "b2.end_a"', 'slave = "b2.impact_face"'),  # mesh sets: the builder checks
    )
    s = load_scenario(path)
    b2 = s.body("b2")
    assert b2.mesh_file == (tmp_path / "meshes" / "target.msh").resolve()
    assert b2.rod is None and b2.model.region is not None and b2.model.region.ball is not None
    assert s.with_overrides(dt_s=0.5e-6).body("b2").mesh_file == b2.mesh_file
    bad = _variant(tmp_path, (B2_ROD, 'mesh_file = "meshes/target.msh"\n'), name="ij.toml")
    assert "bodies[1].model.selection: the i-j selection needs a [bodies.rod] body" in _error(bad)


def test_inline_material_is_named_after_the_body(tmp_path: Path) -> None:
    path = _variant(
        tmp_path,
        ('material = "aluminium"', "material = {E_pa = 2.32e9, nu = 0.34, rho_kg_m3 = 1140.0}"),
    )
    m = load_scenario(path).body("b2").material_obj()
    assert (m.E, m.nu, m.rho, m.name) == (2.32e9, 0.34, 1140.0, "b2")


def test_model_override_leaves_rigid_bodies_alone(tmp_path: Path) -> None:
    base = load_scenario(SCENARIOS / "rod_impact.toml")
    full = base.with_overrides(model="full")
    assert [b.model.kind for b in full.bodies] == [ModelKind.FULL, ModelKind.FULL]
    assert base.body("b2").model.kind is ModelKind.MVM  # the original is unchanged
    rigid_b1 = load_scenario(_variant(tmp_path, ('kind = "full"', 'kind = "rigid"')))
    over = rigid_b1.with_overrides(model=ModelKind.MODAL)
    assert over.body("b1").model.kind is ModelKind.RIGID
    assert over.body("b2").model.kind is ModelKind.MODAL and over.body("b2").model.modes == 37


def test_time_and_per_body_overrides() -> None:
    base = load_scenario(SCENARIOS / "rod_impact.toml")
    s = base.with_overrides(t_end_s=1e-3, dt_s=0.5e-6)
    assert (s.time.t_end_s, s.time.dt_s, s.time.dt_max_s) == (1e-3, 0.5e-6, 2e-6)
    assert base.with_overrides(dt_s=2e-6).time.dt_max_s == 2e-6  # lifted to the contact step
    s = base.with_overrides(body_models={"b2": ModelConfig(kind="mvm", selection="2-3", modes=13)})
    assert (s.body("b2").model.selection_ij, s.body("b2").model.modes) == ((2, 3), 13)
    assert s.body("b1").model.kind is ModelKind.FULL


@pytest.mark.parametrize(
    ("kwargs", "expected"),
    [
        ({"t_end_s": 0.0}, "time.t_end_s: must be > 0"),
        ({"dt_s": 1e-5}, "time.output_dt_s: must be >= dt_s = 1e-05"),
        ({"model": "fem"}, "model kind 'fem'; expected one of full, mvm"),
        ({"body_models": {"b7": ModelConfig()}}, "no body 'b7'"),
    ],
)
def test_bad_override_gives_one_line(kwargs: dict, expected: str) -> None:
    base = load_scenario(SCENARIOS / "rod_impact.toml")
    with pytest.raises(ScenarioError) as info:
        base.with_overrides(**kwargs)
    assert "\n" not in str(info.value)
    assert str(info.value).startswith(str(SCENARIOS / "rod_impact.toml"))
    assert expected in str(info.value)


def test_model_override_needs_a_selection() -> None:
    """A full-FE striker without a selection: overriding it to mvm-seed names the key."""
    data = load_scenario(SCENARIOS / "pendulum_release.toml").model_dump(mode="json")
    data["bodies"][0]["model"] = {"kind": "full"}
    base = scenario_from_dict(data, "pendulum_release.toml (b1 without selection)")
    with pytest.raises(ScenarioError) as info:
        base.with_overrides(model="mvm-seed")
    assert "\n" not in str(info.value)
    assert "bodies[0].model.selection: kind 'mvm-seed' needs selection" in str(info.value)


def test_rotation_matrix() -> None:
    np.testing.assert_allclose(
        Rotation(axis=(0, 0, 1), angle_deg=180).matrix(), np.diag([-1.0, -1.0, 1.0]), atol=1e-15
    )
    r = Rotation(axis=(2, 0, 0), angle_deg=90).matrix()
    np.testing.assert_allclose(r @ [0, 1, 0], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-15)


def test_docs_example_loads(tmp_path: Path) -> None:
    """The example in docs/scenario_format.md is a valid scenario."""
    doc = (SCENARIOS.parent / "docs" / "scenario_format.md").read_text()
    example = doc.split("## Example", 1)[1].split("```toml\n", 1)[1].split("```", 1)[0]
    path = tmp_path / "example.toml"
    path.write_text(example)
    s = load_scenario(path)
    assert s.body("b2").material_obj().E == 72.71e9
    assert s.body("b2").rod is not None and s.body("b2").rod.end_a is EndShape.FLAT
    assert s.time.dt_max_s == 1e-6


def test_scenario_from_dict_and_zero_length_string() -> None:
    data = tomllib.loads(ROD_IMPACT)
    assert scenario_from_dict(data, "dict").body("b2").model.modes == 37
    data["joints"] = [
        {
            "type": "distance",
            "body": "b2",
            "point_m": [0.25, 0.0, 0.01],
            "ground_m": [0.25, 0.0, 0.01],
        }
    ]
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(data, "dict")
    assert str(info.value).startswith("dict: joints[0]: the two points coincide at t = 0")
    data["joints"][0]["length_m"] = 0.5
    assert scenario_from_dict(data).joints[0].length_m == 0.5


def test_hf_damping_time_sets_theta_from_the_contact_step(tmp_path: Path) -> None:
    """time.hf_damping_time_s = tau gives theta = 1/2 + dt_s / (4 tau) (0.51 for the seed's
    12.5 us at 0.5 us), derived again when dt_s changes, by with_time or by editing a dump
    (which carries tau, not theta); a theta given replaces it; both in a file, or a tau under
    dt_s / 2 (theta above 1), are one-line errors naming the key."""
    sc = load_scenario(SCENARIOS / "rod_impact.toml")
    assert (sc.time.hf_damping_time_s, sc.time.dt_s, sc.time.theta) == (12.5e-6, 0.5e-6, 0.51)
    assert sc.with_time(dt_s=0.25e-6).time.theta == 0.505
    data = sc.model_dump(mode="json")
    assert "theta" not in data["time"]
    data["time"]["dt_s"] = 0.125e-6
    assert scenario_from_dict(data).time.theta == 0.5025
    damped = sc.with_time(theta=0.55).time
    assert damped.theta == 0.55 and damped.hf_damping_time_s is None
    # a scenario without tau dumps as before the key existed (cache identities hash dumps)
    assert "hf_damping_time_s" not in damped.model_dump()
    key = "hf_damping_time_s = 12.5e-6"
    msg = _error(_variant(tmp_path, (key, key + "\ntheta = 0.55")))
    assert "time.theta: give theta or hf_damping_time_s, not both" in msg
    msg = _error(_variant(tmp_path, (key, key + '\ntheta = "x"')))
    assert "time.theta: give theta or hf_damping_time_s, not both" in msg
    msg = _error(_variant(tmp_path, (key, "hf_damping_time_s = 0.2e-6")))
    assert "time.hf_damping_time_s: must be >= dt_s / 2" in msg
    msg = _error(_variant(tmp_path, (key, "hf_damping_time_s = -1.0")))
    assert "time.hf_damping_time_s: must be > 0" in msg
