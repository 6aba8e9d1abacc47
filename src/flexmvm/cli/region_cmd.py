"""`flexmvm region SCENARIO --body NAME`: the retained region a contact needs (the Hertz
estimate of studies/region_estimate.py) and what it costs on the body's mesh."""

from __future__ import annotations

import json
from pathlib import Path

import click


@click.command("region")
@click.argument("scenario", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--body", required=True, help="The body to reduce.")
@click.option(
    "--factor",
    type=float,
    default=None,
    help="Region radius per Hertz contact radius [default: none, the radius is a + h, "
    "h the size of the contact facets within a: studies/region_estimate.py].",
)
@click.option(
    "--radius-mm",
    "radius_mm",
    type=float,
    default=None,
    help="Equivalent curvature radius of the two surfaces [mm], instead of the fit "
    "(needed for flat or line contacts).",
)
@click.option(
    "--speed",
    type=float,
    default=None,
    help="Closing speed [m/s], instead of the placements' and drives' (needed when the "
    "bodies start at rest without a drive).",
)
@click.option(
    "--modes",
    type=int,
    default=None,
    help="Mode count of the costed model [default: the body's model's, else the free-free "
    "modes below 3 / contact duration].",
)
@click.option(
    "--contact",
    type=int,
    default=None,
    help="Index of the contact in the scenario [default: the body's first].",
)
@click.option(
    "--moving",
    "moving",
    default=None,
    help="Size a moving region's windows along this node set instead [default: the body's "
    "model.moving.path, when it has one]: studies/moving_window.py.",
)
@click.option(
    "--force",
    "force_n",
    type=float,
    default=None,
    help="Contact force [N] of a moving region's contact, instead of the partner's force loads.",
)
@click.option("--json", "as_json", is_flag=True, help="Print the estimate as JSON.")
def command(
    scenario: Path,
    body: str,
    factor: float | None,
    radius_mm: float | None,
    speed: float | None,
    modes: int | None,
    contact: int | None,
    moving: str | None,
    force_n: float | None,
    as_json: bool,
) -> None:
    """Estimate the region BODY needs: a ball about the expected first contact point of
    radius a + h (a the Hertz contact radius of the expected impact, h the size of the
    contact facets within a; or --factor x a), its nodes, DOF and memory against full FE.
    Prints the scenario's `region` line to use. For a moving region (the body's model has a
    `moving` table, or --moving PATH): the windows' spacing and half width (a + h + the
    switch's hysteresis) and the `moving` line to use."""
    from flexmvm.scenarios import load_scenario
    from flexmvm.studies.region_estimate import estimate_region

    sc = load_scenario(scenario)
    if moving is not None or sc.body(body).model.moving is not None:
        _moving(sc, body, moving, force_n, radius_mm, contact, as_json)
        return
    est = estimate_region(
        sc,
        body,
        factor=factor,
        radius_m=None if radius_mm is None else radius_mm * 1e-3,
        speed_mps=speed,
        modes=modes,
        contact=contact,
    )
    c = ", ".join(f"{a:.6g}" for a in est.centre_m)
    _echo(
        est, as_json, f"region = {{ ball = {{ centre_m = [{c}], radius_m = {est.radius_m:.4g} }} }}"
    )


def _echo(est, as_json: bool, key_line: str) -> None:
    """An estimate as JSON, or its lines and the scenario key line to paste."""
    if as_json:
        click.echo(json.dumps(est.as_dict(), indent=2))
        return
    for line in est.lines():
        click.echo(line)
    click.echo(key_line)


def _moving(sc, body, path, force_n, radius_mm, contact, as_json: bool) -> None:
    """The moving region's windows (studies/moving_window.py), printed."""
    from flexmvm.studies.moving_window import estimate_moving_window

    est = estimate_moving_window(
        sc,
        body,
        path=path,
        force_n=force_n,
        radius_m=None if radius_mm is None else radius_mm * 1e-3,
        contact=contact,
    )
    _echo(est, as_json, est.key())
