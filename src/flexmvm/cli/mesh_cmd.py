"""`flexmvm mesh rod`: build a rod mesh, print its size, mass and free-free frequencies."""

from __future__ import annotations

from pathlib import Path

import click

from flexmvm.errors import InputError


@click.group("mesh")
def command() -> None:
    """Meshes of the bodies."""


@command.command("rod")
@click.option(
    "--length", "length_m", type=float, default=1.0, show_default=True, help="Rod length L [m]."
)
@click.option(
    "--radius", "radius_m", type=float, default=0.01, show_default=True, help="Rod radius r [m]."
)
@click.option(
    "--end-a",
    type=click.Choice(["flat", "hemisphere"]),
    default="flat",
    show_default=True,
    help="Shape of end A (the contact end, at x = 0).",
)
@click.option(
    "--end-b", type=click.Choice(["flat", "hemisphere"]), default="flat", show_default=True
)
@click.option(
    "--material",
    default="aluminium",
    show_default=True,
    help="Preset: aluminium, brass, copper, tungsten, pa6.",
)
@click.option(
    "--E", "E", type=float, default=None, help="Young's modulus [Pa] (overrides the preset)."
)
@click.option("--nu", type=float, default=None, help="Poisson ratio (overrides the preset).")
@click.option("--rho", type=float, default=None, help="Density [kg/m^3] (overrides the preset).")
@click.option("--n-rings", type=int, default=None, help="O-grid element rings.")
@click.option(
    "--first-element", "first_element_m", type=float, default=None, help="First axial element [m]."
)
@click.option(
    "--max-element", "max_element_m", type=float, default=None, help="Largest axial element [m]."
)
@click.option(
    "--modes",
    "n_modes",
    type=int,
    default=12,
    show_default=True,
    help="Free-free modes to compute (the 6 rigid modes included); 0 skips the eigen solve.",
)
@click.option("--selection", default=None, help="Seed i-j node selection to report, e.g. 1-1.")
@click.option(
    "--write",
    "write_path",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    help="Write the mesh for ParaView (.vtu).",
)
def rod(
    length_m,
    radius_m,
    end_a,
    end_b,
    material,
    E,
    nu,
    rho,
    n_rings,
    first_element_m,
    max_element_m,
    n_modes,
    selection,
    write_path,
) -> None:
    """Mesh a rod and print nodes, cells, DOF, mass, volume and free-free frequencies."""
    from flexmvm.fe.assembly import assemble
    from flexmvm.fe.modes import free_modes
    from flexmvm.materials import PRESETS, Material
    from flexmvm.mesh.io import write_mesh
    from flexmvm.mesh.rod import EndShape, RodSpec, rod_mesh

    if write_path is not None and not write_path.absolute().parent.is_dir():
        raise InputError(
            f"--write {write_path}: directory {write_path.parent} does "
            "not exist; expected a path in an existing directory"
        )
    if material not in PRESETS:
        raise InputError(
            f"--material: unknown preset {material!r}; known: {', '.join(sorted(PRESETS))}"
        )
    base = PRESETS[material]
    mat = Material(
        E=base.E if E is None else E,
        nu=base.nu if nu is None else nu,
        rho=base.rho if rho is None else rho,
        name=base.name,
    )
    extra = {
        k: v
        for k, v in (
            ("n_rings", n_rings),
            ("first_element_m", first_element_m),
            ("max_element_m", max_element_m),
        )
        if v is not None
    }
    spec = RodSpec(
        radius_m=radius_m, length_m=length_m, end_a=EndShape(end_a), end_b=EndShape(end_b), **extra
    )
    rm = rod_mesh(spec)
    mesh = rm.mesh
    fe = assemble(mesh, mat)
    click.echo(f"rod: L = {length_m} m, r = {radius_m} m, end A {end_a}, end B {end_b}, {mat.name}")
    click.echo(
        f"nodes {mesh.n_nodes}, cells {mesh.n_cells} ({', '.join(b.cell_type.value for b in mesh.cells)}), "
        f"DOF {mesh.n_dof}, layers {rm.n_layers}, laps {rm.n_laps}"
    )
    click.echo(
        f"volume {fe.volume:.6e} m^3, mass {fe.mass:.6e} kg (rho * volume = {mat.rho * fe.volume:.6e} kg)"
    )
    if selection is not None:
        try:
            i, j = (int(x) for x in selection.split("-"))
        except ValueError:
            raise InputError(f"--selection: expected i-j such as 1-1, got {selection!r}") from None
        nodes = rm.selection(i, j)
        click.echo(f"selection {selection}: {len(nodes)} nodes, {3 * len(nodes)} DOF")
    if n_modes:
        freqs, _ = free_modes(fe, n_modes)
        c = mat.bar_wave_speed
        click.echo(f"free-free frequencies [Hz] (bar theory n c/2L = {c / (2 * length_m):.2f} n):")
        click.echo("  " + ", ".join(f"{f:.2f}" for f in freqs))
    if write_path is not None:
        write_mesh(write_path, mesh)
        click.echo(f"wrote {write_path}")
