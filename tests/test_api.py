"""The library surface (docs/api.md): lazy top-level names, typed scenario copies, runs with
named accessors, comparisons and the per-process caches."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import flexmvm as fm
from flexmvm.materials import COPPER

ROOT = Path(__file__).resolve().parents[1]
SHORT = ROOT / "scenarios" / "rod_impact_short.toml"
TINY = ROOT / "tests" / "data" / "tiny_impact.toml"


def test_import_is_lazy_and_every_name_resolves():
    code = (
        "import sys, flexmvm; print(json.dumps(sorted(m for m in sys.modules "
        "if m.startswith('flexmvm'))))"
    )
    out = subprocess.run(
        [sys.executable, "-c", "import json; " + code], capture_output=True, text=True, check=True
    ).stdout
    assert json.loads(out) == ["flexmvm"]
    for name in fm.__all__:
        assert getattr(fm, name) is not None, name
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        fm.nope  # noqa: B018


def test_typed_copies_equal_the_edited_file():
    """with_model / with_time / with_material give the scenario the edited TOML dict gives."""
    sc = fm.load_scenario(SHORT)
    data = sc.model_dump(mode="json")
    data["bodies"][1]["model"] = {
        "kind": "mvm",
        "selection": "2-3",
        "modes": 13,
        "region": None,
        "reference": "end_b",
    }
    data["bodies"][1]["material"] = {
        "E_pa": COPPER.E,
        "nu": COPPER.nu,
        "rho_kg_m3": COPPER.rho,
        "name": COPPER.name,
    }
    data["time"] |= {"t_end_s": 1e-4, "dt_s": 1e-6, "dt_max_s": 2e-6}
    edited = fm.scenario_from_dict(data)
    typed = (
        sc.with_model("b2", fm.mvm((2, 3), 13))
        .with_material("b2", COPPER)
        .with_time(t_end_s=1e-4, dt_s=1e-6)
    )
    assert typed.model_dump() == edited.model_dump()  # (== would also compare the sources)
    assert typed.source == str(SHORT)  # a copy keeps naming its file in later errors


def test_with_kind_keeps_selections_and_rigid_bodies():
    sc = fm.load_scenario(SHORT).with_model("b1", fm.rigid())
    over = sc.with_kind(fm.ModelKind.MODAL)
    assert over.body("b1").model.kind is fm.ModelKind.RIGID
    b2 = over.body("b2").model
    assert (b2.kind, b2.selection, b2.modes) == (fm.ModelKind.MODAL, "1-3", 37)
    assert [b.model.kind for b in sc.with_models(fm.full()).bodies] == [
        fm.ModelKind.RIGID,
        fm.ModelKind.FULL,
    ]


@pytest.mark.parametrize(
    ("change", "words"),
    [
        (lambda sc: sc.with_model("b3", fm.full()), "no body 'b3' (bodies: b1, b2)"),
        (lambda sc: sc.with_model("b2", "mvm"), "received str, expected a ModelConfig"),
        (lambda sc: sc.with_time(output_dt_s=1e-7), "time.output_dt_s: must be >= dt_s"),
        (lambda sc: sc.with_time(dt_s=1e-3), "time.hf_damping_time_s: must be >= dt_s / 2"),
        (lambda sc: sc.with_kind("fem"), "model kind 'fem'; expected one of full, mvm"),
        (lambda sc: sc.with_material("b2", "unobtainium"), "unknown material preset"),
        (lambda sc: sc.with_rod("b2", radius_m=-1.0), "bodies[1].rod.radius_m: must be > 0"),
        (lambda sc: fm.mvm("1-3", 0), "modes: must be >= 1 for kind 'mvm'"),
        (lambda sc: fm.mvm("0-3", 5), "must be 'i-j' (layers-laps, both >= 1)"),
    ],
)
def test_bad_changes_are_one_line_scenario_errors(change, words):
    with pytest.raises(fm.ScenarioError) as info:
        change(fm.load_scenario(SHORT))
    assert words in str(info.value) and "\n" not in str(info.value)


@pytest.fixture(scope="module")
def tiny_run():
    """tests/data/tiny_impact.toml with an output after every step."""
    sc = fm.load_scenario(TINY)
    return sc, fm.run(sc.with_time(output_dt_s=sc.time.dt_s))


def test_run_keeps_the_integrated_rates(tiny_run):
    """q_dot is the scheme's own: q(t + h) = q(t) + h (theta q_dot(t + h) + (1 - theta)
    q_dot(t)) holds for every step to round-off (1e-12 of the largest increment), which
    finite differences of q could not give."""
    sc, run = tiny_run
    h, th = sc.time.dt_s, sc.time.theta
    for body in ("b1", "b2"):
        q, qd = run.elastic(body)
        dq = np.diff(q, axis=0)
        scheme = h * (th * qd[1:] + (1 - th) * qd[:-1])
        assert np.abs(dq - scheme).max() <= 1e-12 * np.abs(dq).max()


def test_run_accessors_and_step_history(tiny_run):
    sc, run = tiny_run
    pv = run.probe("b2_free_end")
    assert pv.v.shape == pv.x.shape == (len(run.t), 3)
    np.testing.assert_array_equal(run.curves()[2]["b2_free_end"], pv.v[:, 0])
    steps = run.steps
    assert len(steps.t_s) == run.result.n_steps == round(sc.time.t_end_s / sc.time.dt_s)
    assert steps.size_counts() == {sc.time.dt_s: run.result.n_steps}
    # one output per step: the output force is that step's impulse over its size
    np.testing.assert_allclose(
        run.contact_force[1:], steps.contact_impulse_Ns / steps.h_s, rtol=1e-14
    )
    assert run.dof("b2") == run.summary["dof"]["b2"]
    with pytest.raises(fm.InputError, match="no probe 'nope'"):
        run.probe("nope")
    with pytest.raises(fm.InputError, match="no body 'b9'"):
        run.elastic("b9")


def test_compare_takes_runs_results_and_tuples(tiny_run):
    _, run = tiny_run
    same = fm.compare(run, run.result)
    assert same.ncc_force == pytest.approx(1.0, abs=1e-12) and same.peak_err == 0.0
    assert set(same.ncc_probes) == {"b2_impact_end", "b2_free_end"}
    t, f, probes = run.curves()
    half = fm.compare((t, 0.5 * f, probes), run)
    assert half.ncc_force == pytest.approx(1.0, abs=1e-12)  # NCC is blind to scale ...
    assert half.peak_err == pytest.approx(-0.5)  # ... the peak error is not
    assert half.as_dict()["peak_err"] == half.peak_err
    with pytest.raises(fm.InputError, match="received int"):
        fm.compare(run, 3)


def test_caches_can_be_cleared_and_bounded():
    """fm.set_cache_sizes bounds the caches of the process-wide setup cache that fm.run builds
    through, fm.clear_caches empties them; a bad name or bound is one InputError line."""
    from flexmvm.assembly.build_cache import default_setup

    caches = default_setup().caches
    try:
        fm.set_cache_sizes(fe_models=1, bases=2)
        assert fm.cache_sizes() == {"meshes": 8, "fe_models": 1, "bases": 2, "body_parts": 16}
        assert caches.fe_model.cache_info().maxsize == 1
        assert caches.basis.cache_info().maxsize == 2
        fm.run(fm.load_scenario(TINY).with_time(t_end_s=1e-6))
        # at most the bound (a warm reduced body loads no FE model: setup cache on disk)
        assert caches.fe_model.cache_info().currsize <= 1
        assert caches.basis.cache_info().currsize == 2  # b1 full, b2 mvm: the bound
        fm.clear_caches()
        assert caches.fe_model.cache_info().currsize == 0 == caches.basis.cache_info().currsize
        with pytest.raises(fm.InputError, match="unknown"):
            fm.set_cache_sizes(models=3)
        with pytest.raises(fm.InputError, match="integers >= 0"):
            fm.set_cache_sizes(bases=-1)
    finally:
        fm.set_cache_sizes(meshes=8, fe_models=8, bases=64, body_parts=16)


def test_mechanism_constructors_equal_the_file_tables():
    """fm.joint, fm.drive, fm.spin_up, fm.clamp, fm.applied_load, fm.spring, fm.damping,
    fm.rigid_motion and fm.prescribed_path give the tables the same keys give in a scenario
    dict (validated by the same models: equal dumps, exactly), and a scenario built from them
    dumps as the all-dict one. No mesh, no run: well under a second."""
    rod = {"length_m": 0.3, "radius_m": 0.01}
    as_dicts = {
        "name": "m",
        "time": {"t_end_s": 0.1, "dt_s": 1e-3, "output_dt_s": 1e-3},
        "bodies": [
            {
                "name": "link",
                "material": "aluminium",
                "rod": rod,
                "model": {"kind": "modal", "modes": 4},
                "damping": {"rayleigh_ratios": [[10.0, 0.02], [200.0, 0.03]]},
                "placement": {"rigid_motion": {"angular_velocity_radps": [0, 0, 0]}},
            }
        ],
        "supports": [{"type": "clamp", "body": "link", "node_set": "end_a", "ground_frame": False}],
        "joints": [
            {
                "type": "revolute",
                "name": "motor",
                "body": "link",
                "point_m": [0, 0, 0],
                "ground_m": [0, 0, 0],
                "axis": [0, 0, 1],
                "drive": {"angular_velocity_radps": {"spin_up": {"final": 5.0, "duration_s": 0.05}}},
            }
        ],
        "loads": [{"type": "motor", "joint": 0, "times_s": [0.0, 0.1], "torque_nm": [0.0, 1.0]}],
        "springs": [
            {"body": "link", "node_set": "end_b_centre", "ground_m": [0.3, -0.1, 0.0],
             "stiffness_n_per_m": 50.0, "damping_n_s_per_m": 0.5},
            {"type": "rotational", "joint": 0, "stiffness_nm_per_rad": 2.0},
        ],
    }  # fmt: skip
    made = {
        **as_dicts,
        "bodies": [
            {
                **as_dicts["bodies"][0],
                "model": fm.modal(4),
                "damping": fm.damping(rayleigh_ratios=[(10.0, 0.02), (200.0, 0.03)]),
                "placement": {"rigid_motion": fm.rigid_motion((0, 0, 0))},
            }
        ],
        "supports": [fm.clamp("link", "end_a", ground_frame=False)],
        "joints": [
            fm.joint(
                "revolute",
                "link",
                name="motor",
                point_m=(0, 0, 0),
                ground_m=(0, 0, 0),
                axis=(0, 0, 1),
                drive=fm.drive(angular_velocity_radps=fm.spin_up(5.0, 0.05)),
            )
        ],
        "loads": [fm.applied_load("motor", joint=0, times_s=[0.0, 0.1], torque_nm=[0.0, 1.0])],
        "springs": [
            fm.spring(
                body="link",
                node_set="end_b_centre",
                ground_m=(0.3, -0.1, 0.0),
                stiffness_n_per_m=50.0,
                damping_n_s_per_m=0.5,
            ),
            fm.spring("rotational", joint=0, stiffness_nm_per_rad=2.0),
        ],
    }
    assert fm.scenario_from_dict(made).model_dump() == fm.scenario_from_dict(as_dicts).model_dump()
    bare = fm.scenario_from_dict({**made, "loads": [], "springs": []})
    again = bare.with_tables(loads=made["loads"], springs=made["springs"])
    assert again.model_dump() == fm.scenario_from_dict(as_dicts).model_dump()
    rows = [[0.0, 0.0], [0.1, 0.5]]
    assert (
        fm.drive(angle_rad=rows)
        == fm.scenario_from_dict(
            {
                **as_dicts,
                "joints": [{**as_dicts["joints"][0], "drive": {"angle_rad": {"table": rows}}}],
            }
        )
        .joints[0]
        .drive
    )
    assert fm.drive(angular_velocity_radps=2.0).angle().value(0.5) == pytest.approx(1.0)
    path = fm.prescribed_path(velocity_mps=[[0, 1, 0, 0], [1, 1, 0, 0]])
    np.testing.assert_allclose(path.displacement().value(0.5), [0.5, 0.0, 0.0], rtol=1e-15)


@pytest.mark.parametrize(
    ("make", "words"),
    [
        (lambda: fm.spin_up(1.0, -1.0), "spin_up(1.0, -1.0): spin_up.duration_s: must be > 0"),
        (lambda: fm.drive(angle_rad=1.0), "drive(...): angle_rad: must be 0 rad at t = 0"),
        (lambda: fm.joint("revolute", "a", point_m=(0, 0, 0), ground_m=(0, 0, 0)), "axis: req"),
        (lambda: fm.joint("hinge", "a"), "joint('hinge', 'a'): type: input should be 'ground'"),
        (lambda: fm.applied_load("force", body="a", torque_nm=1.0), "point_m: required by a"),
        (lambda: fm.spring("rotational", joint=0), "stiffness_nm_per_rad: required by a"),
        (lambda: fm.damping(alpha_per_s=1.0, modal_ratios=[0.1]), "needs exactly one of"),
        (lambda: fm.rigid_motion((0, 0, 1), about_joint="a", about_m=(0, 0, 0)), "give one of"),
        (lambda: fm.prescribed_path(), "give exactly one of displacement_m, velocity_mps"),
        (lambda: fm.load_scenario(SHORT).with_tables(spring=[]), "(with spring): spring: unknown"),
        (
            lambda: fm.load_scenario(SHORT).with_tables(
                loads=[fm.applied_load("motor", joint=0, torque_nm=1.0)]
            ),
            "(with loads): loads[0].joint: no joints[0] (0 joint(s))",
        ),
    ],
)
def test_mechanism_constructors_refuse_in_one_line(make, words):
    """Each bad table, and a bad table given to Scenario.with_tables, is one ScenarioError
    line naming the call (or the copy) and the key."""
    with pytest.raises(fm.ScenarioError) as info:
        make()
    assert words in str(info.value) and "\n" not in str(info.value)
