"""The interface kind in the selection study (issue 12 part 2): a grid of patch-radius sets x
mode counts of the study body as an interface basis (reduction/interface.py), run beside
the node selections against the same full-FE reference, and the smallest model over both.

Keys ``if-r<radii in um, '_'-joined>-m<modes>`` (``if-r-m10``: no patch vector); params
{body, kind: "interface", patch_radii_m, modes, mode_choice, mode_pool, scenario,
reference_sha256} (+ patch_surface, patch_centre_m where given: any facet set of a mesh
body, patch_place). Rows: {model, patch_radii_m, n_patch, modes, mode_pool, dof (= patches +
modes, elastic coordinates), dof_total, ncc_force, ncc_<probe>..., peak_err, impulse_err,
duration_err, wall_time_s, guard_outside_fraction} (ncc_interface.csv: the evaluated cases).

Mode pool. Every case of a patch set gets the same explicit ``mode_pool``: the pool from which
the grid's largest mode count takes its modes by default (reduction.interface
participation_pool: 4 m + 6 doubled until it holds m excited modes), computed when the cases
are made. The cases of a patch set then share one free-free eigen solve and one static solve
(setup cache, keyed without the mode count), and a case is the standalone scenario with that
``mode_pool`` (docs/interface_basis.md "In the selection study"). A smaller mode count picks its
modes from this larger pool, which can differ from its default pool's choice. Mode counts
above the largest one whose pool exists (MAX_POOL), cases without modes and the frequency
choice get none (their default). Brute force runs the whole
grid of both kinds; ``--search`` runs one search over both (studies/search.py): each patch
set is a family, searched over its mode counts like a node selection, and a pass of either
kind closes the other kind's models of more DOF.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from flexmvm.errors import InputError, SolverError
from flexmvm.reduction.interface import ModeChoice
from flexmvm.results.atomic import file_sha256, write_table_csv
from flexmvm.runs.guard import VALIDITY_KEYS
from flexmvm.scenarios import Scenario, interface, scenario_from_dict
from flexmvm.studies.reference_run import case_reference, scored_row
from flexmvm.studies.report import failure_list
from flexmvm.studies.runner import Case

__all__ = [
    "interface_cases",
    "interface_columns",
    "interface_key",
    "interface_summary",
    "is_interface_key",
    "mode_pools",
    "parse_patches",
    "run_interface_case",
    "write_interface_csv",
]


def parse_patches(text: str) -> list[tuple[float, ...]]:
    """'0.46;0.2,0.46,0.9' (radii in mm, sets separated by ';', '-' for none) -> patch-radius
    sets [m]. InputError (one line) on anything else."""
    sets: list[tuple[float, ...]] = []
    for part in text.split(";"):
        part = part.strip()
        if part == "-":
            sets.append(())
            continue
        try:
            radii = tuple(float(a) * 1e-3 for a in part.split(","))
        except ValueError:
            radii = ()
        if not radii or min(radii) <= 0 or len(set(radii)) != len(radii):
            raise InputError(
                f"--patches {text!r}: expected sets of distinct radii > 0 in mm, "
                "comma-separated, sets separated by ';' (e.g. '0.46;0.2,0.46,0.9')"
            )
        sets.append(radii)
    return sets


def interface_key(radii_m: Sequence[float], modes: int) -> str:
    return "if-r" + "_".join(f"{round(a * 1e6):d}" for a in radii_m) + f"-m{int(modes)}"


def is_interface_key(key: str) -> bool:
    """Whether a case key of a selection study is the interface kind's (node keys: l<i>-...)."""
    return key.startswith("if-")


