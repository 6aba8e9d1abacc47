"""Command-line options shared by the study commands (`flexmvm select`, `flexmvm study ...`):
where the cases run and the settings of the runs."""

from __future__ import annotations

import click

from flexmvm.errors import InputError

_OPTIONS = (
    click.option(
        "--scheduler", default=None, help="Address of a Dask scheduler (tcp://host:port)."
    ),
    click.option("--workers", type=int, default=None, help="Local worker processes."),
    click.option("--serial", is_flag=True, help="Run in this process, no Dask."),
    click.option("--t-end", "t_end", type=float, default=None, help="End time [s]."),
    click.option(
        "--dt",
        "dt",
        type=float,
        default=None,
        help="Contact time step [s] (reference and candidates alike).",
    ),
    click.option(
        "--other",
        "other",
        default="scenario",
        show_default=True,
        help="Model of the other bodies: 'scenario' (as in the file: the seed's b1 is "
        "full FE), 'full', or 'mvm:I-J:M', shared by the reference and every run.",
    ),
)


def study_run_options(command):
    """Decorator adding --scheduler, --workers, --serial, --t-end, --dt, --other."""
    for option in reversed(_OPTIONS):
        command = option(command)
    return command


def check_workers(workers: int | None) -> None:
    if workers is not None and workers < 1:
        raise InputError(f"--workers {workers}: expected a positive integer")
