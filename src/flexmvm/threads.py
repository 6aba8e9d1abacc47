"""How many threads flexmvm's own thread pools may use (FLEXMVM_THREADS).

One setting for every place that splits work over threads: the per-body work of several
full-FE bodies in a step (integrate.moreau_jean.body_threads) and the two elimination-tree halves of
a supernodal LDL^T solve (fe.ldl), e.g. in a Craig-Bampton build. Unset: the machine's cores;
1: everything on the calling thread (e.g. a study's many single-threaded workers).
"""

from __future__ import annotations

import os

from flexmvm.errors import SolverError

#: Environment variable: threads for flexmvm's pools (default: the number of cores).
ENV_THREADS = "FLEXMVM_THREADS"


def worker_threads() -> int:
    """The number of threads set by FLEXMVM_THREADS (default: os.cpu_count()).
    Raises SolverError for a value that is not a whole number >= 1."""
    value = os.environ.get(ENV_THREADS, "").strip()
    if not value:
        return os.cpu_count() or 1
    try:
        n = int(value)
    except ValueError:
        raise SolverError(
            f"{ENV_THREADS} must be a whole number of threads, got {value!r}"
        ) from None
    if n < 1:
        raise SolverError(f"{ENV_THREADS} must be >= 1, got {n}")
    return n


__all__ = ["ENV_THREADS", "worker_threads"]