def patch_place(
    sc: Scenario, body: str, surface: str | None = None, centre_m: Sequence[float] | None = None
) -> dict:
    """Where the interface kind's patches of ``body`` lie, as interface_cases' keywords: on a
    mesh body the facet set ``surface`` (default: the body's surface in its first contact)
    about ``centre_m`` (default: the centre of that set); on a rod ``surface`` if given (the
    rod's default is end_a, and its cases' params stay as before)."""
    cfg = sc.body(body)
    if cfg.rod is not None and surface is None:
        return {}
    if surface is None:
        from flexmvm.studies.estimate import contact_surface

        surface = contact_surface(sc, body)
    out: dict[str, Any] = {"patch_surface": surface}
    if centre_m is not None:
        out["patch_centre_m"] = [float(a) for a in centre_m]
    return out


def interface_cases(
    sc: Scenario,
    body: str,
    patches: Iterable[Sequence[float]],
    modes: Iterable[int],
    reference: str | Path | None = None,
    mode_choice: str = "participation",
    patch_surface: str | None = None,
    patch_centre_m: Sequence[float] | None = None,
) -> list[Case]:
    """The cases patch sets x mode counts of ``body`` as an interface model, each patch set's
    with one ``mode_pool`` (module doc; computing it solves the free-free eigenproblem of the
    body, stored in the setup cache for the runs). ``patch_surface`` / ``patch_centre_m``:
    the patches' facet set and centre (patch_place), in the params only when given."""
    cfg = sc.body(body)
    patches = [tuple(float(a) for a in radii) for radii in patches]
    for radii in patches:
        if not all(a > 0 for a in radii) or len(set(radii)) != len(radii):
            raise InputError(
                f"interface grid: patch radii {list(radii)}: expected distinct radii > 0 [m]"
            )
    if len(set(patches)) != len(patches):
        raise InputError(
            f"interface grid: a patch set appears twice in {patches}; expected each once"
        )
    counts = sorted({int(v) for v in modes})
    for radii in patches:
        for m in counts:
            if m < 0 or m + len(radii) < 1:
                raise InputError(
                    f"interface grid: modes {m} with {len(radii)} patch radii gives no column"
                )
    data = sc.model_dump(mode="json")
    sha = file_sha256(reference) if reference is not None else None
    place: dict[str, Any] = {}
    if patch_surface is not None:
        place["patch_surface"] = patch_surface
    if patch_centre_m is not None:
        place["patch_centre_m"] = [float(a) for a in patch_centre_m]
    cases = []
    for radii in patches:
        pools = mode_pools(cfg, radii, counts, mode_choice, place)
        for m in counts:
            cases.append(
                Case(
                    interface_key(radii, m),
                    {
                        "body": body,
                        "kind": "interface",
                        "patch_radii_m": [float(a) for a in radii],
                        "modes": m,
                        "mode_choice": mode_choice,
                        "mode_pool": pools[m],
                        "scenario": data,
                        "reference_sha256": sha,
                    }
                    | place,
                )
            )
    return cases


def mode_pools(
    cfg,
    radii: Sequence[float],
    counts: Sequence[int],
    mode_choice: str = "participation",
    place: dict | None = None,
) -> dict[int, int | None]:
    """The ``mode_pool`` of each mode count of patch set ``radii`` of body ``cfg`` (module
    doc): the pool of the largest count whose pool exists, for that count and the smaller ones
    (0 excluded); None for the others and for the frequency choice."""
    from flexmvm.assembly.build_cache import default_setup

    pools: dict[int, int | None] = {m: None for m in counts}
    if ModeChoice(mode_choice) is not ModeChoice.PARTICIPATION:
        return pools
    for top in sorted((m for m in counts if m > 0), reverse=True):
        # the spec of the case's own model (as run_interface_case makes it), default pool
        spec = _model(
            {
                "patch_radii_m": list(radii),
                "modes": top,
                "mode_choice": mode_choice,
                **(place or {}),
            }
        ).interface_spec()
        try:
            pool = default_setup().interface_mode_pool(cfg, spec, top)
        except InputError:  # too few excited modes within MAX_POOL: those cases fail alone
            continue
        return pools | {m: pool for m in counts if 0 < m <= top}
    return pools


