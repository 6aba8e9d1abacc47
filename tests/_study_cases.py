"""Case functions for tests/test_runner.py, at module level so Dask workers can import them.

The case computation is small but real: the lowest eigenvalues of a seeded spring chain
(n masses, random stiffnesses), which depend on every parameter, so a mixed-up case shows.
"""

from __future__ import annotations

import os
import uuid
from pathlib import Path

import numpy as np

from flexmvm.studies.runner import Case


def chain_eigenvalues(case: Case) -> dict:
    """Three lowest eigenvalues of a fixed-free chain of ``n`` unit masses with seeded springs.

    K is tridiagonal with springs k_i in [1, 2) (seed ``seed``), scaled by ``scale``;
    the mass matrix is the identity, so the eigenvalues are those of K.
    Raises ValueError when ``params["fail"]`` is true (a deliberate failure).
    """
    p = case.params
    if p.get("fail", False):
        raise ValueError(f"deliberate failure in case {case.key}")
    n = int(p["n"])
    k = 1.0 + np.random.default_rng(int(p["seed"])).random(n)
    k = k * float(p.get("scale", 1.0))
    stiffness = np.diag(k + np.append(k[1:], 0.0)) - np.diag(k[1:], 1) - np.diag(k[1:], -1)
    lam = np.linalg.eigvalsh(stiffness)
    return {"lowest": lam[:3], "trace": float(np.trace(stiffness)), "n": n}


class CountingCase:
    """``chain_eigenvalues`` that leaves one marker file per call in ``log_dir``.

    Works across worker processes (the markers are files, not memory). With
    ``interrupt_after`` set, the call after that many calls in this process raises
    KeyboardInterrupt, like a user pressing Ctrl-C in the middle of a serial sweep.
    """

    def __init__(self, log_dir: str | os.PathLike[str], interrupt_after: int | None = None):
        self.log_dir = str(log_dir)
        self.interrupt_after = interrupt_after
        self.calls = 0

    def __call__(self, case: Case) -> dict:
        if self.interrupt_after is not None and self.calls >= self.interrupt_after:
            raise KeyboardInterrupt
        self.calls += 1
        (Path(self.log_dir) / f"{case.key}.{os.getpid()}.{uuid.uuid4().hex}").touch()
        return chain_eigenvalues(case)


def computed_keys(log_dir: str | os.PathLike[str]) -> list[str]:
    """Keys of all calls logged by CountingCase in ``log_dir``, sorted, with repeats."""
    return sorted(path.name.rsplit(".", 2)[0] for path in Path(log_dir).iterdir())


def computing_pids(log_dir: str | os.PathLike[str], keys: list[str]) -> set[int]:
    """Process ids that computed the cases ``keys`` (from CountingCase markers)."""
    wanted = set(keys)
    pids = set()
    for path in Path(log_dir).iterdir():
        key, pid, _ = path.name.rsplit(".", 2)
        if key in wanted:
            pids.add(int(pid))
    return pids
