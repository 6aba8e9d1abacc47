"""The case grid of a selection study: the study body's rod, the layers x laps x modes grid
checked against its mesh, the scenario a study runs and the scenarios of one case and of
the full-FE reference (studies/selection.py module doc)."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from flexmvm.errors import InputError
from flexmvm.integrate import DEFAULT_THETA
from flexmvm.reduction.kinds import KINDS, kind_spec
from flexmvm.results.atomic import file_sha256
from flexmvm.scenarios import ModelConfig, ModelKind, Scenario, full, mvm, scenario_from_dict
from flexmvm.scenarios.problems import validate_part
from flexmvm.studies.runner import Case


def rod_of(sc: Scenario, body: str):
    """The (cached) RodMesh of rod body ``body``; InputError if there is no such rod body."""
    from flexmvm.assembly.build_cache import default_setup

    cfg = sc.body(body)
    if cfg.rod is None:
        raise InputError(f"body {body!r} is not a rod ([bodies.rod]); the i-j selection needs one")
    return default_setup().rod_mesh(cfg.rod.spec())


def _ints(name: str, values: Iterable[int]) -> list[int]:
    out = sorted({int(v) for v in values})
    if not out or out[0] < 1:
        raise InputError(f"{name}: expected integers >= 1, got {list(values)!r}")
    return out


def redistributing_contacts(sc: Scenario, body: str) -> list[int]:
    """Indices of the contacts that redistribute the mass of ``body``'s contact nodes."""
    return [
        k
        for k, c in enumerate(sc.contacts)
        if c.redistribute_mass and body in (c.slave_body, c.master_body)
    ]


#: The console line of a study whose scenario's contact redistributes the study body's mass.
SEED_SCHEME_NOTE = (
    "study scheme: the study body's contact on the velocity law without mass "
    "redistribution, theta = 0.55 (the seed's models: 3 x nodes + modes "
    "coordinates; studies.grid.seed_scheme)"
)


def seed_scheme(sc: Scenario, body: str) -> Scenario:
    """The scheme a study of ``body`` runs: the seed's models, whose coordinates a study counts
    as 3 x nodes + modes. A contact that redistributes the mass of ``body``'s contact nodes
    (the seed scenarios' scheme, docs/contact_law.md: position law, massless contact nodes,
    whose Craig-Bampton constraint modes split and add static columns, theta(h) = 1/2 +
    h / (4 tau) from hf_damping_time_s: 0.51 at their 0.5 us step) goes back to the velocity law
    without redistribution, and the scheme to a fixed theta = DEFAULT_THETA (0.55: the velocity
    law's contact nodes carry mass and ring at theta near 1/2). ``sc`` itself
    when no contact redistributes ``body``'s mass. The seed study's answer (1-3 + 25 for
    force NCC >= 0.99) is the same on the scenario's own scheme: benchmarks/study_scheme.py,
    docs/notes/2026-11-29-study-scheme.md."""
    touched = redistributing_contacts(sc, body)
    if not touched:
        return sc
    data = sc.model_dump(mode="json")
    for k in touched:
        data["contacts"][k].update(law="velocity", redistribute_mass=False)
    data["time"]["theta"] = DEFAULT_THETA
    data["time"].pop("hf_damping_time_s", None)
    return scenario_from_dict(data, source=f"{data.get('name', 'scenario')} (study scheme)")


def check_study_scheme(sc: Scenario, body: str) -> None:
    """InputError unless ``sc`` is on the study scheme for ``body`` (seed_scheme)."""
    for k in redistributing_contacts(sc, body):
        # a massless retained node adds static columns (reduction/basis.py), so a case's
        # DOF would not be 3 x nodes + modes, the count the grid and the search rank by
        # (the studies' entry points run seed_scheme first)
        raise InputError(
            f"contacts[{k}] redistributes the mass of {body!r}'s contact nodes;"
            " a selection study counts 3 x nodes + modes coordinates: run it on "
            "studies.grid.seed_scheme(scenario, body)"
        )


def check_grid(sc: Scenario, body: str, layers, laps, modes):
    if sc.body(body).rod is None:
        raise InputError(
            f"body {body!r} is a mesh body: its selection study varies region "
            "families, ball radii or node sets (fm.select radii_m= / node_sets=, "
            "flexmvm select --radii / --node-sets); the i-j layers x laps grid is "
            "a rod's"
        )
    rod = rod_of(sc, body)
    check_study_scheme(sc, body)
    layers, laps, modes = _ints("layers", layers), _ints("laps", laps), _ints("modes", modes)
    for name, vals, top in (("layers", layers, rod.n_layers), ("laps", laps, rod.n_laps)):
        if vals[-1] > top:
            raise InputError(
                f"{name} up to {vals[-1]} exceeds the mesh of body {body!r}: maximum {top} {name}"
            )
    return rod, layers, laps, modes


def case_key(layers: int, laps: int, modes: int) -> str:
    return f"l{layers}-j{laps}-m{modes}"