def _model(p, reference: str = "end_b") -> Any:
    """The interface model of case params ``p`` (its ``mode_pool`` included)."""
    return interface(
        list(p["patch_radii_m"]),
        int(p["modes"]),
        mode_choice=p["mode_choice"],
        mode_pool=p.get("mode_pool"),
        reference=reference,
        patch_surface=p.get("patch_surface", "end_a"),
        patch_centre_m=p.get("patch_centre_m"),
    )


def run_interface_case(case: Case, reference: str | Path | None = None) -> dict:
    """One interface run of the study against the stored reference history (as
    selection.run_selection_case)."""
    from flexmvm.runs.run import run_scenario

    p = case.params
    sc = scenario_from_dict(p["scenario"], source=f"case {case.key}")
    body = p["body"]
    ref_model = sc.body(body).model.reference
    model = _model(p, ref_model)
    t_ref, f_ref, probes_ref = case_reference(case, reference)
    n_patch = len(p["patch_radii_m"])
    dof = n_patch + int(p["modes"])
    row: dict[str, Any] = {
        "model": model.label,
        "patch_radii_m": list(p["patch_radii_m"]),
        "n_patch": n_patch,
        "modes": int(p["modes"]),
        "mode_pool": p.get("mode_pool"),
        "dof": dof,
        "dof_total": dof + 6,
    }
    try:
        run = run_scenario(sc.with_model(body, model), warn=False)
    except SolverError as exc:
        return row | {"failed": str(exc).splitlines()[0]}
    return scored_row(row, run, body, t_ref, f_ref, probes_ref)


def failed_interface_row(case: Case, line: str) -> dict:
    p = case.params
    n = len(p["patch_radii_m"])
    return {
        "model": _model(p).label,
        "patch_radii_m": list(p["patch_radii_m"]),
        "n_patch": n,
        "modes": int(p["modes"]),
        "mode_pool": p.get("mode_pool"),
        "dof": n + int(p["modes"]),
        "dof_total": n + int(p["modes"]) + 6,
        "failed": line,
    }


def interface_summary(
    rows: dict[str, dict],
    cases: Sequence[Case],
    winner_key: str | None,
    exact: bool,
    made: int,
    loaded: int,
    patches: Iterable[Sequence[float]],
    modes: Iterable[int],
) -> dict:
    """selection.json's ``interface`` entry: the grid and its size, the runs of this kind
    (evaluated, made, loaded), its failures and its winner (``winner_key``: the case of the
    kind's best passing candidate by search.rank_key, or None), ``exact`` as
    search.kind_exact says."""
    done = [(c.key, rows[c.key]) for c in cases if c.key in rows]
    entry = {
        "passed": winner_key is not None,
        "exact": bool(exact),
        "grid": {
            "patch_radii_m": [list(p) for p in patches],
            "modes": sorted({int(m) for m in modes}),
        },
        "grid_size": len(cases),
        "runs": len(done),
        "runs_made": made,
        "runs_loaded": loaded,
        "failures": failure_list(done),
    }
    if winner_key is not None:
        entry |= {
            k: rows[winner_key].get(k)
            for k in (
                "model",
                "patch_radii_m",
                "modes",
                "mode_pool",
                "dof",
                "dof_total",
                "ncc_force",
                "peak_err",
            )
        }
    return entry


def interface_columns(probes: Sequence[str]) -> list[str]:
    return (
        ["model", "n_patch", "modes", "mode_pool", "dof", "ncc_force"]
        + [f"ncc_{p}" for p in probes]
        + ["peak_err", "impulse_err", "duration_err", *VALIDITY_KEYS, "wall_time_s"]
    )


def write_interface_csv(path: Path, rows: Iterable[dict], probes: Sequence[str]) -> None:
    rows = sorted(rows, key=lambda r: (r["dof"], r["n_patch"], r["model"]))
    write_table_csv(path, interface_columns(probes), rows)
