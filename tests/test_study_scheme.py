"""The scheme a study runs (studies.grid.seed_scheme): the seed's models, whatever the
scenario's contact. A massless retained node adds static columns to a Craig-Bampton body
(reduction/basis.py), so a study on the undamped scheme of rod_impact.toml would not count
3 x nodes + modes coordinates, the count its grid and search rank by."""

from __future__ import annotations

from pathlib import Path

import pytest

from flexmvm.constraints.contact import ContactLaw
from flexmvm.errors import InputError
from flexmvm.scenarios import load_scenario
from flexmvm.studies.grid import check_grid, seed_scheme, study_scenario

SEED = Path(__file__).parents[1] / "scenarios" / "rod_impact.toml"
TINY = Path(__file__).parent / "data" / "tiny_impact.toml"


def test_seed_scheme_of_the_undamped_seed_case():
    """rod_impact.toml ships theta = 1/2 + dt_s / (4 tau) (0.51), the position law and mass
    redistribution; a study of b2 runs it on the velocity law without redistribution at
    theta = 0.55 (no damping time), the rest of the
    scenario as it is; study_scenario applies it, check_grid refuses the scenario as shipped
    with a one-line reason."""
    sc = load_scenario(SEED)
    assert sc.time.theta == 0.51 and sc.contacts[0].redistribute_mass
    study = seed_scheme(sc, "b2")
    c = study.contacts[0]
    assert c.law is ContactLaw.VELOCITY and not c.redistribute_mass
    assert study.time.theta == 0.55 and study.time.hf_damping_time_s is None
    a, b = sc.model_dump(mode="json"), study.model_dump(mode="json")
    for d in (a, b):
        d["time"].pop("theta", None), d["time"].pop("hf_damping_time_s", None)
        for key in ("law", "redistribute_mass"):
            d["contacts"][0].pop(key, None)
    assert a == b
    assert study_scenario(sc, "b2").model_dump() == study.model_dump()
    with pytest.raises(InputError, match="seed_scheme"):
        check_grid(sc, "b2", [1], [1], [7])
    check_grid(study, "b2", [1], [1], [7])


def test_seed_scheme_keeps_a_scenario_without_redistribution():
    sc = load_scenario(TINY)
    assert not any(c.redistribute_mass for c in sc.contacts)
    assert seed_scheme(sc, "b2") is sc
