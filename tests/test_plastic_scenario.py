"""The ``plasticity`` table of an inline material: read and validated (one ScenarioError line
per bad value, naming the key), absent from the dumps of elastic materials (cache and study
keys unchanged), refused in one line by a dynamic run for a reduced body, and built as a
PlasticPart of the System for a full-FE one. Runs in about 3 s."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from flexmvm.assembly.build import build_scenario
from flexmvm.errors import InputError
from flexmvm.plasticity import J2Plasticity
from flexmvm.scenarios import ScenarioError, scenario_from_dict
from flexmvm.scenarios.plasticity_schema import plasticity_of

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
AL = 'material = "aluminium"'


def _with_b2(material: str) -> dict:
    text = (SCENARIOS / "rod_impact.toml").read_text()
    assert text.count(AL) == 1
    return tomllib.loads(text.replace(AL, f"material = {material}"))


def test_plasticity_is_read_and_defaults_to_no_hardening():
    sc = scenario_from_dict(
        _with_b2(
            "{ E_pa = 72.71e9, nu = 0.33, rho_kg_m3 = 2700.0, plasticity = "
            "{ yield_pa = 2.76e8, hardening_pa = 5e8, kinematic_hardening_pa = 1e8 } }"
        )
    )
    assert plasticity_of(sc.body("b2")) == J2Plasticity(2.76e8, 5e8, 1e8)
    assert plasticity_of(sc.body("b1")) is None
    sc = scenario_from_dict(
        _with_b2(
            "{ E_pa = 72.71e9, nu = 0.33, rho_kg_m3 = 2700.0, plasticity = { yield_pa = 2.76e8 } }"
        )
    )
    assert plasticity_of(sc.body("b2")) == J2Plasticity(2.76e8, 0.0, 0.0)


def test_elastic_material_dumps_as_before():
    sc = scenario_from_dict(_with_b2("{ E_pa = 72.71e9, nu = 0.33, rho_kg_m3 = 2700.0 }"))
    dumped = sc.model_dump()
    b2 = next(b for b in dumped["bodies"] if b["name"] == "b2")
    assert set(b2["material"]) == {"E_pa", "nu", "rho_kg_m3", "name"}


@pytest.mark.parametrize(
    "table, where, says",
    [
        ("{ yield_pa = -1.0 }", "plasticity.yield_pa", "must be > 0"),
        ("{ yield_pa = 0.0 }", "plasticity.yield_pa", "must be > 0"),
        ("{ yield_pa = 1e8, hardening_pa = -5.0 }", "plasticity.hardening_pa", "must be >= 0"),
        (
            "{ yield_pa = 1e8, kinematic_hardening_pa = -1.0 }",
            "plasticity.kinematic_hardening_pa",
            "must be >= 0",
        ),
        ("{ hardening_pa = 1e8 }", "plasticity.yield_pa", "missing required key"),
        ("{ yield_pa = 1e8, yield_stress = 2.0 }", "plasticity.yield_stress", "unknown key"),
        ('{ yield_pa = "high" }', "plasticity.yield_pa", "valid number"),
    ],
)
def test_bad_plasticity_is_one_line_naming_the_key(table, where, says):
    data = _with_b2(f"{{ E_pa = 72.71e9, nu = 0.33, rho_kg_m3 = 2700.0, plasticity = {table} }}")
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(data, source="s.toml")
    msg = str(info.value)
    assert "\n" not in msg
    assert f"bodies[1].material.{where}" in msg and says in msg, msg


def test_dynamic_run_refuses_plastic_modal_body_in_one_line():
    data = _with_b2(
        "{ E_pa = 72.71e9, nu = 0.33, rho_kg_m3 = 2700.0, plasticity = { yield_pa = 2.76e8 } }"
    )
    b2 = next(b for b in data["bodies"] if b["name"] == "b2")
    b2["model"] = {"kind": "modal", "modes": 4}
    with pytest.raises(InputError) as info:
        build_scenario(scenario_from_dict(data))
    msg = str(info.value)
    assert "\n" not in msg
    assert "'b2'" in msg and 'model.kind = "full" and the MVM kinds only' in msg, msg


def test_full_fe_plastic_body_is_built_as_a_plastic_part():
    """The sphere-on-block scenario's block (full FE) plastic: the System carries its
    PlasticPart on the body's own mesh; with mass redistribution at its contact it is refused
    (the plastic force has no part in the massless nodes' equilibrium)."""
    path = SCENARIOS / "sphere_block.toml"
    data = tomllib.loads(path.read_text())
    block = next(b for b in data["bodies"] if b["name"] == "block")
    block["material"] = {
        "name": "al",
        "E_pa": 72.71e9,
        "nu": 0.33,
        "rho_kg_m3": 2700.0,
        "plasticity": {"yield_pa": 2.76e8},
    }
    built = build_scenario(scenario_from_dict(data, source=str(path), base_dir=SCENARIOS))
    (part,) = built.system.plastic
    assert part.body == 1 and part.model.plastic == J2Plasticity(2.76e8)
    assert part.model.n_dof == built.system.bodies[1].psi.shape[0]
    data["contacts"][0]["redistribute_mass"] = True
    with pytest.raises(InputError, match=r"contacts\[0\]: redistribute_mass cannot be used"):
        build_scenario(scenario_from_dict(data, source=str(path), base_dir=SCENARIOS))


def test_plastic_model_keys_are_read_and_left_out_of_dumps_at_defaults():
    """``model.plastic_tangent`` and ``model.plastic_outside`` reach the body's PlasticPart;
    at their defaults a dump is as before the keys existed (cache and study keys hash it); a
    bad value is one line naming the key."""
    data = _with_b2(
        "{ E_pa = 72.71e9, nu = 0.33, rho_kg_m3 = 2700.0, plasticity = { yield_pa = 2.76e8 } }"
    )
    b2 = next(b for b in data["bodies"] if b["name"] == "b2")
    plain = scenario_from_dict(data).model_dump(mode="json")["bodies"][1]["model"]
    assert not {"plastic_tangent", "plastic_outside"} & set(plain)
    b2["model"] |= {"plastic_tangent": True, "plastic_outside": "stop"}
    model = scenario_from_dict(data).body("b2").model
    assert model.plastic_tangent is True and model.plastic_outside == "stop"
    b2["model"]["plastic_outside"] = "halt"
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(data, source="s.toml")
    msg = str(info.value)
    assert "\n" not in msg and "bodies[1].model.plastic_outside" in msg, msg
