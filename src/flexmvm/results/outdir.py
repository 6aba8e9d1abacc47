"""Output directories: created with a one-line error, or written whole and renamed into place.

:func:`make_out_dir` creates a directory (parents included) and turns the OS error of a path
that cannot be a directory (a file on the way, no permission) into an InputError naming the
option and the path.

:func:`staged_dir` gives a command a temporary sibling ``DIR.partial-<pid>`` to write into; only
when the command has written everything is it renamed to ``DIR``. A failure (or Ctrl-C) removes
the temporary directory and leaves ``DIR`` as it was: no history without its comparison, no
summary of a run that did not finish. An existing ``DIR`` is replaced as a whole at the end
(files of the older run that the new one does not write, e.g. ``results.h5`` after a rerun
with ``--no-fields``, do not survive), and only if it is empty or an earlier output of the
same command (it holds the marker file :data:`MARKER`, or one of the ``legacy`` files a
command names); any other directory is refused, so ``--out ~`` cannot delete a home.
"""

from __future__ import annotations

import contextlib
import os
import shutil
from collections.abc import Iterable, Iterator
from pathlib import Path

from flexmvm.errors import InputError

#: File in every directory written through staged_dir: the command that wrote it.
MARKER = ".flexmvm-output"

__all__ = ["MARKER", "make_out_dir", "staged_dir"]


def _reason(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__


def check_creatable(path: str | os.PathLike[str], option: str = "--out") -> Path:
    """InputError unless ``path`` is a directory or can be created as one (every existing
    ancestor is a writable directory). Nothing is created."""
    path = Path(path)
    if path.is_dir():
        return path
    if path.exists():
        raise InputError(f"{option} {path}: exists and is not a directory; expected a directory")
    parent = path.absolute().parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"{option} {path}: cannot be created, {parent} is a file; expected a "
                         "path under a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"{option} {path}: cannot be created, no write permission in {parent}")
    return path


def make_out_dir(path: str | os.PathLike[str], option: str = "--out") -> Path:
    """Create directory ``path`` (and its parents); InputError naming ``option`` if it cannot."""
    path = Path(path)
    check_creatable(path, option)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"{option} {path}: cannot create the directory ({_reason(exc)})") from None
    return path


def _replaceable(path: Path, command: str, legacy: Iterable[str]) -> bool:
    if not path.is_dir():
        return False
    try:
        entries = list(path.iterdir())
    except OSError:
        return False
    if not entries:
        return True
    marker = path / MARKER
    if marker.is_file():
        with contextlib.suppress(OSError):
            return marker.read_text(encoding="utf-8").strip() == command
        return False
    return any((path / name).exists() for name in legacy)


@contextlib.contextmanager
def staged_dir(path: str | os.PathLike[str], command: str, option: str = "--out",
               legacy: Iterable[str] = ()) -> Iterator[Path]:
    """Yield an empty temporary directory beside ``path``; on success it becomes ``path``.

    ``command`` (e.g. ``"flexmvm run"``) is written to the marker file; an existing ``path``
    is replaced only if it is empty or holds the marker of the same command or one of the
    ``legacy`` file names (outputs of versions before the marker). On an exception inside the
    block the temporary directory is removed and ``path`` is untouched.

    Raises:
        InputError: ``path`` cannot be created, exists as a file, or is a directory that is
            neither empty nor an earlier output of ``command`` (checked before the block runs).
    """
    final = Path(path)
    if final.is_symlink():  # --out pointing elsewhere (a scratch disk): keep the link
        final = final.resolve()
    check_creatable(final, option)
    legacy = tuple(legacy)
    if final.exists() and not _replaceable(final, command, legacy):
        raise InputError(f"{option} {final}: the directory holds files not written by {command}; "
                         "expected a new or empty directory, or an earlier output of "
                         f"{command} (which is replaced)")
    cwd = Path.cwd().resolve()
    if final.exists() and (cwd == final.resolve() or final.resolve() in cwd.parents):
        raise InputError(f"{option} {final}: is the current directory (or holds it); expected "
                         "another directory")
    parent = final.absolute().parent
    created = [d for d in (parent, *parent.parents) if not d.exists()]
    make_out_dir(parent, option)
    tmp = final.with_name(f"{final.name}.partial-{os.getpid()}")
    if tmp.exists():
        shutil.rmtree(tmp, ignore_errors=True)
    try:
        tmp.mkdir()
    except OSError as exc:
        _remove_empty(created)
        raise InputError(f"{option} {final}: cannot create {tmp} ({_reason(exc)})") from None
    try:
        yield tmp
        (tmp / MARKER).write_text(command + "\n", encoding="utf-8")
        _swap_in(tmp, final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        _remove_empty(created)
        raise


def _remove_empty(dirs: list[Path]) -> None:
    """rmdir the parents staged_dir created (deepest first) if still empty."""
    for d in dirs:
        with contextlib.suppress(OSError):
            d.rmdir()


def _swap_in(tmp: Path, final: Path) -> None:
    """Rename tmp to final; an existing final is moved aside first and removed after."""
    if not final.exists():
        os.replace(tmp, final)
        return
    old = final.with_name(f"{final.name}.old-{os.getpid()}")
    if old.exists():
        shutil.rmtree(old, ignore_errors=True)
    os.replace(final, old)
    try:
        os.replace(tmp, final)
    except BaseException:
        os.replace(old, final)
        raise
    shutil.rmtree(old, ignore_errors=True)
