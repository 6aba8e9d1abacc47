"""Output directories: created with a one-line error, or written whole and renamed into place.

:func:`make_out_dir` creates a directory (parents included) and turns the OS error of a path
that cannot be a directory (a file on the way, no permission) into an InputError naming the
option and the path.

:func:`staged_dir` gives a command a temporary sibling ``DIR.partial-<pid>`` to write into; only
when the command has written everything is it renamed to ``DIR``. A failure (or Ctrl-C, or
SIGTERM through the CLI) removes the temporary directory and leaves ``DIR`` as it was. A
process killed outright (SIGKILL) cannot clean up: its ``DIR.partial-<pid>`` carries the
marker :data:`PARTIAL_MARKER` with its pid, and the next command writing to ``DIR`` removes it
once that pid is gone (and says so).

Nothing a user wrote is ever deleted. Every directory written through staged_dir ends with a
manifest, :data:`MARKER`: the command and the SHA-256 of every file it wrote. An existing
``DIR`` is replaced as a whole only if it is empty, or if its manifest names the same command
and every file in it is a file of that manifest with its content unchanged; a file the
manifest does not list (a user's ``NOTES.txt``), a changed file, or a directory without a
manifest (whatever it holds, ``summary.json`` included) is refused in one line, naming it.

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
    return sorted(f for f in out if f not in (MARKER, PARTIAL_MARKER))


def manifest_of(root: Path, command: str) -> dict:
    """The manifest of the files under ``root``: {"command", "version", "files": {rel: sha256}}."""
    files = {}
    for rel in _files(root):
        p = root / rel
        files[rel] = _sha256(p) if p.is_file() and not p.is_symlink() else "link"
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
        entries = list(path.iterdir())
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
        elif listed[rel] != "link" and _sha256(path / rel) != listed[rel]:
            changed.append(rel)
    if foreign:
        return f"holds files {command} did not write ({_names(foreign)})"
    if changed:
        return f"holds files changed since {command} wrote them ({_names(changed)})"
    return None


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    except OSError:
        return True
    return True


def remove_stale_partials(final: Path, echo=None) -> list[Path]:
    """Remove the ``final.partial-<pid>`` directories of processes that are gone.

    Only a directory that carries :data:`PARTIAL_MARKER` with that pid is removed (one
    staged_dir made it); one whose process still runs is left alone. Returns the removed
    paths; ``echo`` (a print-like callable) is told of each.
    """
    removed = []
    parent = final.absolute().parent
    if not parent.is_dir():
        return removed
    prefix = f"{final.name}.partial-"
    for d in parent.iterdir():
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
            or _pid_alive(pid)
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
    """Yield an empty temporary directory beside ``path``; on success it becomes ``path``.

    ``command`` (e.g. ``"flexmvm run"``) and the SHA-256 of every file written go to the
    manifest :data:`MARKER`; an existing ``path`` is replaced only if it is empty or an
    unchanged earlier output of the same command (module doc). On an exception inside the
    block the temporary directory is removed and ``path`` is untouched. Stale staging
    directories of dead processes beside ``path`` are removed first (reported to ``echo``).

    Raises:
        InputError: ``path`` cannot be created, exists as a file, or is a directory that is
            neither empty nor an unchanged earlier output of ``command`` (checked before the
            block runs).
    """
    final = Path(path)
    if final.is_symlink():  # --out pointing elsewhere (a scratch disk): keep the link
        final = final.resolve()
    check_creatable(final, option)
    why = _refusal(final, command) if final.exists() else None
    if why is not None:
        raise InputError(
            f"{option} {final}: {why}; expected a new or empty directory, or an "
            f"unchanged earlier output of {command} (which is replaced)"
        )
    cwd = Path.cwd().resolve()
    if final.exists() and (cwd == final.resolve() or final.resolve() in cwd.parents):
        raise InputError(
            f"{option} {final}: is the current directory (or holds it); expected another directory"
        )
    parent = final.absolute().parent
    created = [d for d in (parent, *parent.parents) if not d.exists()]
    make_out_dir(parent, option)
    remove_stale_partials(final, echo)
    tmp = final.with_name(f"{final.name}.partial-{os.getpid()}")
    if tmp.exists():
        shutil.rmtree(tmp, ignore_errors=True)
    try:
        tmp.mkdir()
        (tmp / PARTIAL_MARKER).write_text(
            json.dumps({"command": command, "pid": os.getpid()}) + "\n", encoding="utf-8"
        )
    except OSError as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        _remove_empty(created)
        raise InputError(f"{option} {final}: cannot create {tmp} ({_reason(exc)})") from None
    try:
        yield tmp
        (tmp / PARTIAL_MARKER).unlink()
        (tmp / MARKER).write_text(
            json.dumps(manifest_of(tmp, command), indent=1) + "\n", encoding="utf-8"
        )
        _swap_in(tmp, final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        _remove_empty(created)
        raise


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
