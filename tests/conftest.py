"""Suite-wide settings and fixtures: the kernels' compilation for the test run, the order in
which the xdist workers meet the kernels, and the disk cache of setup results in a temporary
directory."""

from __future__ import annotations

import hashlib
import os
import shutil
import sys
from pathlib import Path

import pytest

# The compiled kernels (numba, cache=True) of a test run: optimisation level 1 in a cache of
# their own. A fresh clone compiles ~100 kernels in each xdist worker, ~85 s of CPU each at
# numba's default level 3; level 1 cut tests/test_step_paths.py from an empty cache from
# 117.8 to 91.0 s of CPU, and with the kernels compiled the same file ran in 21.1 s against
# 22.7 s (level 3): the test kernels are no slower to run. Level-1 code never reaches the
# cache beside the sources that benchmarks and users' runs read (numba's cache key does not
# hold the level), hence the separate directory. A developer who sets NUMBA_OPT keeps it and
# their own cache directory.
#
# The directory is named for the kernels' sources (_kernel_sources_digest): numba checks a
# cached kernel against its own file's time stamp only, so a kernel that calls or inlines one
# of another module (contact.search's scans and contact.certificate) kept its old compiled
# callee when only the callee's file changed (a checkout of another branch, an edit): the
# tests then ran the old code and passed (so did a constant read by a kernel from a module
# without kernels). Any change to the package's sources now starts an empty directory (the
# others are removed): a test run after an edit compiles its kernels again.


def _kernel_sources_digest(package: Path) -> str:
    """A digest of the contents of every module of `package`."""
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16]


def _kernel_cache_dir(root: Path) -> Path:
    """.pytest_cache/numba-opt1-<digest>; the directories of other digests removed."""
    name = f"numba-opt1-{_kernel_sources_digest(root / 'src' / 'flexmvm')}"
    cache = root / ".pytest_cache"
    for old in cache.glob("numba-opt1*"):
        if old.name != name:
            shutil.rmtree(old, ignore_errors=True)  # a worker may be removing it too
    return cache / name


if "NUMBA_OPT" not in os.environ:
    os.environ["NUMBA_OPT"] = "1"
    os.environ["NUMBA_CACHE_DIR"] = str(_kernel_cache_dir(Path(__file__).resolve().parents[1]))
    if "numba" in sys.modules:  # imported by a plugin before this file: read the settings again
        from numba.core import config

        config.reload_config()

# Test files whose kernels no test at the start of the collection compiles (the MVM bodies'
# momentum kernels, the plastic returns). pytest-xdist's worksteal gives each of n workers a
# contiguous 1/n of the collection at the start; these files open the second worker's part, so
# that it compiles them while the first worker compiles the FE, contact and solver kernels in
# its first test (tests/test_api.py), and finds those in the shared cache when it needs them,
# instead of compiling them at the same time (measured on a fresh clone: 33 s of the second
# worker's compile time was the first worker's kernels, compiled at the same moment).
_SECOND_WORKER_FIRST = (
    "test_momentum_kernel.py",
    "test_plastic_point.py",
    "test_plastic_kernels.py",
    "test_plastic_body.py",
)


def pytest_collection_modifyitems(config, items):
    workers = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
    if workers < 2:
        return
    first = [it for it in items if it.path.name in _SECOND_WORKER_FIRST]
    first.sort(key=lambda it: _SECOND_WORKER_FIRST.index(it.path.name))
    rest = [it for it in items if it.path.name not in _SECOND_WORKER_FIRST]
    k = len(items) // workers
    items[:] = rest[:k] + first + rest[k:]


@pytest.fixture(scope="session", autouse=True)
def _temporary_setup_cache(tmp_path_factory):
    """Point FLEXMVM_CACHE_DIR (read at every cache access, inherited by CLI subprocesses) at a
    session temporary directory, so tests never read or fill the user's cache. Under
    pytest-xdist the workers of one run share it (the run's base temporary directory): the
    seed rods' FE models and bases are then built once per run, not once per worker; entries
    are written atomically with a checksum (setup_cache.store), so two workers writing the
    same entry leave one whole copy."""
    old = os.environ.get("FLEXMVM_CACHE_DIR")
    os.environ["FLEXMVM_CACHE_DIR"] = str(_shared_cache_dir(tmp_path_factory))
    yield
    if old is None:
        os.environ.pop("FLEXMVM_CACHE_DIR", None)
    else:
        os.environ["FLEXMVM_CACHE_DIR"] = old


def _shared_cache_dir(tmp_path_factory):
    """The run's cache directory: beside the workers' base temporary directories under xdist
    (their common parent belongs to this run alone), else a session temporary directory."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        path = tmp_path_factory.getbasetemp().parent / "flexmvm-cache"
        path.mkdir(exist_ok=True)
        return path
    return tmp_path_factory.mktemp("flexmvm-cache")
