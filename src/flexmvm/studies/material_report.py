"""The report step of a material study: materials.csv's rows and materials.json's content.

From the evaluated runs of every material (studies/materials.py): one row per run with the
material's properties (a run that raised gets its grid fields and ``failed``), the mean NCC of
the force per material over all its runs and over the models valid for every material
(runs.guard.invalid_reason), whether those means decrease in the seed's order, the
failures, and the theory's contact radius beside the selections' radii (studies/materials.py
module doc lists the fields).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence

import numpy as np

from flexmvm.errors import InputError
from flexmvm.materials import Material
from flexmvm.runs.guard import VALIDITY_KEYS, invalid_reason
from flexmvm.scenarios import ModelKind, Scenario
from flexmvm.studies.case_store import Case
from flexmvm.studies.report import failed_case_row, failure_list

__all__ = ["material_case_key", "material_columns", "material_rows", "material_summary"]

_NOTE = (
    "seed_ordering_holds: mean NCC of the force over the same selections x "
    "modes strictly decreasing in the seed's order W > Cu > Al > PA6 "
    "(restricted to the materials run; false if a material has no mean). "
    "n_cases: the runs the mean covers (runs - failed). The _valid means and "
    "ordering: over valid_models, the models whose run is valid for every "
    "material (runs.guard.invalid_reason: at most WARN_FRACTION of the "
    "contact impulse on nodes the basis holds stiff, no energy rise above "
    "ENERGY_GAIN_WARN); guard_outside_validity: the invalid runs"
)
_RADIUS_NOTE = (
    "theory_contact_radius_m (1D wave-Hertz, per material) against "
    "selection_radius_m (outermost retained node from the axis): a "
    "contact patch wider than the retained nodes puts contact rows on "
    "nodes the reduced basis holds stiff"
)


def material_case_key(row: dict) -> str:
    """The case key of a materials.csv row: ``<material>-l<i>-j<j>-m<m>``."""
    return f"{row['material']}-l{row['layers']}-j{row['laps']}-m{row['modes']}"


def material_columns(probes: Sequence[str]) -> list[str]:
    """materials.csv's columns, with an NCC column per probe name."""
    return (
        [
            "material",
            "kind",
            "E_pa",
            "nu",
            "rho_kg_m3",
            "selection",
            "nodes",
            "modes",
            "dof",
            "ncc_force",
        ]
        + [f"ncc_{p}" for p in probes]
        + ["peak_err", "impulse_err", "duration_err", *VALIDITY_KEYS, "wall_time_s"]
    )


def material_rows(
    cases: Sequence[Case],
    results: Mapping[str, dict],
    case_failed: Mapping[str, str],
    rod,
    kind: ModelKind,
    mats: Mapping[str, Material],
) -> list[dict]:
    """materials.csv's rows in the order of ``cases``: a run's result (or, for a case in
    ``case_failed``, its grid fields on ``rod`` and the one-line reason) with its material's
    properties (``mats`` by name) and model ``kind``."""
    rows = []
    for c in cases:
        if c.key in results:
            r = dict(results[c.key])
        else:
            nodes = len(rod.selection(c.params["layers"], c.params["laps"]))
            r = failed_case_row(c, case_failed.get(c.key, "failed"), nodes)
        mat = mats[c.params["material"]]
        r.update(
            material=c.params["material"],
            kind=kind.value,
            E_pa=mat.E,
            nu=mat.nu,
            rho_kg_m3=mat.rho,
            selection=f"{r['layers']}-{r['laps']}",
        )
        rows.append(r)
    return rows


def _theory(sc: Scenario, body: str) -> dict:
    """1D wave-Hertz contact radius and duration of the material's scenario (no FE run)."""
    from flexmvm.theory.scenario import theory_pulse

    try:
        p = theory_pulse(sc, body)
    except InputError:
        return {}
    return {
        "theory_contact_radius_m": p.get("contact_radius_m"),
        "theory_contact_duration_s": p.get("contact_duration_s"),
        "theory_peak_force_N": p.get("peak_force_N"),
    }


def _radius(rod, i: int, j: int) -> float:
    X = rod.mesh.nodes[rod.selection(i, j)]
    return float(np.hypot(X[:, 1], X[:, 2]).max())


