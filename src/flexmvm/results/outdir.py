"""Output directories: created with a one-line error, or written whole and renamed into place.

:func:`make_out_dir` creates a directory (parents included) and turns the OS error of a path
that cannot be a directory (a file on the way, no permission) into an InputError naming the
option and the path.

:func:`staged_dir` gives a command a staging directory ``DIR.partial-<pid>`` beside ``DIR`` to
write into (inside ``DIR``, ``DIR/.flexmvm-partial-<pid>``, when ``DIR`` is a mount point that
cannot be renamed); only when the command has written everything do its files become ``DIR``
(results/outswap.py). A failure (or Ctrl-C, or SIGTERM through the CLI) removes the staging
directory and leaves ``DIR`` as it was. One process at a time writes ``DIR``: a second is
refused naming the first one's pid (results/outlock.py). A process killed outright (SIGKILL)
cannot clean up: its staging directory carries the marker :data:`PARTIAL_MARKER` with its
pid and start time, and the next command writing to ``DIR`` removes it once that process is
gone (and says so), a reused pid not mistaken for it.

Nothing a user wrote is ever deleted. Every directory written through staged_dir ends with a
manifest, :data:`MARKER`: the command and the SHA-256 of every file it wrote. An existing
``DIR`` is replaced as a whole only if it is empty, or if its manifest names the same command
and every file in it is a file of that manifest with its content unchanged; a file the
manifest does not list (a user's ``NOTES.txt``), a changed file, or a directory without a
manifest (whatever it holds, ``summary.json`` included) is refused in one line, naming it.
The check is made again just before the swap: a file a user wrote into ``DIR`` during the run
is kept (the new output then kept beside it, both named). A symbolic link is recorded with its
target, so every manifest entry is checked.

:func:`claim_study_dir` is the same rule for the directory of a resumable study, which is
written into in place: it must be new, empty, or an earlier study of the same command
(its :data:`MARKER` names it); files a user adds beside a study's are never touched, since a
study writes only its own names.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
from collections.abc import Iterable, Iterator
from pathlib import Path

from flexmvm.errors import InputError
from flexmvm.results.outlock import LOCK_NAME, hold_lock, holder_alive
from flexmvm.results.outswap import INSIDE_PREFIX, swap_in

#: Manifest in every directory written by a command: the command and its files' SHA-256.
MARKER = ".flexmvm-output"
#: Marker in a staging directory while it is written: the command and the writer's pid.
PARTIAL_MARKER = ".flexmvm-partial"
_MANIFEST_VERSION = 1
_SHOWN = 3  # foreign files named in a refusal

__all__ = [
    "MARKER",
    "PARTIAL_MARKER",
    "check_creatable",
    "claim_study_dir",
    "make_out_dir",
    "manifest_of",
    "remove_stale_partials",
    "staged_dir",
]


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
        raise InputError(
            f"{option} {path}: cannot be created, {parent} is a file; expected a "
            "path under a directory"
        )
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


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _files(root: Path) -> list[str]:
    """Relative POSIX paths of every non-directory entry under root (symlinks not followed),
    the markers left out."""
    out = []
    for dirpath, dirnames, filenames in os.walk(root):
        rel = Path(dirpath).relative_to(root)
        dirnames[:] = [d for d in dirnames if not (Path(dirpath) / d).is_symlink()]
        out += [(rel / f).as_posix() for f in filenames]
        out += [
            (rel / d).as_posix()
            for d in os.listdir(dirpath)
            if (Path(dirpath) / d).is_symlink() and (Path(dirpath) / d).is_dir()
        ]
    return sorted(
        f
        for f in out
        if f not in (MARKER, PARTIAL_MARKER, LOCK_NAME) and not f.startswith(INSIDE_PREFIX)
    )


def _entry(p: Path) -> str:
    """A file's manifest entry: its SHA-256, or ``link:<target>`` for a symbolic link (so a
    hand-edited entry, such as a bare "link", matches nothing flexmvm wrote)."""
    if p.is_symlink():
        return "link:" + os.readlink(p)
    return _sha256(p) if p.is_file() else "?"


def manifest_of(root: Path, command: str) -> dict:
    """The manifest of the files under ``root``: {"command", "version", "files": {rel: entry}}
    (an entry is the file's SHA-256 or ``link:<target>``)."""
    files = {rel: _entry(root / rel) for rel in _files(root)}
    return {"flexmvm_output": _MANIFEST_VERSION, "command": command, "files": files}


def _read_manifest(path: Path) -> dict | None:
    try:
        data = json.loads((path / MARKER).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or not isinstance(data.get("files", {}), dict):
        return None
    return data


def _names(items: list[str]) -> str:
    shown = ", ".join(items[:_SHOWN])
    return shown + (f" and {len(items) - _SHOWN} more" if len(items) > _SHOWN else "")


def _refusal(path: Path, command: str) -> str | None:
    """Why ``path`` may not be replaced by an output of ``command``; None if it may."""
    if not path.is_dir():
        return None
    try:
        entries = [  # this run's own lock and staging inside a mount point left out
            e
            for e in path.iterdir()
            if e.name != LOCK_NAME and not e.name.startswith(INSIDE_PREFIX)
        ]
    except OSError as exc:
        return f"cannot be read ({_reason(exc)})"
    if not entries:
        return None
    manifest = _read_manifest(path)
    if manifest is None or "files" not in manifest:
        present = _files(path)
        return (
            f"holds files not written by {command} ({_names(present or ['?'])}; no flexmvm "
            "manifest: flexmvm replaces only a directory whose every file it wrote)"
        )
    if manifest.get("command") != command:
        return f"is an output of {manifest.get('command')!r}, not of {command}"
    listed = manifest["files"]
    foreign, changed = [], []
    for rel in _files(path):
        if rel not in listed:
            foreign.append(rel)
        elif _entry(path / rel) != listed[rel]:
            changed.append(rel)
    if foreign:
        return f"holds files {command} did not write ({_names(foreign)})"
    if changed:
        return f"holds files changed since {command} wrote them ({_names(changed)})"
    return None


def remove_stale_partials(final: Path, echo=None) -> list[Path]:
    """Remove the ``final.partial-<pid>`` directories (and ``final/.flexmvm-partial-<pid>``
    inside a mount point) of processes that are gone.

    Only a directory that carries :data:`PARTIAL_MARKER` with that pid is removed (one
    staged_dir made it); one whose process still runs (same pid and same start time, so a
    reused pid is not mistaken for it) is left alone. Returns the removed paths; ``echo`` (a
    print-like callable) is told of each.
    """
    removed: list[Path] = []
    parent = final.absolute().parent
    if not parent.is_dir():
        return removed
    beside = [(d, f"{final.name}.partial-") for d in parent.iterdir()]
    inside = [(d, INSIDE_PREFIX) for d in final.iterdir()] if final.is_dir() else []
    for d, prefix in beside + inside:
        if not d.name.startswith(prefix) or not d.is_dir() or d.is_symlink():
            continue
        try:
            pid = int(d.name[len(prefix) :])
            info = json.loads((d / PARTIAL_MARKER).read_text(encoding="utf-8"))
        except (ValueError, OSError):
            continue
        if (
            not isinstance(info, dict)
            or info.get("pid") != pid
            or pid == os.getpid()
            or holder_alive(info)
        ):
            continue
        shutil.rmtree(d, ignore_errors=True)
        removed.append(d)
        if echo is not None:
            echo(
                f"removed {d}: the unfinished output of {info.get('command', 'flexmvm')} "
                f"(process {pid}, no longer running)"
            )
    return removed


@contextlib.contextmanager
def staged_dir(
    path: str | os.PathLike[str], command: str, option: str = "--out", echo=None
) -> Iterator[Path]:
    """Yield an empty staging directory; on success its files become ``path``.

    ``command`` (e.g. ``"flexmvm run"``) and the SHA-256 of every file written go to the
    manifest :data:`MARKER`; an existing ``path`` is replaced only if it is empty or an
    unchanged earlier output of the same command (module doc), checked before the block runs
    and again just before the swap. The staging directory sits beside ``path`` and is renamed
    onto it, or inside ``path`` when ``path`` is a mount point (a tmpfs, a container volume),
    whose files are then moved (results/outswap.py). One process at a time writes ``path``
    (results/outlock.py). On an exception inside the block the staging directory is removed
    and ``path`` is untouched. Stale staging directories of dead processes are removed first
    (reported to ``echo``).

    Raises:
        InputError: ``path`` cannot be created, exists as a file, is a directory that is
            neither empty nor an unchanged earlier output of ``command``, or is being written
            by another live process; also, after the block, when a file not written by
            ``command`` appeared in ``path`` during the run: ``path`` is then left as it is and
            the new output kept beside it, both named.
    """
    final = Path(path)
    if final.is_symlink():  # --out pointing elsewhere (a scratch disk): keep the link
        final = final.resolve()
    _refuse(final, command, option)
    cwd = Path.cwd().resolve()
    if final.exists() and (cwd == final.resolve() or final.resolve() in cwd.parents):
        raise InputError(
            f"{option} {final}: is the current directory (or holds it); expected another directory"
        )
    check_creatable(final, option)  # its own path named, not the parent's (a file as parent)
    parent = final.absolute().parent
    created = [d for d in (parent, *parent.parents) if not d.exists()]
    make_out_dir(parent, option)
    inside = final.is_dir() and os.path.ismount(final)
    lock = final / LOCK_NAME if inside else parent / f".{final.name}{LOCK_NAME}"
    try:
        with hold_lock(lock, final, command, option) as me:
            _refuse(final, command, option)  # another run may have written it meanwhile
            remove_stale_partials(final, echo)
            tmp = _staging(final, inside, me, option)
            try:
                yield tmp
                (tmp / PARTIAL_MARKER).unlink()
                (tmp / MARKER).write_text(
                    json.dumps(manifest_of(tmp, command), indent=1) + "\n", encoding="utf-8"
                )
                swap_in(tmp, final, lambda d: _refusal(d, command), option)
            except BaseException:
                shutil.rmtree(tmp, ignore_errors=True)
                raise
    except BaseException:
        _remove_empty(created)
        raise


def _refuse(final: Path, command: str, option: str) -> None:
    why = _refusal(final, command) if final.exists() else None
    if why is not None:
        raise InputError(
            f"{option} {final}: {why}; expected a new or empty directory, or an "
            f"unchanged earlier output of {command} (which is replaced)"
        )


def _staging(final: Path, inside: bool, me: dict, option: str) -> Path:
    """The empty staging directory of this process (beside ``final``, or inside it), carrying
    :data:`PARTIAL_MARKER` with this process's pid, start time and token."""
    pid = me["pid"]
    tmp = (
        final / f"{INSIDE_PREFIX}{pid}"
        if inside
        else final.with_name(f"{final.name}.partial-{pid}")
    )
    if tmp.exists():
        shutil.rmtree(tmp, ignore_errors=True)
    try:
        tmp.mkdir()
        (tmp / PARTIAL_MARKER).write_text(json.dumps(me) + "\n", encoding="utf-8")
    except OSError as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        raise InputError(f"{option} {final}: cannot create {tmp} ({_reason(exc)})") from None
    return tmp


def claim_study_dir(
    path: str | os.PathLike[str], command: str, own: Iterable[str] = (), option: str = "--out"
) -> Path:
    """Create or resume the directory of a study written in place by ``command``.

    ``path`` may be new, empty, or an earlier study of ``command`` (its :data:`MARKER` says
    so); a directory without the marker is accepted only if every entry is one of the study's
    ``own`` names (a study written before the marker existed), and then gets the marker. A
    study never deletes, and writes only its own names, so a user's files beside them are
    kept.

    Raises:
        InputError: any other directory (naming its first entries), or one that cannot be
            created.
    """
    out = make_out_dir(path, option)
    marker = out / MARKER
    data = _read_manifest(out)
    if data is not None and data.get("command") == command:
        return out
    if data is not None:
        raise InputError(
            f"{option} {out}: is an output of {data.get('command')!r}, not of "
            f"{command}; expected a new or empty directory, or an earlier study "
            f"of {command} (which is resumed)"
        )
    own = set(own)
    foreign = sorted(e.name for e in out.iterdir() if e.name not in own)
    if foreign:
        raise InputError(
            f"{option} {out}: holds files not written by {command} "
            f"({_names(foreign)}); expected a new or empty directory, or an "
            f"earlier study of {command} (which is resumed)"
        )
    try:
        marker.write_text(
            json.dumps({"flexmvm_output": _MANIFEST_VERSION, "command": command, "study": True})
            + "\n",
            encoding="utf-8",
        )
    except OSError as exc:
        raise InputError(f"{option} {out}: cannot write {MARKER} ({_reason(exc)})") from None
    return out


def _remove_empty(dirs: list[Path]) -> None:
    """rmdir the parents staged_dir created (deepest first) if still empty."""
    for d in dirs:
        with contextlib.suppress(OSError):
            d.rmdir()
