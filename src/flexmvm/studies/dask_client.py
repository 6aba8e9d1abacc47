"""Reaching and leaving a study's Dask cluster.

A scheduler given by address (``--scheduler``) is reached with a short timeout
(:func:`check_scheduler`, before a study's full-FE reference: a mistyped address was found
only after it). When the study stops early, after an error (a full disk while a case is
written), a Ctrl-C or a SIGTERM, the user sees one line, not Dask's:

- The worker processes of a study's local cluster ignore SIGINT (this module is their Dask
  preload, :func:`dask_setup`): a Ctrl-C in a terminal goes to the whole process group, and
  each worker printed a 30-line KeyboardInterrupt traceback from its event loop. The driver
  alone handles the Ctrl-C and closes the cluster, which stops the workers; the line a
  worker logs for its cancelled case is dropped.
- While the cluster is closed after an error or an interrupt, logging is off in the driver
  (:func:`quiet`): cancelled tasks and the nanny's "Worker process still alive after 4.0
  seconds, killing" are the expected course of a stop, not news for the user.
"""

from __future__ import annotations

import contextlib
import logging
import signal
import socket
import threading
import warnings
from collections.abc import Iterator

from flexmvm.errors import InputError

__all__ = [
    "CONNECT_TIMEOUT_S",
    "PRELOAD",
    "check_scheduler",
    "close_quietly",
    "connect",
    "dask_setup",
    "quiet",
]

#: The preload of a local cluster's workers (distributed imports it and calls dask_setup).
PRELOAD = __name__


def _not_a_cancellation(record: logging.LogRecord) -> bool:
    """False for the worker's line about a task cancelled while it ran ("Async instruction
    ... ended with CancelledError"): what closing a study's cluster does to its running case."""
    return "ended with CancelledError" not in record.getMessage()


def dask_setup(worker) -> None:
    """Dask preload hook, run in each worker process of a study's local cluster: SIGINT
    ignored and the line of a cancelled task dropped (module doc). The signal only in the
    main thread, where handlers can be set (a worker process runs its event loop there)."""
    logging.getLogger("distributed.worker.state_machine").addFilter(_not_a_cancellation)
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Within the block every log record of this process is dropped (logging.disable); the
    previous setting is restored after."""
    previous = logging.root.manager.disable
    logging.disable(logging.CRITICAL)
    try:
        yield
    finally:
        logging.disable(previous)


def close_quietly(*closers) -> None:
    """Call each of ``closers`` (a client's or a cluster's ``close``) under :func:`quiet`;
    an error of one (a cluster already half gone) does not keep the next from running and
    does not replace the error that stopped the study."""
    with quiet():
        for close in closers:
            if close is None:
                continue
            with contextlib.suppress(Exception):
                close()


#: Seconds to reach a scheduler before the study is refused (Dask's default is 30 s of
#: retries; a scheduler that is up answers in milliseconds on a LAN).
CONNECT_TIMEOUT_S = 5.0


def connect(scheduler: str, timeout_s: float | None = None):
    """A distributed Client of the running scheduler at ``scheduler`` (within ``timeout_s``
    seconds, Dask's own connect timeout when None); InputError if none."""
    from distributed import Client

    wait = {} if timeout_s is None else {"timeout": timeout_s}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return Client(scheduler, set_as_default=False, **wait)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        why = " ".join(str(exc).split())[:200]
        raise _refused(scheduler, f"{type(exc).__name__}: {why}") from None


def _refused(scheduler: str, why: str) -> InputError:
    return InputError(
        f"Dask scheduler {scheduler!r}: cannot connect ({why}); expected the address of a "
        "running scheduler, e.g. tcp://host:8786"
    )


def check_scheduler(scheduler: str | None, timeout_s: float = CONNECT_TIMEOUT_S) -> None:
    """InputError in one line unless ``scheduler`` is an address whose host accepts a TCP
    connection within ``timeout_s`` seconds (tcp:// and tls://; other protocols by a Dask
    client with that timeout); nothing to check when None. A study calls it before its
    full-FE reference, which takes minutes that a mistyped address would waste. A plain
    socket, not a Client: a Client that fails to start blocks 10 s in its finaliser."""
    if scheduler is None:
        return
    from distributed.comm.addressing import get_address_host_port, parse_address

    try:
        protocol = parse_address(scheduler)[0]
        host, port = get_address_host_port(scheduler) if protocol in ("tcp", "tls") else ("", 0)
    except ValueError as exc:
        raise _refused(scheduler, " ".join(str(exc).split())) from None
    if protocol not in ("tcp", "tls"):
        close_quietly(connect(scheduler, timeout_s).close)
        return
    try:
        socket.create_connection((host, port), timeout=timeout_s).close()
    except OSError as exc:
        raise _refused(scheduler, exc.strerror or type(exc).__name__) from None
