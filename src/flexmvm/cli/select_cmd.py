"""`flexmvm select SCENARIO --body NAME --out DIR`: the selection study (seed section 3.2),
of a rod's i-j selections or, with --radii / --node-sets, of any body's region families."""

from __future__ import annotations

import re
from pathlib import Path

import click

from flexmvm.cli.kind_choice import selectable_kinds
from flexmvm.cli.study_options import check_workers, study_output, study_run_options
from flexmvm.errors import InputError

_DOTS = re.compile(r"^\s*(\d+)\s*\.\.\s*(\d+)\s*$")
_COLON = re.compile(r"^\s*(\d+)\s*:\s*(\d+)\s*(?::\s*(\d+)\s*)?$")
_ONE = re.compile(r"^\s*(\d+)\s*$")


def parse_range(text: str, name: str = "range") -> list[int]:
    """'1..4' -> [1, 2, 3, 4]; '7:43:6' -> [7, 13, ..., 43] (stop included when on the step;
    step 1 if omitted); '5' -> [5]. InputError (one line) on anything else."""
    m = _DOTS.match(text)
    if m:
        a, b = int(m[1]), int(m[2])
        if a < 1 or b < a:
            raise InputError(f"--{name} {text!r}: expected a..b with 1 <= a <= b")
        return list(range(a, b + 1))
    m = _COLON.match(text)
    if m:
        a, b, s = int(m[1]), int(m[2]), int(m[3] or 1)
        if a < 1 or b < a or s < 1:
            raise InputError(
                f"--{name} {text!r}: expected start:stop:step with 1 <= start <= stop and step >= 1"
            )
        return list(range(a, b + 1, s))
    m = _ONE.match(text)
    if m and int(m[1]) >= 1:
        return [int(m[1])]
    raise InputError(
        f"--{name} {text!r}: expected a..b (inclusive), start:stop:step "
        "(stop included) or one integer >= 1"
    )


def parse_point(text: str, name: str) -> list[float]:
    """'100,0,0' (mm) -> [0.1, 0.0, 0.0] [m]. InputError (one line) on anything else."""
    try:
        xyz = [float(a) * 1e-3 for a in text.split(",")]
    except ValueError:
        xyz = []
    if len(xyz) != 3:
        raise InputError(f"--{name} {text!r}: expected three coordinates in mm, 'x,y,z'")
    return xyz


@click.command("select")
@click.argument("scenario", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--body", required=True, help="The body to reduce (the seed's b2).")
@click.option("--layers", default="1..4", show_default=True, help="Node layers i: a..b.")
@click.option("--laps", default="1..5", show_default=True, help="Node laps j: a..b.")
@click.option(
    "--modes",
    default="7:43:6",
    show_default=True,
    help="Mode counts: start:stop:step, stop included.",
)
@click.option(
    "--target",
    default="ncc>=0.99",
    show_default=True,
    help="Accuracy target, e.g. 'ncc>=0.99,peak<=0.02'.",
)
@click.option(
    "--kind",
    type=selectable_kinds(),
    default="mvm",
    show_default=True,
    help="Model of the candidates: Craig-Bampton (mvm) or the seed's eq. (4) readings.",
)
@click.option(
    "--patches",
    default=None,
    help="Also sweep the interface kind (docs/interface_basis.md): patch-radius sets "
    "in mm, comma-separated, sets separated by ';' (e.g. '0.46;0.2,0.46,0.9'; "
    "'-': no patch vector).",
)
@click.option(
    "--radii",
    default=None,
    help="Region families of a mesh body: ball radii in mm, comma-separated (e.g. "
    "'0.4,0.8,1.2'), about --centre; replace --layers x --laps "
    "(`flexmvm region` estimates the radius a contact needs).",
)
@click.option(
    "--node-sets",
    "node_sets",
    default=None,
    help="Region families: node-set names of the body's mesh, comma-separated.",
)
@click.option(
    "--centre",
    default=None,
    help="Centre of the --radii balls in mm, body coordinates 'x,y,z' (default: the "
    "body's region ball centre in the scenario, else the expected first contact "
    "point).",
)
@click.option(
    "--patch-surface",
    "patch_surface",
    default=None,
    help="Facet set of the interface kind's patches (with --patches; default: a mesh "
    "body's contact surface, a rod's end_a).",
)
@click.option(
    "--interface-modes",
    default="5:20:5",
    show_default=True,
    help="Mode counts of the interface kind (with --patches): a..b, start:stop:step.",
)
@click.option(
    "--search",
    is_flag=True,
    help="Search the mode counts per node selection and per patch set (one search "
    "over both kinds: the largest model under the DOF bound first, then "
    "bisection) instead of running the whole grid.",
)
@click.option(
    "--allow-costly",
    "allow_costly",
    is_flag=True,
    help="Build the body's reduced candidates even when they cost more memory than its "
    "full-FE model (sets the body's model.allow_costly; a large region of a fine mesh).",
)
@study_run_options
@click.option(
    "--out",
    "out_dir",
    required=True,
    type=click.Path(file_okay=False, path_type=Path),
    help="Study directory (a rerun resumes).",
)
@click.option("--progress/--no-progress", default=True, show_default=True)
def command(
    scenario,
    body,
    layers,
    laps,
    modes,
    target,
    kind,
    patches,
    radii,
    node_sets,
    centre,
    patch_surface,
    interface_modes,
    search,
    allow_costly,
    out_dir,
    options,
) -> None:
    """Selection study: node selections x mode counts of BODY against the full-FE force;
    writes ncc.csv, selection.json, fig7_ncc_map.png, fig8_ncc_modes.png (with --patches
    also ncc_interface.csv and fig_front_ncc_dof.png, the NCC-DOF front of both kinds). With
    --radii / --node-sets (a body of any mesh): ncc.csv per region x modes and
    fig_front_ncc_dof.png."""
    from flexmvm.metrics.ncc import Target
    from flexmvm.studies.interface import parse_patches
    from flexmvm.studies.options import BasisSpec
    from flexmvm.studies.region_families import parse_node_sets, parse_radii
    from flexmvm.studies.selection import run_selection_study

    regions = (
        (parse_radii(radii) if radii is not None else [])
        + (parse_node_sets(node_sets) if node_sets is not None else [])
    ) or None
    centre_m = parse_point(centre, "centre") if centre is not None else None

    basis = BasisSpec(
        layers=parse_range(layers, "layers"),
        laps=parse_range(laps, "laps"),
        modes=parse_range(modes, "modes"),
        kind=kind,
        patches=parse_patches(patches) if patches is not None else None,
        interface_modes=parse_range(interface_modes, "interface-modes"),
        regions=regions,
        centre_m=centre_m,
        patch_surface=patch_surface,
    )
    tgt = Target.parse(target)
    check_workers(options.n_workers, options.scheduler)
    studied = _allowing_costly(scenario, body) if allow_costly else scenario
    with study_output(out_dir):
        run_selection_study(studied, body, out_dir, basis, tgt, search, options)
    click.echo(f"wrote {out_dir}")


def _allowing_costly(scenario: Path, body: str):
    """The scenario of file ``scenario`` with body ``body``'s model.allow_costly set (the
    study's candidates take it: studies/grid.py, studies/region_families.py)."""
    from flexmvm.scenarios import load_scenario

    sc = load_scenario(scenario)
    model = sc.body(body).model
    return sc.with_model(body, model.model_copy(update={"allow_costly": True}))
