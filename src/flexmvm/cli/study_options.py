"""Command-line options shared by the study commands (`flexmvm select`, `flexmvm study ...`):
where the cases run and the settings of the runs."""

from __future__ import annotations

import contextlib
import errno
import functools
import re
import sys
from collections.abc import Iterator
from pathlib import Path

import click

from flexmvm.errors import FlexmvmError, InputError, OutputError, StudyInterrupted
from flexmvm.processes import Terminated

#: OSErrors of a storage that takes no more data: full, over quota, read-only.
NO_ROOM = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EROFS})
_TMP = re.compile(r"^\.(?P<name>.+)\.[^.]+\.tmp$")  # results.atomic's temporary files

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
    """Decorator adding --scheduler, --workers, --serial, --t-end, --dt, --other, passed to
    ``command`` with its --progress as one frozen ``options``
    (flexmvm.studies.options.StudyOptions, console lines through click.echo)."""

    @functools.wraps(command)
    def with_options(**kw):
        from flexmvm.studies.options import StudyOptions

        options = StudyOptions(
            scheduler=kw.pop("scheduler"),
            n_workers=kw.pop("workers"),
            serial=kw.pop("serial"),
            progress=kw.pop("progress"),
            t_end_s=kw.pop("t_end"),
            dt_s=kw.pop("dt"),
            other=kw.pop("other"),
            echo=click.echo,
        )
        return command(options=options, **kw)

    for option in reversed(_OPTIONS):
        with_options = option(with_options)
    return with_options


def check_workers(workers: int | None, scheduler: str | None = None) -> None:
    """InputError (one line) for --workers below 1, or a --scheduler that does not answer
    within a few seconds (studies.dask_client.check_scheduler): checked before the study's
    full-FE reference, which a bad address made the user wait for."""
    if workers is not None and workers < 1:
        raise InputError(f"--workers {workers}: expected a positive integer")
    if scheduler is not None:
        from flexmvm.studies.dask_client import check_scheduler

        check_scheduler(scheduler)


def _written(filename, out_dir: Path) -> Path:
    """The file an OSError names (a temporary ``.<name>.<random>.tmp`` of results.atomic:
    the file it was to become), or the study directory when it names none."""
    if not filename:
        return Path(out_dir)
    path = Path(str(filename))
    m = _TMP.match(path.name)
    return path.with_name(m["name"]) if m else path


@contextlib.contextmanager
def study_output(out_dir: Path) -> Iterator[None]:
    """A study command's last guard for its writes: an OSError of a full, over-quota or
    read-only storage (NO_ROOM) that no writer named becomes an OutputError of one line
    naming the file (exit status 2, not 1 with the raw OSError); a Ctrl-C its one line (during
    the cases: StudyInterrupted's, how many are stored) and exit status 130; SIGTERM and
    other errors pass."""
    try:
        yield
    except KeyboardInterrupt as exc:  # here, not in click: it prints a blank line, aborts
        if isinstance(exc, Terminated):
            raise
        line = (
            str(exc)
            if isinstance(exc, StudyInterrupted)
            else f"interrupted before the cases ran; rerun to resume in {out_dir}"
        )
        click.echo(f"flexmvm: {line}", err=True)
        sys.exit(130)  # not click's Exit: main(standalone_mode=False) returns its code
    except FlexmvmError:
        raise
    except OSError as exc:
        if exc.errno not in NO_ROOM:
            raise
        where = _written(exc.filename, out_dir)
        reason = exc.strerror or errno.errorcode.get(exc.errno, "")
        raise OutputError(f"cannot write {where}: {reason}") from exc
