"""The threads a step's per-body work runs on: one object per integrator, no module state.

The back-substitutions of sparse (full-FE) bodies release the GIL (fe.ldl), so with two or
more such bodies each body's work in a step runs on a thread of its own (results as serial:
the work of one body touches nothing of another). With one full-FE body the threads go to
its back-substitutions instead (fe.ldl: two elimination-tree halves, the same results on one
thread), and with none to a large dense (MVM) body's G2 contraction, memory-bound, in two
halves (bodies.body.FlexibleBody.contractions; bit for bit). Up to $FLEXMVM_THREADS threads
(flexmvm.threads; default: the cores; 1: everything on the calling thread).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor

from flexmvm.threads import worker_threads


class BodyThreads:
    """Where the per-body work of a system's steps runs (module doc). Attributes:
    ``sparse`` (the full-FE bodies), ``executor`` (None: one thread), ``threaded`` (bodies whose work goes on threads),
    ``solve_pool`` (per body: the pool of its back-substitutions, or None) and
    ``contraction_pool`` (the pool of the G2 contractions, or None)."""

    def __init__(self, bodies):
        sparse = {b for b, body in enumerate(bodies) if body.nq and body.is_sparse}
        self.sparse = frozenset(sparse)  # the full-FE bodies
        halves = any(body.contracts_in_halves for body in bodies)
        n = worker_threads()
        wanted = bool(sparse) or halves
        self.executor = (
            ThreadPoolExecutor(max_workers=n, thread_name_prefix="flexmvm-body")
            if n >= 2 and wanted
            else None
        )
        several = len(sparse) >= 2
        self.threaded: set[int] = sparse if (several and self.executor) else set()
        self.solve_pool = [
            self.executor if (len(sparse) == 1 and b in sparse) else None
            for b in range(len(bodies))
        ]
        self.contraction_pool = self.executor if (not several and halves) else None

    def each(self, fn: Callable, bodies: Iterable[int]) -> dict:
        """{b: fn(b)} for b in bodies, the threaded ones on threads of their own (the first
        on the calling thread)."""
        bodies = list(bodies)
        threaded = [b for b in bodies if b in self.threaded]
        if len(threaded) < 2:
            return {b: fn(b) for b in bodies}
        futures = {b: self.executor.submit(fn, b) for b in threaded[1:]}
        done = {b: fn(b) for b in bodies if b not in futures}
        return {b: done[b] if b in done else futures[b].result() for b in bodies}