def selection_cases(
    sc: Scenario,
    body: str,
    layers: Iterable[int] = range(1, 5),
    laps: Iterable[int] = range(1, 6),
    modes: Iterable[int] = range(7, 44, 6),
    reference: str | Path | None = None,
    kind: ModelKind = ModelKind.MVM,
) -> list[Case]:
    """The cases of the grid layers x laps x modes for body ``body`` of scenario ``sc``, the
    body modelled by ``kind`` (a kind that retains nodes: mvm, the default, mvm-seed or
    mvm-seed-fixed; params carry ``kind`` only when it is not mvm, so that the keys of the
    Craig-Bampton studies stored before stay valid).

    Keys ``l<i>-j<j>-m<m>``; params {body, layers, laps, modes, modes_max (the grid's largest
    mode count: each selection's Craig-Bampton basis is solved once with it and cut,
    assembly.build_cache.SetupCache.with_mode_floor), scenario (sc.model_dump(json)),
    reference_sha256 (of the reference history CSV ``reference``, or None)}. The path itself is
    not a parameter, so a study directory can be moved; it is given to the case function as
    ``functools.partial(run_selection_case, reference=path)``. Raises InputError for an
    unknown or non-rod body, or layers/laps beyond the rod mesh (naming the maximum).
    """
    _, layers, laps, modes = check_grid(sc, body, layers, laps, modes)
    kind = study_kind(kind)
    data = sc.model_dump(mode="json")
    sha = file_sha256(reference) if reference is not None else None
    top = max(modes)
    extra = {} if kind is ModelKind.MVM else {"kind": kind.value}
    return [
        Case(
            case_key(i, j, m),
            {
                "body": body,
                "layers": i,
                "laps": j,
                "modes": m,
                "modes_max": top,
                "scenario": data,
                "reference_sha256": sha,
            }
            | extra,
        )
        for i in layers
        for j in laps
        for m in modes
    ]


def study_kind(kind: ModelKind | str) -> ModelKind:
    """The model kind of a selection study's candidates: one that retains an i-j node
    selection beside its modes; InputError otherwise."""
    try:
        model_kind = ModelKind(kind)
    except ValueError:
        model_kind = None
    if model_kind is None or not model_kind.retains_nodes:
        options = ", ".join(k.value for k in ModelKind if k.retains_nodes)
        raise InputError(
            f"kind: a selection study varies node selections; expected one of {options}"
        )
    return model_kind


def parse_model(text: str) -> ModelConfig | None:
    """'scenario' -> None (keep); else 'kind:args', read by the kind's study hook
    (ModelKindSpec.study_fields): 'full'; 'mvm:I-J:M' (Craig-Bampton, selection I-J, M modes;
    the other kinds that retain nodes likewise). The reference condition is the rod default
    (end_b). InputError (one line) otherwise."""
    t = text.strip().lower()
    if t == "scenario":
        return None
    name, *args = t.split(":")
    fields = None
    if name in {k.value for k in KINDS}:
        fields = kind_spec(name).study_fields(tuple(args))
    if fields is not None:
        try:
            return validate_part(ModelConfig, dict(fields), f"model {text!r}")
        except InputError:
            pass
    raise InputError(
        f"model {text!r}: expected 'scenario', 'full' or 'mvm:I-J:M' (e.g. mvm:3-5:40)"
    )


def study_scenario(
    sc: Scenario,
    body: str,
    *,
    t_end_s: float | None = None,
    dt_s: float | None = None,
    other: str | ModelConfig | None = None,
) -> Scenario:
    """The scenario a study runs: end time and contact step overridden, and the model of
    every body other than ``body`` (rigid ones excepted) replaced by ``other`` (a
    ModelConfig or parse_model text; None keeps the scenario's), on the study's scheme
    (seed_scheme)."""
    sc.body(body)
    sc = seed_scheme(sc, body)
    if isinstance(other, str):
        other = parse_model(other)
    models = {}
    if other is not None:
        models = {
            b.name: other for b in sc.bodies if b.name != body and b.model.kind.spec.has_basis
        }
    for name, cfg in models.items():
        sc = sc.with_model(name, cfg)
    if t_end_s is not None or dt_s is not None:
        sc = sc.with_time(t_end_s=t_end_s, dt_s=dt_s)
    return sc


def mvm_scenario(
    sc: Scenario, body: str, layers: int, laps: int, modes: int, kind: ModelKind = ModelKind.MVM
) -> Scenario:
    """``sc`` with ``body`` as the ``kind`` model (default Craig-Bampton) of selection
    layers-laps + modes, keeping the scenario's consent to a reduced body that costs more
    than its full-FE one (``model.allow_costly``)."""
    given = sc.body(body).model
    model = mvm((layers, laps), modes, reference=given.reference, kind=kind)
    return sc.with_model(body, model.model_copy(update={"allow_costly": given.allow_costly}))


def reference_scenario(sc: Scenario, body: str) -> Scenario:
    """``sc`` with ``body`` full FE: the study's reference."""
    return sc.with_model(body, full(reference=sc.body(body).model.reference))
