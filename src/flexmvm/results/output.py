"""Everything a run writes: history CSV, summary JSON, HDF5, ParaView series, figure."""

from __future__ import annotations

import contextlib
import errno
from collections.abc import Iterator
from pathlib import Path

from flexmvm.errors import OutputError
from flexmvm.results.atomic import nulled_nonfinite
from flexmvm.results.writers import (
    write_history_csv,
    write_paraview_series,
    write_results_h5,
    write_summary_json,
)


def _no_space(exc: OSError) -> bool:
    """A full disk: ENOSPC, or HDF5's wording of it (h5py raises OSError without errno and
    a message holding "errno = 28, error message = 'No space left on device'")."""
    return exc.errno == errno.ENOSPC or "no space left" in str(exc).lower()


@contextlib.contextmanager
def writing(path: Path) -> Iterator[None]:
    """OSError while writing ``path`` -> OutputError of one line naming the file."""
    try:
        yield
    except OutputError:
        raise
    except OSError as exc:
        reason = (
            "no space left on the device"
            if _no_space(exc)
            else exc.strerror or " ".join(str(exc).split())[:200]
        )
        raise OutputError(f"cannot write {path}: {reason}") from exc


#: summary.json key listing the fields that were NaN/inf (written as null).
NON_FINITE_KEY = "non_finite_fields"


def write_summary(path: Path, summary) -> list[str]:
    """summary.json at ``path``: NaN/inf values written as null and listed under
    :data:`NON_FINITE_KEY` (JSON has no NaN/inf; a failed run's summary must still be
    written), OutputError naming the file if it cannot be written. Returns that list."""
    clean, bad = nulled_nonfinite(dict(summary))
    if bad:
        clean[NON_FINITE_KEY] = bad
    with writing(path):
        write_summary_json(path, clean)
    return bad


def write_run(out_dir: Path, srun, fields: bool = True) -> dict[str, Path]:
    """Write one ScenarioRun into out_dir (created); returns the paths written. OutputError
    (one line naming the file) when a file cannot be written (a full disk, ...)."""
    out_dir = Path(out_dir)
    with writing(out_dir):
        out_dir.mkdir(parents=True, exist_ok=True)
    res = srun.result
    bodies = list(srun.built.system.bodies)
    materials = [info.material for info in srun.built.info]
    paths = {
        "history": out_dir / "history.csv",
        "summary": out_dir / "summary.json",
        "results": out_dir / "results.h5",
    }
    with writing(paths["history"]):
        write_history_csv(paths["history"], res, probe_axis=None)
    write_summary(paths["summary"], srun.summary)
    if fields:
        with writing(paths["results"]):
            write_results_h5(paths["results"], res, bodies)
        with writing(out_dir / "paraview"):
            paths["paraview"] = write_paraview_series(out_dir / "paraview", res, bodies, materials)
    return paths
