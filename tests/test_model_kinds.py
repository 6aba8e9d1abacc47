"""One place per model kind (reduction/kinds/): each kind's properties come from its registered
spec, and a kind registered by ``fm.register_kind`` alone (no other file edited) is read from a
scenario, built through the setup cache and run."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

import flexmvm as fm
from flexmvm.assembly.build import build_scenario
from flexmvm.assembly.build_cache import SetupCache
from flexmvm.bodies.build import body_from_fe
from flexmvm.errors import InputError
from flexmvm.fe.modes import constrained_modes
from flexmvm.reduction.kinds import KINDS, Basis, BasisRequest, kind_spec, unregister_kind

TINY = Path(__file__).parent / "data" / "tiny_impact.toml"


@dataclass(frozen=True)
class SkipFirstMode(fm.KindSpec):
    """A toy modal kind with another mode choice: modes 2..N+1 of the reference-supported
    body (the first left out)."""

    name: str = "modal-skip-first"
    uses_modes: bool = True
    reads_modes: bool = True

    def build_basis(self, request: BasisRequest) -> Basis:
        fe, ref, n = request.fe, request.reference, request.n_modes
        freqs, phi = constrained_modes(fe.M, fe.K, ref.fixed_dofs, n + 1)
        kind = fm.ModelKind(self.name)
        return Basis(kind, phi[:, 1:], np.zeros(0, dtype=np.int64), n, ref, freqs[1:])


@pytest.fixture
def toy_kind():
    kind = fm.register_kind(SkipFirstMode())
    yield kind
    if SkipFirstMode.name in {k.value for k in KINDS}:
        unregister_kind(SkipFirstMode.name)


def test_built_in_kinds_answer_as_the_enum_did():
    """The properties the former ModelKind/BasisKind comparisons encoded, now each kind's."""
    table = {  # has_basis, retains_nodes, uses_modes, reads_modes, nodal, uses_patches, clampable
        "full": (True, False, False, False, True, False, True),
        "mvm": (True, True, True, True, False, False, True),
        "mvm-seed": (True, True, True, True, False, False, True),
        "mvm-seed-fixed": (True, True, True, True, False, False, True),
        "modal": (True, False, True, True, False, False, True),
        "interface": (True, False, False, True, False, True, False),
        "rigid": (False, False, False, False, False, False, False),
        "mvm-sparse": (True, True, True, True, False, False, True),
        "mvm-moving": (True, True, True, True, False, False, True),
    }
    got = {
        k.value: (s.has_basis, s.retains_nodes, s.uses_modes, s.reads_modes, s.nodal)
        + (s.uses_patches, s.clampable)
        for k, s in KINDS.items()
    }
    assert got == table
    assert [k.value for k in fm.ModelKind] == list(table)
    assert fm.ModelKind.CRAIG_BAMPTON is fm.ModelKind.MVM
    assert all(isinstance(s, fm.KindSpec) for s in KINDS.values())


def test_a_registered_kind_runs_the_tiny_case(toy_kind):
    """The toy kind, registered and nothing else, is a scenario's model.kind (the file's
    tables as a dict): b2 gets its 6 columns, their stiffnesses k_hat = omega^2 those of
    modal 7 but the first (rel 1e-6: two eigen solves of different size agree to ~1e-10),
    and the tiny case runs to its end with a contact force."""
    data = fm.load_scenario(TINY).model_dump(mode="json")
    data["bodies"][1]["model"] = {"kind": "modal-skip-first", "modes": 6, "reference": "end_b"}
    sc = fm.scenario_from_dict(data).with_time(t_end_s=6e-6)
    assert sc.body("b2").model.kind is toy_kind
    assert sc.body("b2").model.label == "modal-skip-first 6"
    built = build_scenario(sc, SetupCache())
    assert built.info[1].model is toy_kind and built.info[1].n_modes == 6
    toy = np.diag(np.asarray(built.system.bodies[1].k_hat))
    modal = build_scenario(sc.with_model("b2", fm.modal(7)), SetupCache())
    np.testing.assert_allclose(toy, np.diag(modal.system.bodies[1].k_hat)[1:], rtol=1e-6)
    res = fm.run(sc)
    assert res.result.t[-1] == pytest.approx(6e-6, rel=1e-9)
    assert np.max(np.abs(res.result.contact_force)) > 0.0


def test_a_kind_may_build_its_body_itself():
    """A spec's body_builder replaces the default body of the cached parts."""
    calls = []

    def builder(name, fe, basis, damping=None, parts_cache=None):
        calls.append((name, basis.kind.value, basis.nq))
        return body_from_fe(name, fe, basis, damping=damping)

    @dataclass(frozen=True)
    class OwnBody(SkipFirstMode):
        name: str = "modal-own-body"

    kind = fm.register_kind(OwnBody(body_builder=builder))
    try:
        sc = fm.load_scenario(TINY)
        sc = sc.with_model("b2", fm.modal(5)).with_kind(kind)
        build_scenario(sc, SetupCache())
    finally:
        unregister_kind("modal-own-body")
    assert calls == [("b1", "modal-own-body", 10), ("b2", "modal-own-body", 5)]


def test_registering_refuses_a_taken_name_and_unknown_kinds_stay_unknown(toy_kind):
    with pytest.raises(InputError, match="registered already"):
        fm.register_kind(SkipFirstMode())
    unregister_kind(SkipFirstMode.name)
    with pytest.raises(InputError, match="expected one of full, mvm"):
        kind_spec("modal-skip-first")
    with pytest.raises(fm.ScenarioError, match="modal-skip-first"):
        fm.load_scenario(TINY).with_kind("modal-skip-first")


def test_a_kind_reusing_another_builder_names_its_own_bases():
    """build_basis gives a registered variant's basis the variant's kind even when the
    builder it reuses (modal's) names its own, so its cache entries and body label are the
    variant's."""

    @dataclass(frozen=True)
    class Variant(type(kind_spec("modal"))):
        name: str = "modal-variant"

    kind = fm.register_kind(Variant())
    try:
        sc = fm.load_scenario(TINY).with_model("b2", fm.modal(4)).with_kind(kind)
        built = build_scenario(sc, SetupCache())
    finally:
        unregister_kind("modal-variant")
    assert [b.label for b in built.system.bodies] == ["modal-variant", "modal-variant"]


def test_a_registered_kind_is_a_choice_of_the_commands(toy_kind):
    """`flexmvm run --model` reads the registry (cli/kind_choice.py): a kind registered by
    register_kind alone is a choice, no CLI list edited; `select` takes the selectable ones."""
    from flexmvm.cli.run_cmd import command as run_command
    from flexmvm.cli.select_cmd import command as select_command

    (model,) = [p for p in run_command.params if p.name == "model"]
    assert toy_kind.value in model.type.choices
    (kind,) = [p for p in select_command.params if p.name == "kind"]
    assert toy_kind.value not in kind.type.choices  # not selectable (KindSpec's default)
    assert "mvm" in kind.type.choices and "mvm-moving" not in kind.type.choices
    unregister_kind(toy_kind.value)
    assert toy_kind.value not in model.type.choices
