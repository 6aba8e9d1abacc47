"""Region families of a selection study on any body (issue 34): the retained nodes a ball of
radius r about a centre, or a named node set of the mesh, x mode counts (Craig-Bampton by
default), against the same full-FE reference, resume and search as the rod's i-j
selections (studies/selection.py).

Centre of the balls: ``centre_m`` if given, else the body's model's own region ball centre
(the scenario's ``region = { ball = ... }``), else the expected first contact point of the
region estimate (studies/region_estimate.py). Every family's nodes and memory are checked before
the reference runs: a region that selects no node or costs more than full FE
(assembly/cost.py, refused unless ``model.allow_costly``) is a one-line error naming it.

Keys ``ball<radius in um>-m<modes>`` and ``set-<name>-m<modes>``; params {body, region
(the RegionSpec as JSON), nodes, modes, modes_max, scenario, reference_sha256} (+ kind when not
mvm). Rows: {region (label), radius_m, node_set, nodes, modes, dof (= 3 x nodes + modes),
dof_total, ncc_force, ncc_<probe>..., peak_err, impulse_err, duration_err, validity fields,
wall_time_s}. A family's candidates are ``search.Candidate(None, m, dof, region=family.key)``:
a node family like an i-j selection (same search, same tie order).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from flexmvm.errors import InputError, MeshError, SolverError
from flexmvm.results.atomic import file_sha256, write_table_csv
from flexmvm.runs.guard import VALIDITY_KEYS
from flexmvm.scenarios import ModelKind, Scenario, mvm, scenario_from_dict
from flexmvm.studies.reference_run import case_reference, scored_row
from flexmvm.studies.runner import Case
from flexmvm.studies.search import Candidate

__all__ = [
    "RegionFamily",
    "RegionGrid",
    "parse_node_sets",
    "parse_radii",
    "region_columns",
    "run_region_case",
]


@dataclass(frozen=True)
class RegionFamily:
    """One region family: a ball of ``radius_m`` [m] (about the grid's centre) or the mesh's
    node set ``node_set``; exactly one."""

    radius_m: float | None = None
    node_set: str | None = None

    def __post_init__(self) -> None:
        if (self.radius_m is None) == (self.node_set is None):
            raise InputError("a region family is a ball radius or a node set; expected one")
        if self.radius_m is not None and not (math.isfinite(self.radius_m) and self.radius_m > 0):
            raise InputError(f"region ball radius {self.radius_m!r}: expected > 0 [m]")

    @property
    def key(self) -> tuple:
        """The family's sortable key (search.Candidate.region): ('ball', r) or ('set', name)."""
        return (
            ("ball", float(self.radius_m))
            if self.radius_m is not None
            else ("set", str(self.node_set))
        )

    @property
    def label(self) -> str:
        return (
            f"ball {self.radius_m * 1e3:g} mm"
            if self.radius_m is not None
            else f"set {self.node_set}"
        )

    def case_key(self, modes: int) -> str:
        head = (
            f"ball{round(self.radius_m * 1e6):d}um"
            if self.radius_m is not None
            else f"set-{self.node_set}"
        )
        return f"{head}-m{int(modes)}"

    def spec(self, centre_m: Sequence[float]) -> Any:
        """The scenario's ``region`` table of this family (a dict, validated into a
        RegionSpec where a model is made of it)."""
        if self.radius_m is not None:
            return {
                "ball": {"centre_m": [float(a) for a in centre_m], "radius_m": float(self.radius_m)}
            }
        return {"node_set": self.node_set}


def parse_radii(text: str) -> list[RegionFamily]:
    """'0.5,1,2' (ball radii in mm) -> ball families. InputError (one line) otherwise."""
    try:
        radii = [float(a) * 1e-3 for a in text.split(",")]
    except ValueError:
        radii = []
    if (
        not radii
        or min(radii) <= 0
        or len(set(radii)) != len(radii)
        or not all(math.isfinite(a) for a in radii)
    ):
        raise InputError(
            f"--radii {text!r}: expected distinct ball radii > 0 in mm, "
            "comma-separated (e.g. '0.4,0.8,1.2')"
        )
    return [RegionFamily(radius_m=a) for a in radii]


def parse_node_sets(text: str) -> list[RegionFamily]:
    """'near,wide' (node-set names of the mesh) -> node-set families."""
    names = [a.strip() for a in text.split(",")]
    if not all(names) or len(set(names)) != len(names):
        raise InputError(f"--node-sets {text!r}: expected distinct node-set names, comma-separated")
    return [RegionFamily(node_set=a) for a in names]


def _centre(sc: Scenario, body: str, centre_m) -> tuple[float, float, float]:
    """The balls' centre (module doc)."""
    if centre_m is not None:
        c = tuple(float(a) for a in centre_m)
        if len(c) != 3 or not all(math.isfinite(a) for a in c):
            raise InputError(f"centre_m {centre_m!r}: expected three finite coordinates [m]")
        return c[0], c[1], c[2]
    region = sc.body(body).model.region
    if region is not None and region.ball is not None:
        x, y, z = (float(a) for a in region.ball.centre_m)
        return x, y, z
    from flexmvm.studies.region_estimate import estimate_region

    # the expected contact point only: the closing speed and curvature are not needed
    return estimate_region(sc, body, speed_mps=1.0, radius_m=1.0, modes=0).centre_m


class RegionGrid:
    """The region families x mode counts of body ``body`` (module doc), checked against its
    mesh: nodes per family, costs within the full-FE body's (assembly/cost.py)."""

    def __init__(
        self,
        sc: Scenario,
        body: str,
        families: Iterable[RegionFamily],
        modes: Iterable[int],
        centre_m=None,
        kind: ModelKind = ModelKind.MVM,
    ) -> None:
        from flexmvm.assembly.build_cache import default_setup
        from flexmvm.assembly.cost import check_cost, reduced_cost
        from flexmvm.assembly.mesh_lookup import retained_nodes

        self.families = sorted(set(families), key=lambda f: f.key)
        if not self.families:
            raise InputError("region grid: expected at least one ball radius or node set")
        self.modes = sorted({int(m) for m in modes})
        if not self.modes or self.modes[0] < 1:
            raise InputError(f"modes: expected integers >= 1, got {list(modes)!r}")
        self.body, self.kind = body, kind
        cfg = sc.body(body)
        self.centre = _centre(sc, body, centre_m)
        fe = default_setup().free_modes_source(cfg)[0]
        self.nodes: dict[tuple, int] = {}
        for fam in self.families:
            model = mvm(region=fam.spec(self.centre), modes=self.modes[-1])
            where = f"region {fam.label} of {body!r}"
            try:
                n = len(retained_nodes(model, fe.mesh, None, where))
            except MeshError as exc:  # an unknown or empty node set: one line naming it
                raise InputError(f"{where}: {exc}") from None
            columns = self.kind.spec.cost_columns(n, self.modes[-1])
            if columns is not None:  # None: a kind the dense estimate does not cost
                cost = reduced_cost(body, fe.mesh.n_nodes, columns, fe.K.nnz)
                check_cost(cost, cfg.model.allow_costly, where)
            self.nodes[fam.key] = n

    def cases(self, sc: Scenario, reference: str | Path | None) -> list[Case]:
        data = sc.model_dump(mode="json")
        sha = file_sha256(reference) if reference is not None else None
        extra = {} if self.kind is ModelKind.MVM else {"kind": self.kind.value}
        top = self.modes[-1]
        return [
            Case(
                fam.case_key(m),
                {
                    "body": self.body,
                    "region": fam.spec(self.centre),
                    "label": fam.label,
                    "nodes": self.nodes[fam.key],
                    "modes": m,
                    "modes_max": top,
                    "scenario": data,
                    "reference_sha256": sha,
                }
                | extra,
            )
            for fam in self.families
            for m in self.modes
        ]

    def candidate(self, case: Case) -> Candidate:
        fam = _family(case.params["region"])
        m = int(case.params["modes"])
        return Candidate(None, m, 3 * self.nodes[fam.key] + m, region=fam.key)

    def grid_dict(self) -> dict:
        return {
            "regions": [f.label for f in self.families],
            "centre_m": list(self.centre),
            "modes": self.modes,
        }


def _family(region: dict) -> RegionFamily:
    if "ball" in region:
        return RegionFamily(radius_m=float(region["ball"]["radius_m"]))
    return RegionFamily(node_set=str(region["node_set"]))


def _row(p: Mapping[str, Any]) -> dict[str, Any]:
    fam = _family(p["region"])
    n, m = int(p["nodes"]), int(p["modes"])
    return {
        "region": fam.label,
        "radius_m": fam.radius_m,
        "node_set": fam.node_set,
        "nodes": n,
        "modes": m,
        "dof": 3 * n + m,
        "dof_total": 3 * n + m + 6,
    }


def failed_region_row(case: Case, line: str) -> dict:
    return _row(case.params) | {"failed": line}


def run_region_case(case: Case, reference: str | Path | None = None) -> dict:
    """One run of a region family's model against the stored reference history (as
    selection.run_selection_case)."""
    from flexmvm.assembly.build_cache import default_setup
    from flexmvm.runs.run import run_scenario
    from flexmvm.scenarios import RegionSpec

    p = case.params
    sc = scenario_from_dict(p["scenario"], source=f"case {case.key}")
    body, m = p["body"], int(p["modes"])
    t_ref, f_ref, probes_ref = case_reference(case, reference)
    row = _row(p)
    model = mvm(
        region=RegionSpec(**p["region"]),
        modes=m,
        reference=sc.body(body).model.reference,
        kind=ModelKind(p.get("kind", "mvm")),
    )
    # the scenario's consent to a costly region (checked by RegionGrid) holds for its runs
    model = model.model_copy(update={"allow_costly": sc.body(body).model.allow_costly})
    setup = default_setup().with_mode_floor(int(p.get("modes_max", m)))
    try:
        run = run_scenario(sc.with_model(body, model), warn=False, setup=setup)
    except SolverError as exc:
        return row | {"failed": str(exc).splitlines()[0]}
    info = next(b for b in run.built.info if b.name == body)
    if info.n_retained_nodes != row["nodes"]:
        raise SolverError(
            f"case {case.key}: {info.n_retained_nodes} retained nodes, the grid "
            f"counted {row['nodes']}"
        )
    return scored_row(row, run, body, t_ref, f_ref, probes_ref)


def row_order(r: dict) -> tuple:
    return (
        *_family(
            {"ball": {"radius_m": r["radius_m"]}}
            if r.get("radius_m") is not None
            else {"node_set": r["node_set"]}
        ).key,
        r["modes"],
    )


def region_key(r: dict) -> str:
    fam = (
        RegionFamily(radius_m=r["radius_m"])
        if r.get("radius_m") is not None
        else RegionFamily(node_set=r["node_set"])
    )
    return fam.case_key(r["modes"])


def region_winner(best: Candidate | None, rows: dict[str, dict]) -> dict:
    """selection.json's winner fields of a region study (``rows`` by case key)."""
    if best is None or best.region is None:
        return {"passed": False}
    what, value = best.region
    fam = (
        RegionFamily(radius_m=float(value)) if what == "ball" else RegionFamily(node_set=str(value))
    )
    r = rows[fam.case_key(best.modes)]
    return {"passed": True} | {
        k: r.get(k)
        for k in (
            "region",
            "radius_m",
            "node_set",
            "nodes",
            "modes",
            "dof",
            "dof_total",
            "ncc_force",
        )
    }


def region_columns(probes: Sequence[str]) -> list[str]:
    return (
        ["region", "nodes", "modes", "dof", "ncc_force"]
        + [f"ncc_{p}" for p in probes]
        + ["peak_err", "impulse_err", "duration_err", *VALIDITY_KEYS, "wall_time_s"]
    )


def write_region_csv(path: Path, rows: Iterable[dict], probes: Sequence[str]) -> None:
    write_table_csv(path, region_columns(probes), sorted(rows, key=row_order))


def front_points(rows: Iterable[dict]) -> dict[str, list[tuple[float, float]]]:
    """(dof, force NCC) of the evaluated rows per region family, for the NCC-DOF figure."""
    pts: dict[str, list[tuple[float, float]]] = {}
    for r in sorted(rows, key=row_order):
        if "ncc_force" in r:
            pts.setdefault(r["region"], []).append((float(r["dof"]), float(r["ncc_force"])))
    return pts
