"""The last step of a staged output: the staging directory's files become the output directory.

Beside the output (``DIR.partial-<pid>``) the staging directory is renamed onto ``DIR`` (the
earlier ``DIR`` renamed aside first, checked once more there, removed after). A directory that
cannot be renamed (a mount point: a tmpfs, a container volume ``-v host:/out``; rename gives
EBUSY, or EXDEV across file systems) keeps its inode: the earlier output's files in it are
removed (its manifest last) and the new files moved in (the new manifest first), so a move
cut short leaves files a later run recognises and may replace.

When a file not written by the command appeared in ``DIR`` during the run, nothing is
replaced: ``DIR`` stays as it is and the new output is kept as ``DIR.new-<pid>`` (or
``DIR/flexmvm-new-<pid>`` inside a mount point), both named in the one-line InputError.
"""

from __future__ import annotations

import errno
import os
import shutil
from collections.abc import Callable
from pathlib import Path

from flexmvm.errors import InputError
from flexmvm.results.outlock import LOCK_NAME

#: Name prefix of a staging directory inside a mount point (``DIR/.flexmvm-partial-<pid>``).
INSIDE_PREFIX = ".flexmvm-partial-"
#: The manifest's name (results.outdir.MARKER; repeated here, outdir imports this module).
_MARKER = ".flexmvm-output"
_NOT_RENAMEABLE = (errno.EBUSY, errno.EXDEV)

__all__ = ["INSIDE_PREFIX", "swap_in"]


def swap_in(tmp: Path, final: Path, refusal: Callable[[Path], str | None], option: str) -> None:
    """Make tmp's files those of ``final``. ``refusal(d)`` says why directory d may not be
    replaced (a file the command did not write), None if it may.

    Raises:
        InputError: ``final`` holds a file the command did not write (``refusal``); tmp is
            kept under a new name and ``final`` left as it is.
    """
    why = refusal(final) if final.exists() else None
    if why is not None:
        _keep_both(tmp, final, why, option)
    if not final.exists():
        os.replace(tmp, final)
        return
    if tmp.parent == final:
        _replace_contents(tmp, final)
        return
    old = final.with_name(f"{final.name}.old-{os.getpid()}")
    if old.exists():
        shutil.rmtree(old, ignore_errors=True)
    try:
        os.replace(final, old)
    except OSError as exc:
        if exc.errno not in _NOT_RENAMEABLE:
            raise
        _replace_contents(tmp, final)  # a mount point os.path.ismount did not see (bind mount)
        return
    why = refusal(old)  # a file written between the check and the rename
    if why is not None:
        os.replace(old, final)
        _keep_both(tmp, final, why, option)
    try:
        os.replace(tmp, final)
    except BaseException:
        os.replace(old, final)
        raise
    shutil.rmtree(old, ignore_errors=True)


def _keep_both(tmp: Path, final: Path, why: str, option: str) -> None:
    """Rename tmp to a visible name beside (or inside) final and raise the InputError."""
    pid = os.getpid()
    kept = (
        final / f"flexmvm-new-{pid}"
        if tmp.parent == final
        else final.with_name(f"{final.name}.new-{pid}")
    )
    if kept.exists():
        shutil.rmtree(kept, ignore_errors=True)
    os.replace(tmp, kept)
    raise InputError(
        f"{option} {final}: {why} (written during this run): left as it is; this run's "
        f"output is kept in {kept}; expected nothing else written into {final} during a run"
    )


def _skipped(entry: Path, tmp: Path) -> bool:
    return entry == tmp or entry.name == LOCK_NAME or entry.name.startswith(INSIDE_PREFIX)


def _remove(entry: Path) -> None:
    if entry.is_dir() and not entry.is_symlink():
        shutil.rmtree(entry)
    else:
        entry.unlink()


def _replace_contents(tmp: Path, final: Path) -> None:
    """Replace final's files (an unchanged earlier output, checked) by tmp's, final kept:
    old files removed (manifest last), new ones moved in (manifest first; shutil.move copies
    across file systems), tmp removed."""
    old = sorted(
        (e for e in final.iterdir() if not _skipped(e, tmp)), key=lambda e: e.name == _MARKER
    )
    for entry in old:
        _remove(entry)
    new = sorted(tmp.iterdir(), key=lambda e: e.name != _MARKER)
    for entry in new:
        shutil.move(str(entry), str(final / entry.name))
    shutil.rmtree(tmp, ignore_errors=True)
