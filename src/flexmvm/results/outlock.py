"""Who is writing an output directory: a lock held by one process, recognised after pid reuse.

A process is named by its pid *and* its start time (field 22 of ``/proc/<pid>/stat``, clock
ticks since boot) plus a random token: a lock or a staging folder left by a process that was
killed outright is stale even when the kernel has since given its pid to another process,
since that process started at another time. Where ``/proc`` is missing (not Linux) only the
pid is compared.

:func:`hold_lock` creates the lock file with its content in one step (a hard link of a
complete temporary file, which fails if the name exists), so a second process sees either
no lock or a complete one. A second run into the same directory is refused, not queued: if
it waited, it would then replace the first run's output as silently as before; a refusal
naming the other run's pid lets the user choose another ``--out``.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import secrets
import tempfile
from collections.abc import Iterator
from pathlib import Path

from flexmvm.errors import InputError

#: The lock file of a directory being written (beside it, or inside a mount point).
LOCK_NAME = ".flexmvm-lock"

__all__ = ["LOCK_NAME", "hold_lock", "holder_alive", "process_start", "this_process"]


def process_start(pid: int) -> str | None:
    """The start time of process ``pid`` (``/proc/<pid>/stat`` field 22), None if unknown."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text(encoding="ascii", errors="replace")
    except OSError:
        return None
    fields = stat[stat.rfind(")") + 2 :].split()  # after "(comm) ": field 3 onwards
    return fields[19] if len(fields) > 19 else None


def _pid_exists(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def this_process(command: str) -> dict:
    """This process as a lock or staging marker records it: command, pid, start, token."""
    pid = os.getpid()
    return {
        "command": command,
        "pid": pid,
        "start": process_start(pid),
        "token": secrets.token_hex(8),
    }


def holder_alive(info: dict) -> bool:
    """Whether the process a marker names still runs: its pid exists and, where the marker
    and /proc both give a start time, that time is the same (a reused pid is not it)."""
    pid = info.get("pid")
    if not isinstance(pid, int) or pid <= 0 or not _pid_exists(pid):
        return False
    start = info.get("start")
    now = process_start(pid)
    return start is None or now is None or str(start) == now


def _read(lock: Path) -> dict | None:
    try:
        info = json.loads(lock.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return info if isinstance(info, dict) else None


def _create(lock: Path, text: str) -> bool:
    """Create ``lock`` holding ``text`` unless it exists; False if it does."""
    fd, tmp = tempfile.mkstemp(prefix=f"{lock.name}.", suffix=".tmp", dir=lock.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        try:
            os.link(tmp, lock)
        except FileExistsError:
            return False
        except OSError as exc:  # no hard links here (some network or FUSE file systems)
            if exc.errno not in (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EXDEV):
                raise
            try:
                with open(lock, "x", encoding="utf-8") as f:
                    f.write(text)
            except FileExistsError:
                return False
        return True
    finally:
        with contextlib.suppress(OSError):
            os.unlink(tmp)


@contextlib.contextmanager
def hold_lock(lock: Path, target: Path, command: str, option: str = "--out") -> Iterator[dict]:
    """Hold ``lock`` (a file) while the block writes ``target``; yields this process's info.

    A lock whose process is gone (or whose pid now belongs to another process) is taken over.

    Raises:
        InputError: another live process holds the lock (naming the directory and its pid),
            or the lock cannot be created.
    """
    me = this_process(command)
    text = json.dumps(me) + "\n"
    for _ in range(3):
        try:
            if _create(lock, text):
                break
        except OSError as exc:
            raise InputError(
                f"{option} {target}: cannot create the lock {lock} ({exc.strerror or exc})"
            ) from None
        other = _read(lock)
        if other is not None and holder_alive(other):
            raise InputError(
                f"{option} {target}: is being written by another {other.get('command', 'flexmvm')}"
                f" (pid {other.get('pid')}, lock {lock}); expected one run per output directory "
                "at a time: wait for it or choose another directory"
            )
        with contextlib.suppress(FileNotFoundError):
            lock.unlink()  # stale: its process is gone (or unreadable: a writer killed mid-write)
    else:
        raise InputError(f"{option} {target}: cannot take the lock {lock}; another run holds it")
    try:
        yield me
    finally:
        if _read(lock) == me:
            with contextlib.suppress(OSError):
                lock.unlink()
