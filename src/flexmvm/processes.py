"""Child processes that do not outlive their parent, and SIGTERM as an orderly stop.

A job scheduler or a parent program stops a run with SIGTERM (or SIGKILL) sent to the
``flexmvm`` process alone, not to its process group. Without care the worker processes of
``flexmvm run --jobs 2`` go on computing for minutes after their parent is gone.

- :func:`die_with_parent` is the initializer of every worker pool: the worker asks the kernel
  for SIGKILL when its parent dies (Linux ``prctl(PR_SET_PDEATHSIG)``) and, everywhere, a
  daemon thread checks ``os.getppid()`` twice a second and exits when the parent has changed.
- :func:`sigterm_as_exit` turns SIGTERM into :class:`Terminated` in the main thread, so the
  ``finally`` blocks run: staging directories are removed and workers stopped, as for Ctrl-C.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator

__all__ = ["Terminated", "die_with_parent", "sigterm_as_exit"]

_PR_SET_PDEATHSIG = 1
_POLL_S = 0.5


class Terminated(KeyboardInterrupt):
    """SIGTERM received: an orderly stop, handled where Ctrl-C is (exit status 143)."""


def _parent_watch(parent_pid: int) -> None:
    while True:
        if os.getppid() != parent_pid:
            os._exit(1)
        time.sleep(_POLL_S)


def die_with_parent(parent_pid: int) -> None:
    """Make this (worker) process end when ``parent_pid``, its parent, ends.

    For ``ProcessPoolExecutor(initializer=die_with_parent, initargs=(os.getpid(),))``: the
    parent's pid is passed, so a parent that died before the initializer ran is noticed too.
    """
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent_pid:
        os._exit(1)
    threading.Thread(
        target=_parent_watch, args=(parent_pid,), daemon=True, name="flexmvm-parent-watch"
    ).start()


def _raise_terminated(signum, frame) -> None:
    raise Terminated(f"signal {signum}")


@contextlib.contextmanager
def sigterm_as_exit() -> Iterator[None]:
    """Within the block, SIGTERM raises :class:`Terminated` in the main thread (the previous
    handler is restored after). A no-op outside the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)