def _mean(values: list[float]) -> float | None:
    return sum(values) / len(values) if values else None


def _decreasing(means: list[float | None]) -> bool:
    known = [v for v in means if v is not None]
    return len(known) == len(means) and all(a > b for a, b in itertools.pairwise(known))


def _valid_models(rows: Sequence[dict], reason: Mapping[str, str | None]) -> set[tuple]:
    """The models (selection, modes) every material's run of which has an NCC and is valid
    (runs.guard.invalid_reason): the same models for every material, as the seed's
    ordering compares."""
    common = {(r["selection"], int(r["modes"])) for r in rows}
    for r in rows:
        if "ncc_force" not in r or reason[material_case_key(r)] is not None:
            common.discard((r["selection"], int(r["modes"])))
    return common


def _per_material(
    rows: Sequence[dict], m: str, mat: Material, common: set[tuple], theory: dict
) -> dict:
    """materials.json's entry of material ``m``: its means, run counts, properties, theory."""
    vals = [r["ncc_force"] for r in rows if r["material"] == m and "ncc_force" in r]
    valid = [
        r["ncc_force"]
        for r in rows
        if r["material"] == m and (r["selection"], int(r["modes"])) in common
    ]
    return {
        "mean_ncc_force": _mean(vals),
        "n_cases": len(vals),
        "mean_ncc_force_valid": _mean(valid),
        "n_valid": len(valid),
        "runs": sum(r["material"] == m for r in rows),
        "failed": sum(r["material"] == m and "ncc_force" not in r for r in rows),
        "E_pa": mat.E,
        "nu": mat.nu,
        "rho_kg_m3": mat.rho,
    } | theory


def material_summary(
    rows: Sequence[dict],
    ref_failed: Mapping[str, str],
    scen: Mapping[str, Scenario],
    mats: Mapping[str, Material],
    seed_order: Sequence[str],
    *,
    body: str,
    kind: ModelKind,
    selections: Sequence[tuple[int, int]],
    modes: Sequence[int],
    rod,
) -> dict:
    """materials.json's content: ``rows`` (material_rows) of the materials ``scen`` (each
    material's scenario, ``mats`` its properties), the references that failed (``ref_failed``:
    case key -> one line), ranked against ``seed_order``; ``rod`` the body's mesh of
    ``selections`` x ``modes``."""
    materials = list(scen)
    reason = {material_case_key(r): invalid_reason(r) for r in rows}  # None: valid
    common = _valid_models(rows, reason)
    per = {}
    for m in materials:
        per[m] = _per_material(rows, m, mats[m], common, _theory(scen[m], body))
        if f"ref-{m}" in ref_failed:
            per[m]["reference_failed"] = ref_failed[f"ref-{m}"]
    failures = [
        {"case": k, "reason": f"full-FE reference failed, no MVM run of this material: {v}"}
        for k, v in sorted(ref_failed.items())
    ] + failure_list((material_case_key(r), r) for r in rows)
    ranked = [m for m in seed_order if m in materials]
    outside = [
        {"case": k, "reason": why, "ncc_force": r.get("ncc_force")}
        for (k, why), r in zip(reason.items(), rows, strict=True)
        if why is not None
    ]
    observed = sorted(
        (m for m in materials if per[m]["mean_ncc_force"] is not None),
        key=lambda m: -per[m]["mean_ncc_force"],
    )
    return {
        "body": body,
        "kind": kind.value,
        "selections": [f"{i}-{j}" for i, j in selections],
        "modes": modes,
        "materials": per,
        "seed_order": ranked,
        "observed_order": observed,
        "seed_ordering_holds": bool(_decreasing([per[m]["mean_ncc_force"] for m in ranked])),
        "guard_outside_validity": outside,
        "valid_models": [f"{sel} + {n}" for sel, n in sorted(common)],
        "seed_ordering_holds_valid": bool(
            _decreasing([per[m]["mean_ncc_force_valid"] for m in ranked])
        ),
        "note": _NOTE,
        "failures": failures,
        "nodes": {f"{i}-{j}": len(rod.selection(i, j)) for i, j in selections},
        "selection_radius_m": {f"{i}-{j}": _radius(rod, i, j) for i, j in selections},
        "radius_note": _RADIUS_NOTE,
    }
